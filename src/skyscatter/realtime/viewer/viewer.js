// skyscatter view: the precomputed atmosphere in WebGL2, from the textures of `skyscatter export-luts` and the
// GLSL library of the package (served by `skyscatter view` on 127.0.0.1; nothing is loaded from elsewhere).
// Pass 1 renders linear radiance (linear sRGB, Y = luminance / 683) into an RGBA32F framebuffer; pass 2 applies
// the exposure and the Reinhard curve on luminance and encodes sRGB for the canvas.
"use strict";

const MANIFEST_FORMAT = "skyscatter-realtime-luts";
const MANIFEST_VERSION = 12;
const TEXTURES = ["transmittance", "optical_depth", "irradiance", "rayleigh", "mie", "multiple"];
const SAMPLERS = {transmittance: "transmittance_texture", optical_depth: "optical_depth_texture",
                  irradiance: "irradiance_texture",
                  rayleigh: "rayleigh_texture", mie: "mie_texture", multiple: "multiple_texture"};

const VERTEX = `#version 300 es
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}`;

// The view: pixel directions exactly as skyscatter.conventions (pinhole_directions, fisheye_directions,
// equirect_directions) give them, in the East-North-Up frame of the point below the camera (x east, y north, z up;
// the camera at (0, 0, R + altitude) of the planet-centred frame).
const SKY_MAIN = `
uniform vec3 u_camera;
uniform vec3 u_sun;
uniform float u_heading;
uniform vec3 u_forward;
uniform vec3 u_right;
uniform vec3 u_up;
uniform float u_half_width;
uniform int u_projection;
uniform vec2 u_size;
uniform bool u_show_sun;
uniform bool u_ground;
uniform bool u_fog;
uniform bool u_checker;
out vec4 frag_color;

vec3 DirectionFromAngles(float zenith, float azimuth) {
  return vec3(sin(zenith) * sin(azimuth), sin(zenith) * cos(azimuth), cos(zenith));
}

void main() {
  float col = gl_FragCoord.x;           // pixel centre, from the left: i + 0.5
  float row = u_size.y - gl_FragCoord.y; // pixel centre, from the top: j + 0.5
  vec3 v;
  bool inside = true;
  if (u_projection == 0) {
    // the camera's axes and tan(fov / 2) come from JavaScript in double precision: from orbit a direction 1e-5 rad
    // off (float32 sin, cos, tan on some GPUs) moves the limb of the atmosphere by a tenth of its brightness
    float half_h = u_half_width * u_size.y / u_size.x;
    v = normalize(u_forward + (col / u_size.x * 2.0 - 1.0) * u_half_width * u_right
                  + (1.0 - row / u_size.y * 2.0) * half_h * u_up);
  } else if (u_projection == 1) {
    float s = min(u_size.x, u_size.y);
    float px = (col - 0.5 * (u_size.x - s)) / s * 2.0 - 1.0;
    float py = (row - 0.5 * (u_size.y - s)) / s * 2.0 - 1.0;
    float rr = length(vec2(px, py));
    inside = rr <= 1.0;
    v = DirectionFromAngles(rr * 0.5 * PI, atan(-px, -py) + u_heading);
  } else {
    v = DirectionFromAngles(PI * row / u_size.y, 2.0 * PI * (col / u_size.x - 0.5) + u_heading);
  }
  vec3 radiance = vec3(0.0);
  if (inside) {
    float r = length(u_camera);
    float rmu = dot(u_camera, v);
    float p = length(cross(u_camera, v));  // distance from the planet's centre to the ray's line
    bool hit = rmu < 0.0 && p <= BOTTOM_RADIUS;
    vec3 transmittance;
    vec3 sky = GetSkyRadiance(u_camera, v, u_sun, transmittance);
    radiance = sky;
    if (hit && u_ground) {
      float d = -rmu - sqrt(max((BOTTOM_RADIUS - p) * (BOTTOM_RADIUS + p), 0.0));
      vec3 g = u_camera + d * v;
      vec3 albedo = GROUND_ALBEDO;
      if (u_checker) albedo *= mod(floor(g.x / 1000.0) + floor(g.y / 1000.0), 2.0) < 0.5 ? 0.5 : 1.5;
      if (u_fog) {
        radiance = sky + GetGroundRadiance(u_camera, v, u_sun, albedo);
      } else {
        vec3 sky_irradiance;
        vec3 sun_irradiance = GetSunAndSkyIrradiance(g, normalize(g), u_sun, sky_irradiance);
        radiance = albedo / PI * (sun_irradiance + sky_irradiance);
      }
    }
    if (u_show_sun && !hit && dot(v, u_sun) > cos(SUN_ANGULAR_RADIUS)) radiance += GetSolarRadiance(u_camera, u_sun);
  }
  frag_color = vec4(radiance, 1.0);
}`;

