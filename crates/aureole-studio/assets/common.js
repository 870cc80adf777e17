// What the studio page's modules share: the elements, this tab's client
// name, the page's state, where an error is shown, and the next render.

export const $ = (id) => document.getElementById(id);
// Each tab is a client of its own: a new render replaces only this tab's
// last one, never another tab's.
export const client = self.crypto && crypto.randomUUID ? crypto.randomUUID() : `${Date.now()}-${Math.random()}`;
export const state = { view: "result", split: 0.5, controller: null, timer: null, presets: [] };

export function showError(message) {
  // Each message goes next to the control that caused it.
  $("error").textContent = "";
  $("config-error").textContent = "";
  $("light-error").textContent = "";
  if (!message) return;
  if (/^config:|effect|camera|preset|seed|no effect/i.test(message)) $("config-error").textContent = message;
  else if (/threshold|knee/i.test(message)) $("light-error").textContent = message;
  else $("error").textContent = message;
}

// A render soon: controls move many times a second, one render follows.
// The page's render is registered as state.render.
export function schedule() {
  clearTimeout(state.timer);
  state.timer = setTimeout(() => state.render(), 120);
}
