// The studio page: every control change asks the server for a new
// picture of the view's width; a newer request aborts an older one.
"use strict";

const $ = (id) => document.getElementById(id);
// Each tab is a client of its own: a new render replaces only this tab's
// last one, never another tab's.
const client = self.crypto && crypto.randomUUID ? crypto.randomUUID() : `${Date.now()}-${Math.random()}`;
const state = { view: "result", split: 0.5, controller: null, timer: null, presets: [] };

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

function showError(message) {
  // Each message goes next to the control that caused it.
  $("error").textContent = "";
  $("config-error").textContent = "";
  $("light-error").textContent = "";
  if (!message) return;
  if (/^config:|effect|camera|preset|seed|no effect/i.test(message)) $("config-error").textContent = message;
  else if (/threshold|knee/i.test(message)) $("light-error").textContent = message;
  else $("error").textContent = message;
}

// The display transform of aureole-io's display.rs, run here so that
// exposure and tone curve redraw at the display's rate without the server:
// x = L / white, the tone curve, then sRGB (a fine table).
const SRGB_STEPS = 65536;
const SRGB = (() => {
  const table = new Uint8ClampedArray(SRGB_STEPS + 1);
  for (let i = 0; i <= SRGB_STEPS; i++) {
    const v = i / SRGB_STEPS;
    const e = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    table[i] = Math.round(e * 255);
  }
  return table;
})();
const CURVES = {
  clip: (x) => Math.min(x, 1),
  reinhard: (x) => Math.min((x * (1 + x / 4)) / (1 + x), 1),
  filmic: (x) => Math.min(Math.max((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0), 1),
};

// srgb(curve(x)) as codes over 0 ≤ x < the curve's clipping point (code
// 255 beyond), one table per curve: a draw is a multiply and a look-up.
const CODE_STEPS = 1 << 18;
const codeTables = {};
function codeTable(name) {
  if (codeTables[name]) return codeTables[name];
  const curve = CURVES[name];
  const srgb = (t) => SRGB[Math.round(t * SRGB_STEPS)];
  let top = 1;
  while (srgb(curve(top)) < 255) top *= 2;
  const table = new Uint8ClampedArray(CODE_STEPS + 1);
  for (let i = 0; i <= CODE_STEPS; i++) table[i] = srgb(curve((i / CODE_STEPS) * top));
  codeTables[name] = { table, perUnit: CODE_STEPS / top };
  return codeTables[name];
}

function white(shown) {
  const tone = $("tonemap").value;
  return $("auto").checked ? shown.autoWhite[tone] : 1.2 * Math.pow(2, Number($("ev").value));
}

// The display: WebGL2 where the browser has it, so that the tone mapping
// runs per pixel on the GPU at the display's frame rate, else a 2D canvas
// (also with ?display=2d), where codes are looked up in a table of the same
// transform.
const VERTEX = `#version 300 es
in vec2 corner;
void main() { gl_Position = vec4(corner, 0.0, 1.0); }`;
// The curves and the sRGB encoding of display.rs, in f32 as there.
const FRAGMENT = `#version 300 es
precision highp float;
precision highp int;
uniform highp sampler2D shown;
uniform highp sampler2D under;
uniform float gain;
uniform int curve;
uniform int split;
uniform int height;
out vec4 colour;
vec3 tone(vec3 x) {
  x = max(x, 0.0);
  if (curve == 0) return min(x, 1.0);
  if (curve == 1) return min(x * (1.0 + x / 4.0) / (1.0 + x), 1.0);
  return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}
vec3 srgb(vec3 v) {
  return mix(1.055 * pow(v, vec3(1.0 / 2.4)) - 0.055, 12.92 * v, lessThanEqual(v, vec3(0.0031308)));
}
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  p.y = height - 1 - p.y;
  vec3 v = p.x < split ? texelFetch(under, p, 0).rgb : texelFetch(shown, p, 0).rgb;
  colour = vec4(srgb(tone(v * gain)), 1.0);
}`;
const CURVE_NUMBERS = { clip: 0, reinhard: 1, filmic: 2 };

function makeDisplay(canvas, wanted) {
  const gl = wanted === "2d" ? null : canvas.getContext("webgl2", { preserveDrawingBuffer: true, antialias: false });
  if (!gl) return canvasDisplay(canvas);
  const compile = (type, text) => {
    const shader = gl.createShader(type);
    gl.shaderSource(shader, text);
    gl.compileShader(shader);
    if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(shader));
    return shader;
  };
  const program = gl.createProgram();
  gl.attachShader(program, compile(gl.VERTEX_SHADER, VERTEX));
  gl.attachShader(program, compile(gl.FRAGMENT_SHADER, FRAGMENT));
  gl.linkProgram(program);
  if (!gl.getProgramParameter(program, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(program));
  gl.useProgram(program);
  gl.bindBuffer(gl.ARRAY_BUFFER, gl.createBuffer());
  gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 1, -1, -1, 1, 1, 1]), gl.STATIC_DRAW);
  const corner = gl.getAttribLocation(program, "corner");
  gl.enableVertexAttribArray(corner);
  gl.vertexAttribPointer(corner, 2, gl.FLOAT, false, 0, 0);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  const uniform = (name) => gl.getUniformLocation(program, name);
  const texture = (unit, name) => {
    const t = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0 + unit);
    gl.bindTexture(gl.TEXTURE_2D, t);
    for (const p of [gl.TEXTURE_MIN_FILTER, gl.TEXTURE_MAG_FILTER]) gl.texParameteri(gl.TEXTURE_2D, p, gl.NEAREST);
    gl.uniform1i(uniform(name), unit);
    return t;
  };
  const textures = { shown: texture(0, "shown"), under: texture(1, "under") };
  const loaded = { shown: null, under: null };
  const upload = (unit, name, picture) => {
    if (loaded[name] === picture) return;
    loaded[name] = picture;
    gl.activeTexture(gl.TEXTURE0 + unit);
    gl.bindTexture(gl.TEXTURE_2D, textures[name]);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGB32F, picture.width, picture.height, 0, gl.RGB, gl.FLOAT, picture.linear);
  };
  return {
    kind: "webgl2",
    draw(shown, under, curve, white, split) {
      upload(0, "shown", shown);
      upload(1, "under", under || shown);
      gl.viewport(0, 0, shown.width, shown.height);
      gl.uniform1f(uniform("gain"), 1 / white);
      gl.uniform1i(uniform("curve"), CURVE_NUMBERS[curve]);
      gl.uniform1i(uniform("split"), split);
      gl.uniform1i(uniform("height"), shown.height);
      gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
    },
    finish() {
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
    },
    pixels() {
      const data = new Uint8Array(canvas.width * canvas.height * 4);
      gl.readPixels(0, 0, canvas.width, canvas.height, gl.RGBA, gl.UNSIGNED_BYTE, data);
      // Rows come bottom first.
      const row = canvas.width * 4;
      const flipped = new Uint8Array(data.length);
      for (let y = 0; y < canvas.height; y++) flipped.set(data.subarray(y * row, (y + 1) * row), (canvas.height - 1 - y) * row);
      return flipped;
    },
  };
}

