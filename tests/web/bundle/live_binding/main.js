import { n } from './a.js';
console.log(n);
