import * as a from './a.js';
a.f();
