// The studio page: every control change asks the server for a new
// picture of the view's width; a newer request aborts an older one.
import { $, client, schedule, showError, state } from "./common.js";
import { canvasDisplay, makeDisplay } from "./display.js";
import { choosePreset, readConfig, writeConfig } from "./panels.js";

function previewWidth() {
  // At 1:1 the preview is the image itself (up to 4096 px wide).
  if (state.actual && state.fullWidth) return Math.min(4096, state.fullWidth);
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
    client,
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
  const header = (name) => Number(response.headers.get(name));
  const [width, height] = (response.headers.get("x-preview-size") || "0x0").split("x").map(Number);
  const linear = body.format === "linear";
  const full = (response.headers.get("x-full-size") || "0x0").split("x").map(Number);
  const range = (response.headers.get("x-luminance") || "").split(" ").map(Number);
  state.fullWidth = full[0];
  $("image-info").textContent =
    `${full[0]}×${full[1]} px · ${header("x-scale")} cd/m² per unit · luminance ` +
    range.map((v) => v.toPrecision(3)).join(" / ") + " cd/m² (min / median / max)";
  return {
    linear: linear ? new Float32Array(await response.arrayBuffer()) : null,
    url: linear ? null : URL.createObjectURL(await response.blob()),
    width, height,
    energyIn: header("x-energy-in"),
    energyOut: header("x-energy-out"),
    ms: header("x-render-ms"),
    radial: (response.headers.get("x-profile-radial") || "").split(",").filter(Boolean).map(Number),
    angular: (response.headers.get("x-profile-angular") || "").split(",").filter(Boolean).map(Number),
    autoWhite: {
      filmic: header("x-auto-white-filmic"),
      reinhard: header("x-auto-white-reinhard"),
      clip: header("x-auto-white-clip"),
    },
  };
}


function white(shown) {
  const tone = $("tonemap").value;
  return $("auto").checked ? shown.autoWhite[tone] : 1.2 * Math.pow(2, Number($("ev").value));
}

function draw() {
  const shown = state.shown;
  if (!shown || !shown.linear) return;
  const started = performance.now();
  const canvas = $("canvas");
  if (canvas.width !== shown.width || canvas.height !== shown.height) {
    canvas.width = shown.width;
    canvas.height = shown.height;
  }
  const split = state.view === "split" && state.under ? Math.round(state.split * shown.width) : -1;
  state.display.draw(shown, state.under, $("tonemap").value, white(shown), split);
  placeSplit();
  state.drawMs = performance.now() - started;
  showNumbers();
}

// Controls move many times a frame: one draw per frame.
function drawSoon() {
  if (state.drawing) return;
  state.drawing = true;
  requestAnimationFrame(() => { state.drawing = false; draw(); });
}

// ?drawbench=1: 60 redraws at as many exposures, each waited for (a pixel
// read back), the median time per redraw in data-draw-ms.
function drawBench() {
  const times = [];
  const ev = $("ev");
  const before = ev.value;
  $("auto").checked = false;
  for (let i = 0; i < 60; i++) {
    ev.value = String(-2 + (i % 12) * 0.5);
    const started = performance.now();
    draw();
    state.display.finish();
    times.push(performance.now() - started);
  }
  ev.value = before;
  times.sort((a, b) => a - b);
  document.body.dataset.drawMs = times[30].toFixed(2);
}

// A line through `values`, spread over the canvas, with its range written.
function plot(canvas, values) {
  const context = canvas.getContext("2d");
  context.clearRect(0, 0, canvas.width, canvas.height);
  if (!values.length) return;
  const finite = values.filter(Number.isFinite);
  const low = Math.min(...finite), high = Math.max(...finite);
  const span = high - low || 1;
  context.strokeStyle = "#e0a040";
  context.beginPath();
  values.forEach((v, i) => {
    const x = (i / Math.max(values.length - 1, 1)) * (canvas.width - 8) + 4;
    const y = canvas.height - 6 - ((v - low) / span) * (canvas.height - 20);
    if (i === 0) context.moveTo(x, y); else context.lineTo(x, y);
  });
  context.stroke();
  context.fillStyle = "#8a8a8a";
  context.font = "10px sans-serif";
  context.fillText(`${high.toPrecision(3)}`, 4, 10);
  context.fillText(`${low.toPrecision(3)}`, 4, canvas.height - 2);
}

function showNumbers() {
  const shown = state.shown;
  if (!shown) return;
  const ratio = shown.energyIn ? (100 * shown.energyOut / shown.energyIn).toFixed(3) + " %" : "–";
  const parts = [`${shown.width}x${shown.height}`,
    `energy in ${shown.energyIn.toExponential(4)} out ${shown.energyOut.toExponential(4)} (${ratio})`];
  if (shown.linear) parts.push(`white ${white(shown).toPrecision(4)} cd/m²`);
  parts.push(`render ${shown.ms.toFixed(0)} ms`);
  if (shown.linear && state.drawMs !== undefined) parts.push(`display ${state.drawMs.toFixed(0)} ms`);
  $("numbers").textContent = parts.join(" · ");
}

