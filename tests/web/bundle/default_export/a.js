export function a() {}
export default a;