// Library functions evaluated for a list of cases (tests and scripts): case i reads its three input vectors from
// column i of u_inputs (rows 0-2) and writes two results into rows 0 and 1 of the output.
const PROBE_MAIN = `
uniform highp sampler2D u_inputs;
uniform int u_kind;
out vec4 frag_color;
void main() {
  int i = int(gl_FragCoord.x);
  int row = int(gl_FragCoord.y);
  vec3 a = texelFetch(u_inputs, ivec2(i, 0), 0).xyz;
  vec3 b = texelFetch(u_inputs, ivec2(i, 1), 0).xyz;
  vec3 c = texelFetch(u_inputs, ivec2(i, 2), 0).xyz;
  vec3 first, second;
  if (u_kind == 0) {          // aerial perspective: camera, point, sun -> inscatter, transmittance
    first = GetSkyRadianceToPoint(a, b, c, second);
  } else if (u_kind == 1) {   // irradiance: point, normal, sun -> sun irradiance, sky irradiance
    first = GetSunAndSkyIrradiance(a, b, c, second);
  } else {                    // sky: camera, view direction, sun -> radiance, transmittance
    first = GetSkyRadiance(a, b, c, second);
  }
  frag_color = vec4(row == 0 ? first : second, 1.0);
}`;

const TONEMAP = `#version 300 es
precision highp float;
uniform highp sampler2D u_hdr;
uniform float u_scale;
out vec4 frag_color;
float Encode(float c) { return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055; }
void main() {
  vec3 c = max(texelFetch(u_hdr, ivec2(gl_FragCoord.xy), 0).rgb * u_scale, vec3(0.0));
  float y = dot(c, vec3(0.2126, 0.7152, 0.0722));
  c = clamp(c / (1.0 + y), 0.0, 1.0);
  frag_color = vec4(Encode(c.r), Encode(c.g), Encode(c.b), 1.0);
}`;

const viewer = {ready: null, error: null, manifest: null, params: null};
window.skyscatterViewer = viewer;

function showError(text) {
  viewer.error = text;
  const box = document.getElementById("message");
  box.textContent = "skyscatter view cannot show the sky:\n\n" + text;
  box.hidden = false;
  document.getElementById("sky").style.visibility = "hidden";
}

async function fetchChecked(url, what) {
  let response;
  try {
    response = await fetch(url, {cache: "no-store"});
  } catch (e) {
    throw new Error(`${what} (${url}): cannot be fetched (${e.message}); is 'skyscatter view' still running?`);
  }
  if (!response.ok) {
    throw new Error(`${what} (${url}): HTTP ${response.status}: the file is missing from the export folder; ` +
                    "export the tables again with 'skyscatter export-luts'");
  }
  return response;
}

async function loadManifest() {
  const response = await fetchChecked("/luts/skyscatter_realtime.json", "the manifest skyscatter_realtime.json");
  let manifest;
  try {
    manifest = await response.json();
  } catch (e) {
    throw new Error(`the manifest skyscatter_realtime.json is not JSON (${e.message})`);
  }
  if (!manifest || manifest.format !== MANIFEST_FORMAT) {
    throw new Error(`skyscatter_realtime.json is not a skyscatter real-time manifest (format ` +
                    `${JSON.stringify(manifest && manifest.format)}, expected "${MANIFEST_FORMAT}")`);
  }
  if (manifest.version !== MANIFEST_VERSION) {
    throw new Error(`skyscatter_realtime.json has manifest version ${JSON.stringify(manifest.version)}; this viewer ` +
                    `reads version ${MANIFEST_VERSION} only: export the tables again with this skyscatter ` +
                    "('skyscatter export-luts --formats rgba32f,rgba16f')");
  }
  return manifest;
}