async function render() {
  if (state.controller) state.controller.abort();
  const controller = new AbortController();
  state.controller = controller;
  const view = state.view;
  const kernel = view === "kernel";
  try {
    const body = request(view === "split" ? "result" : view);
    if (!kernel) body.format = "linear";
    const shown = await fetchPicture(body, controller.signal);
    const under = view === "split"
      ? await fetchPicture({ ...request("original"), format: "linear" }, controller.signal)
      : null;
    if (controller.signal.aborted) return;
    state.shown = shown;
    state.under = under;
    $("canvas").hidden = kernel;
    $("picture").hidden = !kernel;
    $("handle").hidden = view !== "split";
    $("profiles").hidden = !kernel;
    if (kernel) {
      $("picture").src = shown.url;
      plot($("radial"), shown.radial.map((v) => Math.log10(Math.max(v, 1e-30))));
      plot($("angular"), shown.angular);
      showNumbers();
    } else {
      draw();
    }
    showError("");
    document.body.dataset.rendered = String(Number(document.body.dataset.rendered || 0) + 1);
    if (state.selfCheck && !kernel) await selfCheck(controller.signal);
    if (state.drawBench && !kernel) drawBench();
  } catch (error) {
    if (error.name === "AbortError" || error.status === 409) return;
    showError(error.message);
    document.body.dataset.failed = String(Number(document.body.dataset.failed || 0) + 1);
  }
  updateCommand();
}

// ?selfcheck=1: the server's picture of the same view against what this
// page drew, the largest difference in 8-bit codes (the browser test reads
// it).
async function selfCheck(signal) {
  // The server's 8-bit codes come raw, so nothing but the fetch is waited on.
  const body = { ...request(state.view === "split" ? "result" : state.view), format: "rgb8" };
  const response = await fetch("/api/render", {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body), signal,
  });
  const theirs = new Uint8Array(await response.arrayBuffer());
  const ours = state.display.pixels();
  let worst = theirs.length === (ours.length / 4) * 3 ? 0 : 255;
  for (let i = 0, j = 0; i < theirs.length && j < ours.length; i += 3, j += 4) {
    for (let c = 0; c < 3; c++) worst = Math.max(worst, Math.abs(theirs[i + c] - ours[j + c]));
  }
  document.body.dataset.displayMismatch = String(worst);
}


function placeSplit() {
  const canvas = $("canvas");
  $("handle").style.left = `${state.split * canvas.clientWidth}px`;
}

// An export's fields: the render's, the output and whether the glare
// layers go beside the result.
function exportBody() {
  const body = request(state.view === "glare" ? "glare" : "result");
  delete body.width;
  body.output = $("output").value;
  if ($("layers").checked) body.layers = true;
  return body;
}

// The server words the command line, from the same fields as an export.
async function updateCommand() {
  const body = exportBody();
  try {
    const response = await fetch("/api/command", {
      method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
    });
    if (response.ok) $("command").textContent = (await response.json()).text;
  } catch (error) {
    // A command line that cannot be had leaves the last one shown.
  }
}

