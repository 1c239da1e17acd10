export function yes() {}
