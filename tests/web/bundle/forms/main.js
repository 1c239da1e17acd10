// The entry.
import { greet, Greeter } from './words.js';
import {
  twice as double,
  PI,
} from './maths.js';

const importance = double(PI);
new Greeter().say(greet(importance));
