import { nope } from './a.js';
nope();
