import { $, schedule, showError, state } from "./common.js";

// The camera as panels: the library's schema gives each parameter its
// control, unit and range; the server reads the TOML into a table and
// writes the table back, so the panels and the TOML stay one camera.
export async function readConfig() {
  const reply = await fetch("/api/config/read", { method: "POST", body: $("config").value });
  const table = await reply.json();
  if (!reply.ok) { showError(table.error); return false; }
  const effects = table.effect || [];
  delete table.effect;
  state.top = table;
  state.effects = effects.map((t) => ({ table: t, on: true }));
  buildPanels();
  return true;
}

export async function writeConfig() {
  const table = { ...state.top, effect: state.effects.filter((e) => e.on).map((e) => e.table) };
  const reply = await fetch("/api/config/write", {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(table),
  });
  const text = await reply.text();
  if (!reply.ok) { showError(JSON.parse(text).error); return; }
  $("config").value = text;
  buildPanels();
  schedule();
}

function control(parameter, table, changed) {
  const label = document.createElement("label");
  label.title = `${parameter.about} (${parameter.allowed})`;
  label.dataset.param = parameter.name;
  const name = document.createElement("span");
  name.textContent = parameter.name;
  const value = table[parameter.name];
  const fallback = parameter.default === null ? "required" : String(parameter.default);
  let input = document.createElement("input");
  if (parameter.choices) {
    // A choice among names the server knows (a ghosts' shipped lens).
    input = document.createElement("select");
    for (const choice of parameter.choices) input.append(new Option(choice, choice));
    // A lens written inline in the TOML is kept until another is chosen.
    if (value !== undefined && typeof value !== "string") input.append(new Option("(inline)", ""));
    input.value = value === undefined ? parameter.choices[0] : typeof value === "string" ? value : "";
    input.addEventListener("change", () => { table[parameter.name] = input.value; changed(); });
  } else if (parameter.kind === "flag") {
    input.type = "checkbox";
    input.checked = value === undefined ? Boolean(parameter.default) : value;
    input.addEventListener("change", () => { table[parameter.name] = input.checked; changed(); });
  } else if (parameter.kind === "length" || parameter.kind === "text") {
    input.type = "text";
    input.value = value === undefined ? "" : value;
    input.placeholder = fallback;
    input.addEventListener("change", () => {
      if (input.value.trim() === "") delete table[parameter.name]; else table[parameter.name] = input.value.trim();
      changed();
    });
  } else {
    input.type = "number";
    input.step = parameter.kind === "whole" ? "1" : "any";
    if (parameter.low && parameter.low.closed) input.min = parameter.low.value;
    if (parameter.high && parameter.high.closed) input.max = parameter.high.value;
    input.value = value === undefined ? "" : value;
    input.placeholder = fallback;
    input.addEventListener("change", () => {
      if (input.value === "") delete table[parameter.name];
      else table[parameter.name] = parameter.kind === "whole" ? Math.round(Number(input.value)) : Number(input.value);
      changed();
    });
  }
  const unit = document.createElement("span");
  unit.className = "unit";
  unit.textContent = parameter.unit;
  label.append(name, input, unit);
  return label;
}

function buildPanels() {
  const panels = $("panels");
  panels.replaceChildren();
  const fieldset = (title, extra) => {
    const set = document.createElement("fieldset");
    const legend = document.createElement("legend");
    const name = document.createElement("b");
    name.textContent = title;
    legend.append(name, ...extra);
    set.append(legend);
    panels.append(set);
    return set;
  };
  const camera = fieldset("camera", []);
  state.top.camera = state.top.camera || {};
  for (const p of state.schema.camera) camera.append(control(p, state.top.camera, writeConfig));
  camera.append(control({ name: "seed", kind: "whole", low: { value: 0, closed: true }, high: null,
    default: 1, unit: "", allowed: "a whole number from 0", about: "the seed of the rays' randomness" },
  state.top, writeConfig));
  state.effects.forEach((effect, i) => {
    const button = (text, title, act) => {
      const b = document.createElement("button");
      b.textContent = text;
      b.title = title;
      b.addEventListener("click", (e) => { e.preventDefault(); act(); writeConfig(); });
      return b;
    };
    const on = document.createElement("input");
    on.type = "checkbox";
    on.checked = effect.on;
    on.title = "on or off (an effect off stays here, out of the camera)";
    on.addEventListener("change", () => { effect.on = on.checked; writeConfig(); });
    const move = (d) => () => {
      const j = i + d;
      if (j < 0 || j >= state.effects.length) return;
      [state.effects[i], state.effects[j]] = [state.effects[j], state.effects[i]];
    };
    const set = fieldset(effect.table.type, [on,
      button("↑", "earlier in the chain", move(-1)), button("↓", "later in the chain", move(1)),
      button("✕", "remove", () => state.effects.splice(i, 1))]);
    set.classList.toggle("off", !effect.on);
    const kind = state.schema.effects.find((e) => e.type === effect.table.type);
    for (const p of kind ? kind.parameters : []) set.append(control(p, effect.table, writeConfig));
    if (effect.table.type === "ghosts" && effect.on) set.append(lensPicture());
    // Sub-tables (an aperture's star-filter families): each with its
    // controls and a remove, and one to add.
    for (const [name, parameters] of Object.entries((kind && kind.tables) || {})) {
      const families = effect.table[name] || [];
      families.forEach((family, f) => {
        const sub = document.createElement("fieldset");
        const legend = document.createElement("legend");
        legend.textContent = `${name} ${f + 1} `;
        legend.append(button("✕", `remove this ${name} family`, () => {
          families.splice(f, 1);
          if (!families.length) delete effect.table[name];
        }));
        sub.append(legend);
        for (const p of parameters) sub.append(control(p, family, writeConfig));
        set.append(sub);
      });
      set.append(button(`+ ${name}`, `add a ${name} family of lines`, () => {
        effect.table[name] = families.concat([{ angle_deg: 0, spacing_um: 20, width_um: 10 }]);
      }));
    }
  });
}

// The lens the ghosts are traced through, drawn by the server from the
// config as it stands.
function lensPicture() {
  const picture = document.createElement("img");
  picture.id = "lens-picture";
  picture.alt = "the ghosts' lens, in section";
  fetch("/api/lens", { method: "POST", body: $("config").value })
    .then((reply) => (reply.ok ? reply.blob() : null))
    .then((blob) => {
      if (!blob) return;
      picture.src = URL.createObjectURL(blob);
      picture.dataset.drawn = "1";
    });
  return picture;
}

export function choosePreset() {
  const preset = state.presets.find((p) => p.name === $("preset").value);
  $("config").value = preset.toml;
  $("preset-info").textContent = preset.description;
  readConfig();
  schedule();
}
