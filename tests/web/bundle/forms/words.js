export function greet(x) { return 'hello ' + x; }
export class Greeter { say(s) { return s; } }
