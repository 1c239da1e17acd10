import { f } from './a.js';
if (f) {
  export const g = 1;
}