async function start() {
  state.render = render;
  const [presets, images, schema] = await Promise.all([
    fetch("/api/presets").then((r) => r.json()),
    fetch("/api/images").then((r) => r.json()),
    fetch("/api/schema").then((r) => r.json()),
  ]);
  state.schema = schema;
  for (const e of schema.effects) $("add-type").add(new Option(e.type, e.type));
  $("add-effect").addEventListener("click", () => {
    const kind = schema.effects.find((e) => e.type === $("add-type").value);
    state.effects.push({ table: JSON.parse(JSON.stringify(kind.example || { type: kind.type })), on: true });
    writeConfig();
  });
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
  for (const id of ["image", "threshold", "knee"]) $(id).addEventListener("input", schedule);
  let typing = null;
  $("config").addEventListener("input", () => {
    clearTimeout(typing);
    typing = setTimeout(() => readConfig(), 300);
    schedule();
  });
  // Exposure and tone curve are the page's own: redrawn without the server.
  $("tonemap").addEventListener("input", () => { drawSoon(); updateCommand(); });
  $("auto").addEventListener("change", () => { $("ev").disabled = $("auto").checked; drawSoon(); updateCommand(); });
  $("ev").addEventListener("input", () => { $("ev-value").textContent = Number($("ev").value).toFixed(1); drawSoon(); updateCommand(); });
  for (const button of document.querySelectorAll("#views button")) {
    button.addEventListener("click", () => {
      for (const b of document.querySelectorAll("#views button")) b.classList.toggle("on", b === button);
      state.view = button.dataset.view;
      render();
    });
  }
  $("handle").addEventListener("pointerdown", (down) => {
    const frame = $("frame").getBoundingClientRect();
    const move = (e) => { state.split = Math.min(1, Math.max(0, (e.clientX - frame.left) / frame.width)); drawSoon(); };
    move(down);
    window.addEventListener("pointermove", move);
    window.addEventListener("pointerup", () => window.removeEventListener("pointermove", move), { once: true });
  });
  $("output").value = defaultOutput();
  $("image").addEventListener("change", () => { $("output").value = defaultOutput(); });
  $("output").addEventListener("input", updateCommand);
  $("layers").addEventListener("change", updateCommand);
  $("export").addEventListener("click", exportFull);
  $("copy-toml").addEventListener("click", () => navigator.clipboard.writeText($("config").value));
  $("download-toml").addEventListener("click", () => {
    const link = document.createElement("a");
    link.href = URL.createObjectURL(new Blob([$("config").value], { type: "application/toml" }));
    link.download = "camera.toml";
    link.click();
  });
  $("actual").addEventListener("click", () => {
    state.actual = !state.actual;
    $("actual").classList.toggle("on", state.actual);
    document.body.classList.toggle("actual", state.actual);
    render();
  });
  window.addEventListener("resize", schedule);
  window.addEventListener("resize", placeSplit);
  fromAddress();
  render();
}

// A link can open the studio on an image, a preset or config, and a view:
// ?image=PATH&preset=NAME&config=TOML&view=split&tonemap=reinhard&ev=3
function fromAddress() {
  const query = new URLSearchParams(location.search);
  state.selfCheck = query.get("selfcheck") === "1";
  state.drawBench = query.get("drawbench") === "1";
  try {
    state.display = makeDisplay($("canvas"), query.get("display"));
  } catch (error) {
    // A GPU that will not compile the shader: draw on the CPU instead.
    console.warn(`WebGL display unavailable: ${error.message}`);
    const fresh = $("canvas").cloneNode();
    $("canvas").replaceWith(fresh);
    state.display = canvasDisplay(fresh);
  }
  document.body.dataset.display = state.display.kind;
  const image = query.get("image");
  if (image) {
    if (![...$("image").options].some((o) => o.value === image)) $("image").add(new Option(image, image));
    $("image").value = image;
  }
  const tone = query.get("tonemap");
  if (tone && [...$("tonemap").options].some((o) => o.value === tone)) $("tonemap").value = tone;
  if (query.get("ev") !== null && Number.isFinite(Number(query.get("ev")))) {
    $("auto").checked = false;
    $("ev").disabled = false;
    $("ev").value = query.get("ev");
    $("ev-value").textContent = Number($("ev").value).toFixed(1);
  }
  const preset = query.get("preset");
  if (preset && state.presets.some((p) => p.name === preset)) {
    $("preset").value = preset;
    choosePreset();
  }
  if (query.get("config")) { $("config").value = query.get("config"); readConfig(); }
  const view = query.get("view");
  const button = view && document.querySelector(`#views button[data-view="${view}"]`);
  if (button) {
    for (const b of document.querySelectorAll("#views button")) b.classList.toggle("on", b === button);
    state.view = view;
  }
  clearTimeout(state.timer);
}

function defaultOutput() {
  const image = $("image").value;
  if (image === "demo") return "street-aureole.exr";
  return image.replace(/(\.[^./]*)?$/, (ext) => `-aureole${ext || ".exr"}`);
}

async function exportFull() {
  const body = exportBody();
  const status = $("export-status");
  const bar = $("export-progress");
  status.textContent = "";
  const started = await fetch("/api/export", {
    method: "POST", headers: { "Content-Type": "application/json" }, body: JSON.stringify(body),
  });
  const reply = await started.json();
  if (!started.ok) { status.textContent = reply.error; status.className = "error"; return; }
  status.className = "info";
  bar.hidden = false;
  $("cancel-export").hidden = false;
  $("cancel-export").onclick = () => fetch(`/api/export/${reply.job}`, { method: "DELETE" });
  for (;;) {
    const progress = await (await fetch(`/api/export/${reply.job}`)).json();
    bar.value = progress.fraction;
    status.textContent = `${progress.stage} ${Math.round(100 * progress.fraction)} %`;
    if (progress.done) {
      status.textContent = progress.error ? progress.error
        : [`wrote ${progress.output}`, ...progress.notes].join("; ");
      status.className = progress.error ? "error" : "info";
      break;
    }
    await new Promise((resolve) => setTimeout(resolve, 250));
  }
  bar.hidden = true;
  $("cancel-export").hidden = true;
}



start();
