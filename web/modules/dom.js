// The page's elements, and the message that replaces the canvas when the model cannot be drawn.

export const $ = (id) => document.getElementById(id);

export function fail(message) {
  const e = $('error');
  e.textContent = 'linesurf view cannot draw this model:\n' + message;
  e.hidden = false;
  document.title = 'linesurf view: error';
  document.body.setAttribute('data-state', 'error');
}