async function loadTexture(gl, manifest, name, format) {
  const entry = manifest.textures[name];
  const file = entry && entry.files && entry.files[format];
  if (!file) {
    throw new Error(`texture ${name} was not exported as ${format} (exported: ` +
                    `${Object.keys((entry && entry.files) || {}).join(", ") || "none"})`);
  }
  const response = await fetchChecked("/luts/" + file.file, `texture file ${file.file}`);
  const bytes = await response.arrayBuffer();
  const texels = entry.width * entry.height * (entry.depth || 1);
  const expected = texels * 4 * (format === "rgba32f" ? 4 : 2);
  if (bytes.byteLength !== file.bytes || bytes.byteLength !== expected) {
    throw new Error(`texture file ${file.file} has ${bytes.byteLength} bytes; the manifest says ${file.bytes} ` +
                    `(${entry.width} x ${entry.height}${entry.depth ? " x " + entry.depth : ""} RGBA texels): ` +
                    "truncated or damaged, export the tables again");
  }
  const data = format === "rgba32f" ? new Float32Array(bytes) : new Uint16Array(bytes);
  const internal = format === "rgba32f" ? gl.RGBA32F : gl.RGBA16F;
  const type = format === "rgba32f" ? gl.FLOAT : gl.HALF_FLOAT;
  const tex = gl.createTexture();
  const target = entry.dimensions === 3 ? gl.TEXTURE_3D : gl.TEXTURE_2D;
  gl.bindTexture(target, tex);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  if (target === gl.TEXTURE_3D) {
    gl.texImage3D(target, 0, internal, entry.width, entry.height, entry.depth, 0, gl.RGBA, type, data);
    gl.texParameteri(target, gl.TEXTURE_WRAP_R, gl.CLAMP_TO_EDGE);
  } else {
    gl.texImage2D(target, 0, internal, entry.width, entry.height, 0, gl.RGBA, type, data);
  }
  gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
  gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
  gl.texParameteri(target, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
  gl.texParameteri(target, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
  return {tex, target};
}

function compile(gl, type, source, what) {
  const shader = gl.createShader(type);
  gl.shaderSource(shader, source);
  gl.compileShader(shader);
  if (!gl.getShaderParameter(shader, gl.COMPILE_STATUS)) {
    throw new Error(`the ${what} shader does not compile: ${gl.getShaderInfoLog(shader)}`);
  }
  return shader;
}

function program(gl, fragment, what) {
  const p = gl.createProgram();
  gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, VERTEX, "vertex"));
  gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, fragment, what));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) {
    throw new Error(`the ${what} program does not link: ${gl.getProgramInfoLog(p)}`);
  }
  return p;
}

function floatTarget(gl, width, height) {
  const tex = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, tex);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, width, height, 0, gl.RGBA, gl.FLOAT, null);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  const fbo = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
  if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) {
    throw new Error("this browser cannot render to a float framebuffer (RGBA32F)");
  }
  return {tex, fbo, width, height};
}

const DEG = Math.PI / 180;
const state = {sun_elevation: 30, sun_azimuth: 180, altitude: 0, exposure: 0, projection: 0, fov: 90,
               heading: 180, pitch: 10, ground: true, fog: true, checker: false, sun: true,
               exact_filtering: false};

function altitudeFromSlider(x) { return Math.pow(10, 6 * x) - 1; }        // 0 .. 1000 km [m]
function sliderFromAltitude(h) { return Math.log10(h + 1) / 6; }

function formatAltitude(h) { return h < 1000 ? `${h.toFixed(0)} m` : `${(h / 1000).toFixed(h < 1e4 ? 2 : 0)} km`; }

