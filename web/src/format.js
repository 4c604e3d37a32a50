// Text for the panels.
export const fixed = (x, digits = 3) => (Number.isFinite(x) ? x.toFixed(digits) : '–');
export const vec = (v, digits = 3) => `(${v.map((x) => fixed(x, digits)).join(', ')})`;
export const ms = (x) => (Number.isFinite(x) ? `${x.toFixed(1)} ms` : '–');
export const hz = (x) => (Number.isFinite(x) && x > 0 ? `${x.toFixed(1)} fps` : '–');
export const seconds = (x) => (Number.isFinite(x) && x >= 0 ? `${x.toFixed(1)} s` : '–');

// An element with text and an optional class.
export function cell(text, className) {
  const td = document.createElement('td');
  td.textContent = text;
  if (className) td.className = className;
  return td;
}

export function row(cells) {
  const tr = document.createElement('tr');
  for (const c of cells) tr.appendChild(c);
  return tr;
}
