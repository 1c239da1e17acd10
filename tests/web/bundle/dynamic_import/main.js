import('./a.js').then((a) => a.f());