async function start() {
  const canvas = document.getElementById("sky");
  const query = new URLSearchParams(window.location.search);
  const format = query.get("format") || "rgba32f";
  if (format !== "rgba32f" && format !== "rgba16f") throw new Error(`format must be rgba32f or rgba16f, not ${format}`);
  const gl = canvas.getContext("webgl2", {antialias: false, preserveDrawingBuffer: true});
  if (!gl) throw new Error("this browser has no WebGL2 (in Chromium try --use-angle=swiftshader --enable-unsafe-swiftshader)");
  if (!gl.getExtension("EXT_color_buffer_float")) throw new Error("WebGL2 without EXT_color_buffer_float: cannot render to float");
  if (format === "rgba32f" && !gl.getExtension("OES_texture_float_linear")) {
    throw new Error("this GPU cannot filter float32 textures (OES_texture_float_linear); open the page with ?format=rgba16f");
  }
  const manifest = await loadManifest();
  viewer.manifest = manifest;
  const library = await (await fetchChecked("/glsl/atmosphere.glsl", "the GLSL library")).text();
  const textures = {};
  for (const name of TEXTURES) textures[name] = await loadTexture(gl, manifest, name, format);
  const header = "#version 300 es\nprecision highp float;\nprecision highp int;\nprecision highp sampler3D;\n";
  const exact = "#define SKYSCATTER_EXACT_FILTERING\n";
  const sky = program(gl, header + manifest.glsl_constants + library + SKY_MAIN, "sky");
  const skyExact = program(gl, header + exact + manifest.glsl_constants + library + SKY_MAIN, "sky (exact filtering)");
  const tonemap = program(gl, TONEMAP, "tone mapping");
  let probe = null;
  const c = manifest.constants;
  let target = null;

  function uniforms(p, width, height) {
    const prog = p.exact_filtering ? skyExact : sky;
    gl.useProgram(prog);
    TEXTURES.forEach((name, unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(textures[name].target, textures[name].tex);
      gl.uniform1i(gl.getUniformLocation(prog, SAMPLERS[name]), unit);
    });
    const el = p.sun_elevation * DEG, az = p.sun_azimuth * DEG;
    gl.uniform3f(gl.getUniformLocation(prog, "u_sun"), Math.cos(el) * Math.sin(az), Math.cos(el) * Math.cos(az), Math.sin(el));
    gl.uniform3f(gl.getUniformLocation(prog, "u_camera"), 0, 0, c.BOTTOM_RADIUS + p.altitude);
    gl.uniform1f(gl.getUniformLocation(prog, "u_heading"), p.heading * DEG);
    // pinhole camera axes as skyscatter.conventions.pinhole_directions: forward at (heading, pitch), right
    // horizontal, up = right x forward
    const h = p.heading * DEG, t = p.pitch * DEG;
    const fwd = [Math.cos(t) * Math.sin(h), Math.cos(t) * Math.cos(h), Math.sin(t)];
    const right = [Math.cos(h), -Math.sin(h), 0];
    const up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2],
                right[0] * fwd[1] - right[1] * fwd[0]];
    gl.uniform3fv(gl.getUniformLocation(prog, "u_forward"), fwd);
    gl.uniform3fv(gl.getUniformLocation(prog, "u_right"), right);
    gl.uniform3fv(gl.getUniformLocation(prog, "u_up"), up);
    gl.uniform1f(gl.getUniformLocation(prog, "u_half_width"), Math.tan(0.5 * p.fov * DEG));
    gl.uniform1i(gl.getUniformLocation(prog, "u_projection"), p.projection);
    gl.uniform2f(gl.getUniformLocation(prog, "u_size"), width, height);
    for (const k of ["ground", "fog", "checker"]) gl.uniform1i(gl.getUniformLocation(prog, "u_" + k), p[k] ? 1 : 0);
    gl.uniform1i(gl.getUniformLocation(prog, "u_show_sun"), p.sun ? 1 : 0);
  }

  function renderHdr(p, width, height) {
    if (!target || target.width !== width || target.height !== height) target = floatTarget(gl, width, height);
    gl.bindFramebuffer(gl.FRAMEBUFFER, target.fbo);
    gl.viewport(0, 0, width, height);
    uniforms(p, width, height);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  function draw(p) {
    const width = canvas.width, height = canvas.height;
    renderHdr(p, width, height);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    gl.viewport(0, 0, width, height);
    gl.useProgram(tonemap);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, target.tex);
    gl.uniform1i(gl.getUniformLocation(tonemap, "u_hdr"), 0);
    gl.uniform1f(gl.getUniformLocation(tonemap, "u_scale"), Math.pow(2, p.exposure) * 0.25);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
  }

  // For tests and scripts: render a view and read the float radiance back (base64 of little-endian float32 RGBA,
  // rows from the top), time frames, or set the view.
  viewer.render = (params) => { Object.assign(state, params || {}); syncControls(); draw(state); };
  viewer.readFloat = (params, width, height) => {
    const p = Object.assign({}, state, params || {});
    renderHdr(p, width, height);
    const pixels = new Float32Array(width * height * 4);
    gl.readPixels(0, 0, width, height, gl.RGBA, gl.FLOAT, pixels);
    const flipped = new Float32Array(width * height * 4);
    for (let j = 0; j < height; j++) {
      flipped.set(pixels.subarray((height - 1 - j) * width * 4, (height - j) * width * 4), j * width * 4);
    }
    const bytes = new Uint8Array(flipped.buffer);
    let text = "";
    for (let i = 0; i < bytes.length; i += 0x8000) text += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(text);
  };
  // Evaluate a library function for cases [[a, b, c], ...] (kind "aerial", "irradiance" or "sky"); returns
  // [[first, second], ...] as arrays of 3 numbers (float32 on the GPU).
  viewer.probe = (kind, cases) => {
    if (!probe) probe = program(gl, header + manifest.glsl_constants + library + PROBE_MAIN, "probe");
    const n = cases.length;
    const input = new Float32Array(n * 3 * 4);
    cases.forEach((c, i) => { for (let r = 0; r < 3; r++) input.set(c[r], (r * n + i) * 4); });
    const out = floatTarget(gl, n, 2);  // first: it binds its texture to the active unit
    const tex = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0 + TEXTURES.length);
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, n, 3, 0, gl.RGBA, gl.FLOAT, input);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.bindFramebuffer(gl.FRAMEBUFFER, out.fbo);
    gl.viewport(0, 0, n, 2);
    gl.useProgram(probe);
    TEXTURES.forEach((name, unit) => {
      gl.activeTexture(gl.TEXTURE0 + unit);
      gl.bindTexture(textures[name].target, textures[name].tex);
      gl.uniform1i(gl.getUniformLocation(probe, SAMPLERS[name]), unit);
    });
    gl.uniform1i(gl.getUniformLocation(probe, "u_inputs"), TEXTURES.length);
    gl.uniform1i(gl.getUniformLocation(probe, "u_kind"), {aerial: 0, irradiance: 1, sky: 2}[kind]);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const pixels = new Float32Array(n * 2 * 4);
    gl.readPixels(0, 0, n, 2, gl.RGBA, gl.FLOAT, pixels);
    gl.deleteTexture(tex);
    gl.deleteTexture(out.tex);
    gl.deleteFramebuffer(out.fbo);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    return cases.map((_, i) => [Array.from(pixels.subarray(i * 4, i * 4 + 3)),
                                Array.from(pixels.subarray((n + i) * 4, (n + i) * 4 + 3))]);
  };
  viewer.frameTime = (frames) => {
    const one = new Uint8Array(4);
    draw(state);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, one);
    const times = [];
    for (let i = 0; i < frames; i++) {
      const t0 = performance.now();
      draw(state);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, one);
      times.push(performance.now() - t0);
    }
    return times;
  };

  // Controls
  const ids = ["sun_elevation", "sun_azimuth", "altitude", "exposure", "projection", "fov", "ground", "fog", "checker", "sun"];
  function syncControls() {
    for (const id of ids) {
      const el = document.getElementById(id);
      if (el.type === "checkbox") el.checked = state[id];
      else el.value = id === "altitude" ? sliderFromAltitude(state.altitude) : state[id];
    }
    document.getElementById("sun_elevation_out").textContent = state.sun_elevation.toFixed(1);
    document.getElementById("sun_azimuth_out").textContent = state.sun_azimuth.toFixed(1);
    document.getElementById("altitude_out").textContent = formatAltitude(state.altitude);
    document.getElementById("exposure_out").textContent = state.exposure.toFixed(1);
    document.getElementById("fov_out").textContent = state.fov.toFixed(0);
  }
  let pending = false;
  function redraw() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; draw(state); });
  }
  for (const id of ids) {
    document.getElementById(id).addEventListener("input", (ev) => {
      const el = ev.target;
      if (el.type === "checkbox") state[id] = el.checked;
      else if (id === "altitude") state.altitude = altitudeFromSlider(parseFloat(el.value));
      else state[id] = id === "projection" ? parseInt(el.value, 10) : parseFloat(el.value);
      syncControls();
      redraw();
    });
  }
  let drag = null;
  canvas.addEventListener("pointerdown", (ev) => { drag = {x: ev.clientX, y: ev.clientY}; canvas.setPointerCapture(ev.pointerId); });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    const scale = (state.projection === 0 ? state.fov : 180) / canvas.clientWidth;
    state.heading = (state.heading - (ev.clientX - drag.x) * scale + 360) % 360;
    state.pitch = Math.max(-89.9, Math.min(89.9, state.pitch + (ev.clientY - drag.y) * scale));
    drag = {x: ev.clientX, y: ev.clientY};
    redraw();
  });
  syncControls();
  draw(state);
  document.getElementById("status").textContent =
      `drag to look around - ${format}, manifest v${manifest.version}, ${manifest.written_by}`;
}

viewer.ready = start().then(() => true, (e) => { showError(e.message || String(e)); return false; });