function canvasDisplay(canvas) {
  const context = canvas.getContext("2d");
  return {
    kind: "2d",
    draw(shown, under, curve, white, split) {
      const { width, height } = shown;
      const picture = context.createImageData(width, height);
      const data = picture.data;
      const { table, perUnit } = codeTable(curve);
      const gain = perUnit / white;
      for (let y = 0; y < height; y++) {
        for (let x = 0; x < width; x++) {
          const i = y * width + x;
          const source = x < split ? under.linear : shown.linear;
          for (let c = 0; c < 3; c++) {
            const k = source[3 * i + c] * gain;
            data[4 * i + c] = k > 0 ? (k < CODE_STEPS ? table[Math.round(k)] : 255) : 0;
          }
          data[4 * i + 3] = 255;
        }
      }
      context.putImageData(picture, 0, 0);
    },
    finish() {},
    pixels() {
      return context.getImageData(0, 0, canvas.width, canvas.height).data;
    },
  };
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

function schedule() {
  clearTimeout(state.timer);
  state.timer = setTimeout(render, 120);
}

function placeSplit() {
  const canvas = $("canvas");
  $("handle").style.left = `${state.split * canvas.clientWidth}px`;
}

// The server words the command line, from the same fields as an export.
async function updateCommand() {
  const body = request(state.view === "glare" ? "glare" : "result");
  delete body.width;
  body.output = $("output").value;
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
  const body = request(state.view === "glare" ? "glare" : "result");
  delete body.width;
  body.output = $("output").value;
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
      status.textContent = progress.error ? progress.error : `wrote ${progress.output}`;
      status.className = progress.error ? "error" : "info";
      break;
    }
    await new Promise((resolve) => setTimeout(resolve, 250));
  }
  bar.hidden = true;
  $("cancel-export").hidden = true;
}

// The camera as panels: the library's schema gives each parameter its
// control, unit and range; the server reads the TOML into a table and
// writes the table back, so the panels and the TOML stay one camera.
async function readConfig() {
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

async function writeConfig() {
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
  const input = document.createElement("input");
  const value = table[parameter.name];
  const fallback = parameter.default === null ? "required" : String(parameter.default);
  if (parameter.kind === "flag") {
    input.type = "checkbox";
    input.checked = value === undefined ? Boolean(parameter.default) : value;
    input.addEventListener("change", () => { table[parameter.name] = input.checked; changed(); });
  } else if (parameter.kind === "length") {
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

function choosePreset() {
  const preset = state.presets.find((p) => p.name === $("preset").value);
  $("config").value = preset.toml;
  $("preset-info").textContent = preset.description;
  readConfig();
  schedule();
}

start();
