// The studio page: every control change asks the server for a new
// picture of the view's width; a newer request aborts an older one.
"use strict";

const $ = (id) => document.getElementById(id);
const state = { view: "result", split: 0.5, controller: null, timer: null, presets: [] };

function previewWidth() {
  const stage = $("stage");
  return Math.max(64, Math.min(4096, Math.round(stage.clientWidth * (window.devicePixelRatio || 1))));
}

function request(view) {
  const threshold = $("threshold").value;
  const body = {
    image: $("image").value,
    config: $("config").value,
    width: previewWidth(),
    view,
    tonemap: $("tonemap").value,
    knee: Number($("knee").value) || 0,
  };
  if (threshold !== "") body.threshold = Number(threshold);
  body.exposure = $("auto").checked ? "auto" : Number($("ev").value);
  return body;
}

async function fetchPicture(body, signal) {
  const response = await fetch("/api/render", {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
    signal,
  });
  if (!response.ok) {
    let message = response.statusText;
    try { message = (await response.json()).error; } catch (_) { /* not JSON */ }
    const error = new Error(message);
    error.status = response.status;
    throw error;
  }
  return {
    url: URL.createObjectURL(await response.blob()),
    energyIn: Number(response.headers.get("x-energy-in")),
    energyOut: Number(response.headers.get("x-energy-out")),
    ms: Number(response.headers.get("x-render-ms")),
    white: Number(response.headers.get("x-white")),
    size: response.headers.get("x-preview-size"),
  };
}

function showError(message) {
  // Each message goes next to the control that caused it.
  $("error").textContent = "";
  $("config-error").textContent = "";
  $("light-error").textContent = "";
  if (!message) return;
  if (/^config:|effect|camera|preset|seed|NoEffect|no effect/i.test(message)) $("config-error").textContent = message;
  else if (/threshold|knee/i.test(message)) $("light-error").textContent = message;
  else $("error").textContent = message;
}

async function render() {
  if (state.controller) state.controller.abort();
  const controller = new AbortController();
  state.controller = controller;
  const split = state.view === "split";
  try {
    const main = await fetchPicture(request(split ? "result" : state.view), controller.signal);
    const under = split ? await fetchPicture(request("original"), controller.signal) : null;
    if (controller.signal.aborted) return;
    $("picture").src = main.url;
    $("under").hidden = !split;
    $("handle").hidden = !split;
    if (under) $("under").src = under.url;
    placeSplit();
    showError("");
    const ratio = main.energyIn ? (100 * main.energyOut / main.energyIn).toFixed(3) + " %" : "–";
    $("numbers").textContent =
      `${main.size} · energy in ${main.energyIn.toExponential(4)} out ${main.energyOut.toExponential(4)} (${ratio})` +
      (main.white ? ` · white ${main.white.toPrecision(4)} cd/m²` : "") + ` · ${main.ms.toFixed(0)} ms`;
    document.body.dataset.rendered = String(Number(document.body.dataset.rendered || 0) + 1);
  } catch (error) {
    if (error.name === "AbortError" || error.status === 409) return;
    showError(error.message);
    document.body.dataset.failed = String(Number(document.body.dataset.failed || 0) + 1);
  }
  updateCommand();
}

function schedule() {
  clearTimeout(state.timer);
  state.timer = setTimeout(render, 120);
}

function placeSplit() {
  const frame = $("frame");
  const x = state.split * frame.clientWidth;
  $("handle").style.left = `${x}px`;
  $("under").style.clipPath = `inset(0 ${frame.clientWidth - x}px 0 0)`;
}

function updateCommand() {
  const image = $("image").value === "demo" ? "street.exr" : $("image").value;
  const parts = ["aureole apply", JSON.stringify(image), "--config camera.toml"];
  if ($("threshold").value !== "") parts.push(`--threshold ${$("threshold").value}`);
  if (Number($("knee").value)) parts.push(`--knee ${$("knee").value}`);
  if (!$("auto").checked) parts.push(`--exposure ${$("ev").value}`);
  if ($("tonemap").value !== "filmic") parts.push(`--tonemap ${$("tonemap").value}`);
  if (state.view === "glare") parts.push("--glare-only");
  parts.push("-o out.png");
  $("command").textContent =
    ($("image").value === "demo" ? "aureole demo --hdr street.exr -o street.png\n" : "") + parts.join(" ");
}

async function start() {
  const [presets, images] = await Promise.all([
    fetch("/api/presets").then((r) => r.json()),
    fetch("/api/images").then((r) => r.json()),
  ]);
  state.presets = presets;
  for (const p of presets) $("preset").add(new Option(p.name, p.name));
  $("image").add(new Option("demo night street (built in)", images.demo));
  for (const path of images.images) $("image").add(new Option(path, path));
  $("image-info").textContent = `folders: ${images.roots.join(", ") || "none"}`;
  const first = presets.find((p) => p.name === "camera-f8-7blade") || presets[0];
  $("preset").value = first.name;
  choosePreset();
  clearTimeout(state.timer);

  $("preset").addEventListener("change", choosePreset);
  for (const id of ["image", "config", "threshold", "knee", "tonemap"]) $(id).addEventListener("input", schedule);
  $("auto").addEventListener("change", () => { $("ev").disabled = $("auto").checked; schedule(); });
  $("ev").addEventListener("input", () => { $("ev-value").textContent = Number($("ev").value).toFixed(1); schedule(); });
  for (const button of document.querySelectorAll("#views button")) {
    button.addEventListener("click", () => {
      for (const b of document.querySelectorAll("#views button")) b.classList.toggle("on", b === button);
      state.view = button.dataset.view;
      render();
    });
  }
  // The split can only be placed once the pictures have their size.
  $("picture").addEventListener("load", placeSplit);
  $("under").addEventListener("load", placeSplit);
  $("handle").addEventListener("pointerdown", (down) => {
    const frame = $("frame").getBoundingClientRect();
    const move = (e) => { state.split = Math.min(1, Math.max(0, (e.clientX - frame.left) / frame.width)); placeSplit(); };
    move(down);
    window.addEventListener("pointermove", move);
    window.addEventListener("pointerup", () => window.removeEventListener("pointermove", move), { once: true });
  });
  $("copy-toml").addEventListener("click", () => navigator.clipboard.writeText($("config").value));
  $("download-toml").addEventListener("click", () => {
    const link = document.createElement("a");
    link.href = URL.createObjectURL(new Blob([$("config").value], { type: "application/toml" }));
    link.download = "camera.toml";
    link.click();
  });
  window.addEventListener("resize", schedule);
  fromAddress();
  render();
}

// A link can open the studio on an image, a preset or config, and a view:
// ?image=PATH&preset=NAME&config=TOML&view=split
function fromAddress() {
  const query = new URLSearchParams(location.search);
  const image = query.get("image");
  if (image) {
    if (![...$("image").options].some((o) => o.value === image)) $("image").add(new Option(image, image));
    $("image").value = image;
  }
  const preset = query.get("preset");
  if (preset && state.presets.some((p) => p.name === preset)) {
    $("preset").value = preset;
    choosePreset();
  }
  if (query.get("config")) $("config").value = query.get("config");
  const view = query.get("view");
  const button = view && document.querySelector(`#views button[data-view="${view}"]`);
  if (button) {
    for (const b of document.querySelectorAll("#views button")) b.classList.toggle("on", b === button);
    state.view = view;
  }
  clearTimeout(state.timer);
}

function choosePreset() {
  const preset = state.presets.find((p) => p.name === $("preset").value);
  $("config").value = preset.toml;
  $("preset-info").textContent = preset.description;
  schedule();
}

start();
