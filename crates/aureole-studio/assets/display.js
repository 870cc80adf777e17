// The page's display of the linear preview: aureole-io's display.rs
// (exposure, tone curve, sRGB), in WebGL2 or on a 2D canvas.

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

export function makeDisplay(canvas, wanted) {
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

export function canvasDisplay(canvas) {
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

