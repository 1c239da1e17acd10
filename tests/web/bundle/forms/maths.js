export const PI = 3.14159;
export async function later() { return PI; }
export const twice = (x) => 2 * x;
