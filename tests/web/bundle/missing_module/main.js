import { x } from './absent.js';
x();
