// carom play: the page. It draws what the server (or a replay file) sends and sends back what
// the hands do. Messages in: binary (carom.play.wire.pack: 'CRM1', a JSON header, typed
// arrays) for the shapes and every frame; JSON text for replies. Messages out: JSON commands.
"use strict";

(function () {
  const $ = (id) => document.getElementById(id);
  const TYPES = { float32: Float32Array, float64: Float64Array, int32: Int32Array, uint8: Uint8Array, uint32: Uint32Array };

  // -- wire --------------------------------------------------------------------------------
  function unpack(buffer) {
    const view = new DataView(buffer);
    const magic = String.fromCharCode(view.getUint8(0), view.getUint8(1), view.getUint8(2), view.getUint8(3));
    if (magic !== "CRM1") throw new Error("not a carom play message");
    const size = view.getUint32(4, true);
    const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 8, size)));
    const start = 8 + size;
    const arrays = {};
    for (const [name, dtype, shape, offset] of header.arrays) {
      const count = shape.reduce((a, b) => a * b, 1);
      const array = new TYPES[dtype](buffer, start + offset, count);
      array.shape = shape;
      arrays[name] = array;
    }
    return [header, arrays];
  }

  // -- colours -----------------------------------------------------------------------------
  // viridis, 9 stops: slow bodies dark blue, fast ones yellow
  const STOPS = [[68, 1, 84], [71, 44, 122], [59, 81, 139], [44, 113, 142], [33, 144, 141],
    [39, 173, 129], [92, 200, 99], [170, 220, 50], [253, 231, 37]];
  const BINS = 32;
  const PALETTE = [];
  for (let i = 0; i < BINS; i++) {
    const u = (i / (BINS - 1)) * (STOPS.length - 1);
    const k = Math.min(Math.floor(u), STOPS.length - 2);
    const f = u - k;
    PALETTE.push(STOPS[k].map((c, j) => Math.round(c + f * (STOPS[k + 1][j] - c))));
  }
  const STILL = [120, 124, 132];
  const ISLANDS = [[230, 97, 1], [94, 60, 153], [27, 158, 119], [217, 95, 2], [231, 41, 138], [102, 166, 30], [230, 171, 2], [166, 118, 29]];

  // -- state -------------------------------------------------------------------------------
  const state = {
    shapes: null, shapeHeader: null, frame: null, header: null, dim: 2,
    speedScale: 0, energy: [], framesSeen: 0, fps: 0, fpsCount: 0, fpsSince: performance.now(),
    drawings: new Set(["joints"]), options: { resolution: 1, edges: true, adaptive: true }, held: -1, socket: null, replay: null, status: "", statusUntil: 0,
  };

  // -- the view: one WebGL2 canvas for 2D and 3D ---------------------------------------------
  // The bodies' shapes go to the GPU once, in their own frames, each vertex tagged with its
  // body; a frame uploads only each body's place, turn and colour (a float texture, two
  // texels a body), and the vertex shader puts every vertex in the world. A 2D body turns
  // about z (the quaternion of its angle); the camera is orthographic in 2D, perspective in 3D.
  const canvas = $("view");
  const camera2 = { cx: 0, cy: 0, scale: 20 };  // world point at the centre, pixels a metre
  const camera3 = { target: [0, 0, 0], yaw: -0.6, pitch: 0.45, distance: 10, fov: 0.9 };
  const ROW = 1024;  // bodies a texture row
  const STILL_COLOUR = BINS + ISLANDS.length, HIDDEN = -1;

  function fit2d(box) {
    const [lo, hi] = box;
    const w = canvas.clientWidth || 800, h = canvas.clientHeight || 600;
    camera2.cx = 0.5 * (lo[0] + hi[0]);
    camera2.cy = 0.5 * (lo[1] + hi[1]);
    camera2.scale = 0.9 * Math.min(w / Math.max(hi[0] - lo[0], 1e-9), h / Math.max(hi[1] - lo[1], 1e-9));
  }
  function fit3d(box, size) {
    const [lo, hi] = box;
    camera3.target = [0, 1, 2].map((k) => 0.5 * (lo[k] + hi[k]));
    const extent = Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    camera3.distance = Math.min(1.6 * extent, 60 * size + 1.6 * extent) || 10;
  }
  function toScreen(p) {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    return [w / 2 + (p[0] - camera2.cx) * camera2.scale, h / 2 - (p[1] - camera2.cy) * camera2.scale];
  }
  function toWorld(sx, sy) {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    return [camera2.cx + (sx - w / 2) / camera2.scale, camera2.cy - (sy - h / 2) / camera2.scale];
  }
  const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const norm = (a) => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; };
  function eye() {
    const c = camera3, cp = Math.cos(c.pitch);
    return [c.target[0] + c.distance * cp * Math.cos(c.yaw), c.target[1] + c.distance * cp * Math.sin(c.yaw), c.target[2] + c.distance * Math.sin(c.pitch)];
  }
  function basis() {
    const e = eye(), f = norm(sub(camera3.target, e));
    const r = norm(cross(f, [0, 0, 1])), u = cross(r, f);
    return { e, f, r, u };
  }
  function viewProjection() {
    const w = Math.max(canvas.clientWidth, 1), h = Math.max(canvas.clientHeight, 1);
    if (state.dim === 2) {
      const sx = (2 * camera2.scale) / w, sy = (2 * camera2.scale) / h;
      return new Float32Array([sx, 0, 0, 0, 0, sy, 0, 0, 0, 0, 1, 0, -camera2.cx * sx, -camera2.cy * sy, 0, 1]);
    }
    const { e, f, r, u } = basis();
    const near = camera3.distance / 1000, far = camera3.distance * 100;
    const t = 1 / Math.tan(camera3.fov / 2), aspect = w / h;
    const view = [r[0], u[0], -f[0], 0, r[1], u[1], -f[1], 0, r[2], u[2], -f[2], 0, -dot(r, e), -dot(u, e), dot(f, e), 1];
    const proj = [t / aspect, 0, 0, 0, 0, t, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, (2 * far * near) / (near - far), 0];
    const m = new Float32Array(16);
    for (let i = 0; i < 4; i++) for (let j = 0; j < 4; j++) {
      let s = 0;
      for (let k = 0; k < 4; k++) s += proj[k * 4 + i] * view[j * 4 + k];
      m[j * 4 + i] = s;
    }
    return m;
  }
  function pointerRay(sx, sy) {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    const { e, f, r, u } = basis();
    const t = Math.tan(camera3.fov / 2);
    const px = ((2 * sx) / w - 1) * t * (w / h), py = (1 - (2 * sy) / h) * t;
    return { origin: e, direction: norm([f[0] + px * r[0] + py * u[0], f[1] + px * r[1] + py * u[1], f[2] + px * r[2] + py * u[2]]) };
  }

  let gl = null;
  const G = {};  // programs, buffers, the body texture, the counts
  function compile(type, text) {
    const s = gl.createShader(type);
    gl.shaderSource(s, text); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  }
  function link(vs, fs) {
    const p = gl.createProgram();
    gl.attachShader(p, compile(gl.VERTEX_SHADER, vs)); gl.attachShader(p, compile(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
    return p;
  }
  const PALETTE_SIZE = STILL_COLOUR + 1;
  function setup() {
    gl = canvas.getContext("webgl2", { antialias: false });
    if (!gl) { say("this browser has no WebGL2: the scene cannot be drawn", 3600); return false; }
    G.bodies = link(`#version 300 es
      in vec3 local; in vec3 normal; in float body;
      uniform mat4 vp; uniform highp sampler2D places; uniform vec3 palette[${PALETTE_SIZE}]; uniform vec4 flat_colour;
      out vec3 n; out vec3 c;
      vec3 turn(vec4 q, vec3 v) { return v + 2.0 * cross(q.yzw, cross(q.yzw, v) + q.x * v); }
      void main() {
        int i = int(body + 0.5);
        ivec2 at = ivec2((i % ${ROW}) * 2, i / ${ROW});
        vec4 p = texelFetch(places, at, 0);
        vec4 q = texelFetch(places, at + ivec2(1, 0), 0);
        int k = int(p.w + 0.5);
        if (p.w < -0.5) { gl_Position = vec4(2.0, 2.0, 2.0, 1.0); return; }
        gl_Position = vp * vec4(p.xyz + turn(q, local), 1.0);
        n = turn(q, normal);
        c = flat_colour.a > 0.0 ? flat_colour.rgb : palette[k];
      }`, `#version 300 es
      precision mediump float; in vec3 n; in vec3 c; uniform int lit; out vec4 o;
      void main() {
        if (lit == 0) { o = vec4(c, 1.0); return; }
        vec3 l = normalize(vec3(0.4, 0.25, 0.88));
        o = vec4(c * (0.35 + 0.65 * max(dot(normalize(n), l), 0.0)), 1.0);
      }`);
    G.lines = link(`#version 300 es
      in vec3 position; in vec3 colour; uniform mat4 vp; out vec3 c;
      void main() { gl_Position = vp * vec4(position, 1.0); c = colour; }`, `#version 300 es
      precision mediump float; in vec3 c; out vec4 o; void main() { o = vec4(c, 1.0); }`);
    G.texture = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, G.texture);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    G.fill = { vao: gl.createVertexArray(), buffer: gl.createBuffer(), count: 0 };
    G.edges = { vao: gl.createVertexArray(), buffer: gl.createBuffer(), count: 0 };
    G.debug = { vao: gl.createVertexArray(), buffer: gl.createBuffer() };
    const palette = new Float32Array(3 * PALETTE_SIZE);
    [...PALETTE, ...ISLANDS, STILL].forEach((rgb, k) => { for (let j = 0; j < 3; j++) palette[3 * k + j] = rgb[j] / 255; });
    gl.useProgram(G.bodies);
    gl.uniform3fv(gl.getUniformLocation(G.bodies, "palette"), palette);
    return true;
  }
  function upload(target, data) {
    // vertices of 7 floats: local position (3), local normal (3), body
    gl.bindVertexArray(target.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, target.buffer);
    gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
    for (const [name, size, offset] of [["local", 3, 0], ["normal", 3, 12], ["body", 1, 24]]) {
      const at = gl.getAttribLocation(G.bodies, name);
      if (at < 0) continue;
      gl.enableVertexAttribArray(at);
      gl.vertexAttribPointer(at, size, gl.FLOAT, false, 28, offset);
    }
    target.count = data.length / 7;
  }
  // a unit globe (12 x 6) and a unit disk (24 sides) for the spheres and disks of the
  // event-driven engine, which have no pieces
  const GLOBE = (() => {
    const pts = [[0, 0, 1]], tris = [], around = 12, rings = 6;
    for (let k = 1; k < rings; k++) for (let i = 0; i < around; i++) {
      const th = (Math.PI * k) / rings, ph = (2 * Math.PI * i) / around;
      pts.push([Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)]);
    }
    pts.push([0, 0, -1]);
    const bottom = pts.length - 1;
    for (let i = 0; i < around; i++) {
      const j = (i + 1) % around;
      tris.push([0, 1 + i, 1 + j]);
      for (let k = 0; k < rings - 2; k++) {
        const a = 1 + k * around + i, b = 1 + k * around + j;
        tris.push([a, a + around, b + around], [a, b + around, b]);
      }
      const last = 1 + (rings - 2) * around;
      tris.push([last + i, bottom, last + j]);
    }
    return tris.map((t) => t.map((v) => pts[v]));
  })();
  const DISK = Array.from({ length: 24 }, (_, k) => [Math.cos((2 * Math.PI * k) / 24), Math.sin((2 * Math.PI * k) / 24)]);

  function buildShapes(S, dim) {
    if (!gl && !setup()) return;
    const fill = [], edges = [];
    const v = (out, p, nn, body) => out.push(p[0], p[1], p[2] || 0, nn[0], nn[1], nn[2], body);
    const up = [0, 0, 1];
    const n = S.still.length;
    if (dim === 2) {
      const ring = S.ring, start = S.ring_start, owner = S.ring_body, spoke = S.ring_spoke;
      for (let k = 0; k < owner.length; k++) {
        const i = owner[k], a = start[k], b = start[k + 1];
        const p = (j) => [ring[2 * j], ring[2 * j + 1]];
        for (let j = a + 1; j + 1 < b; j++) { v(fill, p(a), up, i); v(fill, p(j), up, i); v(fill, p(j + 1), up, i); }
        for (let j = a; j < b; j++) { v(edges, p(j), up, i); v(edges, p(j + 1 < b ? j + 1 : a), up, i); }
        if (spoke[k]) {
          let cx = 0, cy = 0;
          for (let j = a; j < b; j++) { cx += ring[2 * j] / (b - a); cy += ring[2 * j + 1] / (b - a); }
          v(edges, [cx, cy], up, i); v(edges, p(a), up, i);
        }
      }
      for (let i = 0; i < n; i++) {
        if (!S.round[i]) continue;
        const r = S.radius[i];
        for (let k = 0; k < DISK.length; k++) {
          const a = DISK[k], b = DISK[(k + 1) % DISK.length];
          v(fill, [0, 0], up, i); v(fill, [r * a[0], r * a[1]], up, i); v(fill, [r * b[0], r * b[1]], up, i);
          v(edges, [r * a[0], r * a[1]], up, i); v(edges, [r * b[0], r * b[1]], up, i);
        }
        v(edges, [0, 0], up, i); v(edges, [r, 0], up, i);
      }
    } else {
      const tri = S.tri, owner = S.tri_body;
      for (let k = 0; k < owner.length; k++) {
        const c = [0, 1, 2].map((j) => [tri[9 * k + 3 * j], tri[9 * k + 3 * j + 1], tri[9 * k + 3 * j + 2]]);
        const nn = norm(cross(sub(c[1], c[0]), sub(c[2], c[0])));
        for (const p of c) v(fill, p, nn, owner[k]);
      }
      for (let i = 0; i < n; i++) {
        if (!S.round[i]) continue;
        const r = S.radius[i];
        for (const t of GLOBE) for (const p of t) v(fill, [r * p[0], r * p[1], r * p[2]], p, i);
      }
    }
    upload(G.fill, new Float32Array(fill));
    upload(G.edges, new Float32Array(edges));
    G.places = new Float32Array(2 * 4 * ROW * Math.max(1, Math.ceil(n / ROW)));
  }

  function speedBins(speed, moving) {
    // the scale follows the fastest bodies (the 95th percentile), decaying slowly
    const sample = [];
    const stride = Math.max(1, Math.floor(speed.length / 512));
    for (let i = 0; i < speed.length; i += stride) if (moving[i]) sample.push(speed[i]);
    sample.sort((a, b) => a - b);
    const p95 = sample.length ? sample[Math.floor(0.95 * (sample.length - 1))] : 0;
    state.speedScale = Math.max(p95, 0.995 * state.speedScale, 1e-6);
    return (v) => Math.min(BINS - 1, Math.floor((v / state.speedScale) * (BINS - 1)));
  }

  function draw() {
    if (!gl && !setup()) return;
    const dpr = (window.devicePixelRatio || 1) * state.options.resolution;
    const w = canvas.clientWidth, h = canvas.clientHeight;
    if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
      canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
    }
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(0.078, 0.086, 0.102, 1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    const S = state.shapes, F = state.frame, H = state.shapeHeader;
    if (!S || !F || !H || !G.places) return;
    const d = state.dim, x = F.x, turn = F.turn, speed = F.speed, st = F.state;
    const n = Math.min(S.still.length, speed.length);
    const moving = new Uint8Array(n);
    for (let i = 0; i < n; i++) moving[i] = !S.still[i] && (st[i] & 1);
    const bin = speedBins(speed, moving);
    const sleeping = state.drawings.has("sleeping") && F.island;
    const P = G.places;
    for (let i = 0; i < n; i++) {
      const o = 8 * i;
      P[o] = x[d * i]; P[o + 1] = x[d * i + 1]; P[o + 2] = d === 3 ? x[3 * i + 2] : 0;
      P[o + 3] = !(st[i] & 1) ? HIDDEN : S.still[i] ? STILL_COLOUR
        : sleeping && !(st[i] & 2) ? BINS + (F.island[i] % ISLANDS.length) : bin(speed[i]);
      if (d === 2) { P[o + 4] = Math.cos(0.5 * turn[i]); P[o + 5] = 0; P[o + 6] = 0; P[o + 7] = Math.sin(0.5 * turn[i]); }
      else { P[o + 4] = turn[4 * i]; P[o + 5] = turn[4 * i + 1]; P[o + 6] = turn[4 * i + 2]; P[o + 7] = turn[4 * i + 3]; }
    }
    const rows = P.length / (8 * ROW);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, G.texture);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, 2 * ROW, rows, 0, gl.RGBA, gl.FLOAT, P);
    const vp = viewProjection();
    gl.useProgram(G.bodies);
    gl.uniformMatrix4fv(gl.getUniformLocation(G.bodies, "vp"), false, vp);
    gl.uniform1i(gl.getUniformLocation(G.bodies, "places"), 0);
    const flat = gl.getUniformLocation(G.bodies, "flat_colour"), lit = gl.getUniformLocation(G.bodies, "lit");
    if (d === 3) gl.enable(gl.DEPTH_TEST); else gl.disable(gl.DEPTH_TEST);
    gl.uniform4f(flat, 0, 0, 0, 0); gl.uniform1i(lit, d === 3 ? 1 : 0);
    gl.bindVertexArray(G.fill.vao);
    gl.drawArrays(gl.TRIANGLES, 0, G.fill.count);
    if (d === 2 && state.options.edges) {
      gl.uniform4f(flat, 0.04, 0.04, 0.055, 1); gl.uniform1i(lit, 0);
      gl.bindVertexArray(G.edges.vao);
      gl.drawArrays(gl.LINES, 0, G.edges.count);
    }
    drawLines(vp, F, H);
  }

  function drawLines(vp, F, H) {
    const L = [], d = state.dim;
    const lift = (p) => (p.length === 3 ? p : [p[0], p[1], 0]);
    const add = (a, b, col) => L.push(...lift(a), ...col, ...lift(b), ...col);
    const box = (lo, hi, col) => {
      const c = (i) => [i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], d === 3 ? (i & 4 ? hi[2] : lo[2]) : 0];
      for (let i = 0; i < (d === 3 ? 8 : 4); i++) for (const bit of d === 3 ? [1, 2, 4] : [1, 2]) if (!(i & bit)) add(c(i), c(i | bit), col);
    };
    if (H.boundary !== "open") box(H.box[0], H.box[1], [0.35, 0.4, 0.4]);
    const on = state.drawings, unit = 0.5 * H.size;
    if (F.contacts) {
      const C = F.contacts, w = 2 * d + 1;  // point, normal, impulse
      let most = 1e-12;
      for (let k = w - 1; k < C.length; k += w) most = Math.max(most, C[k]);
      for (let k = 0; k < C.length; k += w) {
        const p = Array.from(C.subarray(k, k + d)), nn = Array.from(C.subarray(k + d, k + 2 * d)), j = C[k + 2 * d];
        const along = (l) => p.map((c, m) => c + l * nn[m]);
        if (on.has("normals")) add(p, along(unit), [0.4, 0.8, 1]);
        if (on.has("impulses") && j > 0) add(p, along((2 * unit * j) / most), [1, 0.5, 0.25]);
        if (on.has("contacts")) {
          const s = 0.12 * unit;
          for (let m = 0; m < d; m++) { const a = p.slice(), b = p.slice(); a[m] -= s; b[m] += s; add(a, b, [1, 0.85, 0.25]); }
        }
      }
    }
    if (F.joints && on.has("joints")) {
      const J = F.joints;
      for (let k = 0; k < J.length; k += 2 * d) add(Array.from(J.subarray(k, k + d)), Array.from(J.subarray(k + d, k + 2 * d)), [0.9, 0.35, 0.9]);
    }
    if (F.boxes && on.has("boxes")) {
      const B = F.boxes;
      for (let k = 0; k < B.length; k += 2 * d) box(Array.from(B.subarray(k, k + d)), Array.from(B.subarray(k + d, k + 2 * d)), [0.45, 0.75, 1]);
    }
    if (gesture && gesture.kind === "drag" && gesture.target && gesture.anchor) add(gesture.anchor, gesture.target, [1, 1, 1]);
    if (gesture && gesture.kind === "drag" && gesture.target && d === 2) {
      const s = 6 / camera2.scale, t = gesture.target;
      add([t[0] - s, t[1]], [t[0] + s, t[1]], [1, 1, 1]); add([t[0], t[1] - s], [t[0], t[1] + s], [1, 1, 1]);
    }
    if (gesture && gesture.kind === "press" && gesture.body !== undefined && gesture.body < 0) add(gesture.start, gesture.now, [1, 0.85, 0.25]);
    if (!L.length) return;
    gl.useProgram(G.lines);
    gl.bindVertexArray(G.debug.vao);
    gl.bindBuffer(gl.ARRAY_BUFFER, G.debug.buffer);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(L), gl.DYNAMIC_DRAW);
    for (const [name, offset] of [["position", 0], ["colour", 12]]) {
      const at = gl.getAttribLocation(G.lines, name);
      gl.enableVertexAttribArray(at);
      gl.vertexAttribPointer(at, 3, gl.FLOAT, false, 24, offset);
    }
    gl.uniformMatrix4fv(gl.getUniformLocation(G.lines, "vp"), false, vp);
    gl.disable(gl.DEPTH_TEST);
    gl.drawArrays(gl.LINES, 0, L.length / 6);
  }

  // -- the panel ---------------------------------------------------------------------------
  function fmt(v, digits = 4) {
    if (v === undefined || v === null) return "";
    if (typeof v !== "number") return String(v);
    if (v !== 0 && (Math.abs(v) >= 1e5 || Math.abs(v) < 1e-3)) return v.toExponential(2);
    return v.toPrecision(digits).replace(/\.?0+$/, "");
  }
  function panel(H) {
    const e = H.energy;
    const total = e.kinetic + e.potential;
    // the ledger closes as E0 + work = E + lost - given: what it misses
    const miss = total + e.lost - e.given - e.start - e.work;
    if (state.replay) {
      $("stats").innerHTML = [
        ["time [s]", fmt(H.time)], ["bodies", H.bodies],
        ["kinetic [J]", fmt(e.kinetic)], ["potential [J]", fmt(e.potential)], ["lost in impacts [J]", fmt(e.lost)],
        ["given by solver [J]", fmt(e.given)], ["work done [J]", fmt(e.work)], ["ledger misses [J]", fmt(miss, 3)],
      ].map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join("");
      return;
    }
    const rows = [
      ["time [s]", fmt(H.time)], ["steps", H.steps],
      ["ms a step", fmt(H.step_ms, 3)], ["frames a second", fmt(state.fps, 3)],
      ["bodies", H.bodies], ["contacts", H.contacts], ["awake bodies", H.awake], ["awake islands", H.islands],
      ["kinetic [J]", fmt(e.kinetic)], ["potential [J]", fmt(e.potential)],
      ["lost in impacts [J]", fmt(e.lost)], ["given by solver [J]", fmt(e.given)], ["work done [J]", fmt(e.work)],
      ["ledger misses [J]", fmt(miss, 3)], ["behind real time [s]", fmt(H.behind, 3)],
    ];
    // the step's stages under its time, in their order
    if (H.stages) Object.entries(H.stages).reverse().forEach(([name, ms]) => rows.splice(3, 0, ["\u2003" + name, fmt(ms, 3)]));
    $("stats").innerHTML = rows.map(([k, v]) => `<tr><td>${k}</td><td>${v}</td></tr>`).join("");
    $("pause").textContent = H.paused ? "play" : "pause";
    $("slow").value = String(H.slow);
  }
  function plotEnergy() {
    const c = $("energy"), ctx = c.getContext("2d"), E = state.energy;
    ctx.clearRect(0, 0, c.width, c.height);
    if (E.length < 2) return;
    let lo = Infinity, hi = -Infinity;
    for (const p of E) for (const v of [p[1], p[2], p[3]]) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (hi - lo < 1e-12) { hi += 1; lo -= 1; }
    const t0 = E[0][0], t1 = E[E.length - 1][0] || t0 + 1;
    const X = (t) => 4 + ((t - t0) / Math.max(t1 - t0, 1e-12)) * (c.width - 8);
    const Y = (v) => c.height - 14 - ((v - lo) / (hi - lo)) * (c.height - 24);
    const series = [[1, "#eee", "E"], [2, "#5c9", "kinetic"], [3, "#f84", "E + lost"]];
    series.forEach(([k, colour, name], j) => {
      ctx.strokeStyle = colour; ctx.beginPath();
      E.forEach((p, i) => (i ? ctx.lineTo(X(p[0]), Y(p[k])) : ctx.moveTo(X(p[0]), Y(p[k]))));
      ctx.stroke();
      ctx.fillStyle = colour; ctx.fillText(name, 6 + 60 * j, c.height - 2);
    });
    ctx.fillStyle = "#889"; ctx.fillText(fmt(hi, 3) + " J", c.width - 70, 10);
  }
  function plotHistogram(F) {
    const c = $("histogram"), S = state.shapes;
    const gas = state.shapeHeader && state.shapeHeader.engine === "edmd";
    c.classList.toggle("hidden", !gas);
    if (!gas || !S) return;
    const ctx = c.getContext("2d");
    ctx.clearRect(0, 0, c.width, c.height);
    const d = state.dim, v = F.speed, m = S.mass, st = F.state;
    let sum = 0, count = 0, twoK = 0;
    for (let i = 0; i < v.length; i++) if (m[i] > 0 && (st[i] & 1)) { twoK += m[i] * v[i] * v[i]; sum += v[i]; count++; }
    if (!count) return;
    const kT = twoK / (d * count);  // equipartition: kT = <m v^2> / d
    const masses = new Map();
    for (let i = 0; i < v.length; i++) if (m[i] > 0 && (st[i] & 1)) masses.set(m[i], (masses.get(m[i]) || 0) + 1);
    const top = 3 * Math.sqrt((d * kT) / Math.min(...masses.keys()));
    const bins = 30, width = top / bins, hist = new Array(bins).fill(0);
    for (let i = 0; i < v.length; i++) if (m[i] > 0 && (st[i] & 1)) hist[Math.min(bins - 1, Math.floor(v[i] / width))]++;
    // Maxwell-Boltzmann: 2D (m v / kT) exp(-m v^2 / 2kT); 3D sqrt(2/pi) (m/kT)^(3/2) v^2 exp(...),
    // a mixture over the masses
    const mb = (u) => {
      let f = 0;
      for (const [mass, k] of masses) {
        const a = mass / kT, g = Math.exp(-0.5 * a * u * u);
        f += (k / count) * (d === 2 ? a * u * g : Math.sqrt(2 / Math.PI) * Math.pow(a, 1.5) * u * u * g);
      }
      return f;
    };
    let most = 0;
    for (let b = 0; b < bins; b++) most = Math.max(most, hist[b] / (count * width), mb((b + 0.5) * width));
    const H = c.height - 14, W = c.width / bins;
    ctx.fillStyle = "#3b6";
    for (let b = 0; b < bins; b++) { const y = (hist[b] / (count * width) / most) * (H - 6); ctx.fillRect(b * W + 1, H - y, W - 2, y); }
    ctx.strokeStyle = "#fd4"; ctx.beginPath();
    for (let s = 0; s <= 120; s++) { const u = (s / 120) * top, y = H - (mb(u) / most) * (H - 6); s ? ctx.lineTo((u / top) * c.width, y) : ctx.moveTo(0, y); }
    ctx.stroke();
    ctx.fillStyle = "#aab"; ctx.fillText(`speeds (bars) and Maxwell-Boltzmann at kT = ${fmt(kT, 3)} J`, 4, c.height - 2);
  }

  function say(text, seconds = 4) {
    state.status = text; state.statusUntil = performance.now() + 1000 * seconds;
    $("status").textContent = text;
  }

  // -- what arrives ------------------------------------------------------------------------
  function takeShapes(header, arrays) {
    const first = !state.shapeHeader || state.shapeHeader.scene !== header.scene || state.dim !== header.dim;
    state.shapes = arrays; state.shapeHeader = header; state.dim = header.dim;
    buildShapes(arrays, header.dim);
    document.body.classList.toggle("dim3", header.dim === 3);
    if (first) {
      if (header.dim === 2) fit2d(header.box); else fit3d(header.box, header.size);
      state.fitPending = state.replay === null || state.replay === undefined || true;
      state.energy = []; state.speedScale = 0;
      const pick = $("scene");
      pick.innerHTML = "";
      for (const name of header.catalog) { const o = document.createElement("option"); o.value = o.textContent = name; pick.appendChild(o); }
      pick.value = header.scene;
      $("title").textContent = header.title + (header.description ? ": " + header.description : "");
      for (const [name, value] of Object.entries(header.settings)) {
        const input = $(name);
        if (!input) continue;
        input.value = value; $(name + "-out").textContent = fmt(value, 3);
        input.disabled = state.replay !== null || (name === "substeps" && header.engine === "edmd") || (name === "friction" && header.engine === "edmd");
      }
      $("hint").textContent = header.engine === "replay" ? `${header.title}: a replay, ${header.dim}D`
        : `${header.title}: ${header.engine} engine, ${header.dim}D`;
    }
  }
  function fitToBodies(F) {
    // the first frame of a scene: the view holds its box and its moving bodies
    const H = state.shapeHeader, S = state.shapes, d = H.dim;
    const lo = H.box[0].slice(), hi = H.box[1].slice();
    for (let i = 0; i < F.speed.length; i++) {
      if (S.still[i] || !(F.state[i] & 1)) continue;
      for (let k = 0; k < d; k++) {
        lo[k] = Math.min(lo[k], F.x[d * i + k] - S.radius[i]);
        hi[k] = Math.max(hi[k], F.x[d * i + k] + S.radius[i]);
      }
    }
    if (!(hi[0] > lo[0])) return;
    const box = { ...H, box: [lo.slice(0, d), hi.slice(0, d)] };
    if (d === 2) fit2d(box.box); else fit3d(box.box, H.size);
  }
  function takeFrame(header, arrays) {
    if (state.fitPending) { state.fitPending = false; state.frame = arrays; fitToBodies(arrays); }
    state.frame = arrays; state.header = header; state.framesSeen++; state.fpsCount++;
    state.held = header.held;
    const now = performance.now();
    if (now - state.fpsSince > 1000) { state.fps = (1000 * state.fpsCount) / (now - state.fpsSince); state.fpsCount = 0; state.fpsSince = now; }
    const e = header.energy, E = state.energy;
    if (!E.length || header.time !== E[E.length - 1][0]) {
      E.push([header.time, e.kinetic + e.potential, e.kinetic, e.kinetic + e.potential + e.lost - e.given]);
      if (E.length > 600) E.shift();
    }
    if (state.framesSeen % 4 === 0 || header.paused) { panel(header); plotEnergy(); plotHistogram(arrays); }
  }
  function take(buffer) {
    const [header, arrays] = unpack(buffer);
    if (header.type === "shapes") takeShapes(header, arrays);
    else if (header.type === "frame") {
      if (state.shapeHeader && header.version !== state.shapeHeader.version) return;  // shapes to come
      takeFrame(header, arrays);
    }
  }

  // -- the connection ----------------------------------------------------------------------
  let retry = 250;
  function connect() {
    const url = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws";
    const socket = new WebSocket(url);
    socket.binaryType = "arraybuffer";
    socket.onopen = () => { retry = 250; state.socket = socket; say("connected", 1.5); resendDrawings(); };
    socket.onmessage = (event) => {
      if (typeof event.data === "string") {
        const reply = JSON.parse(event.data);
        if (reply.op === "refused") say("refused: " + reply.why);
        else if (reply.op === "grabbed" && gesture) { gesture.body = reply.body; gesture.anchor = reply.point; }
        else if (reply.op === "shot") say(`ball ${reply.body} shot`, 1.5);
        return;
      }
      take(event.data);
      // drawn: the server may send the next frame (it keeps at most two in flight)
      if (state.socket) state.socket.send('{"op":"ack"}');
    };
    socket.onclose = () => {
      state.socket = null;
      say("the server went away: connecting again...", 60);
      setTimeout(connect, retry);
      retry = Math.min(2 * retry, 4000);
    };
    socket.onerror = () => {};
  }
  function send(command) {
    if (state.socket && state.socket.readyState === WebSocket.OPEN) state.socket.send(JSON.stringify(command));
  }
  function resendDrawings() {
    for (const name of ["contacts", "normals", "impulses", "joints", "sleeping", "boxes"]) send({ op: "draw", name, on: state.drawings.has(name) });
  }

  // -- hands ---------------------------------------------------------------------------------
  let gesture = null;  // {kind: "drag"|"shoot"|"orbit"|"pan", ...}
  const round6 = (p) => p.map((v) => Math.round(v * 1e6) / 1e6);
  function shootSpeed(length) {
    const H = state.shapeHeader;
    return Math.min(5 * length, H.top_speed * 0.999);
  }
  function onDown(event) {
    state.lastMoved = 0;
    if (state.replay || !state.shapeHeader) { gesture = { kind: state.dim === 3 && event.button !== 2 ? "orbit" : "pan", x: event.clientX, y: event.clientY }; return; }
    const rect = event.target.getBoundingClientRect();
    const sx = event.clientX - rect.left, sy = event.clientY - rect.top;
    event.target.setPointerCapture(event.pointerId);
    if (event.button === 2 || event.button === 1) { gesture = { kind: "pan", x: event.clientX, y: event.clientY }; return; }
    if (state.dim === 2) {
      const p = toWorld(sx, sy);
      gesture = { kind: "press", start: p, now: p, screen: [sx, sy] };
      send({ op: "grab", point: round6(p) });
    } else if (event.shiftKey) {
      gesture = { kind: "shoot3", x: sx, y: sy, now: [sx, sy] };
    } else {
      const ray = pointerRay(sx, sy);
      gesture = { kind: "press3", x: event.clientX, y: event.clientY, ray };
      send({ op: "grab", point: round6(ray.origin), direction: round6(ray.direction) });
    }
  }
  function onMove(event) {
    if (!gesture) return;
    if (gesture.x !== undefined) state.lastMoved += Math.abs(event.clientX - gesture.x) + Math.abs(event.clientY - gesture.y);
    const rect = event.target.getBoundingClientRect();
    const sx = event.clientX - rect.left, sy = event.clientY - rect.top;
    if (gesture.kind === "pan") {
      const dx = event.clientX - gesture.x, dy = event.clientY - gesture.y;
      gesture.x = event.clientX; gesture.y = event.clientY;
      if (state.dim === 2) { camera2.cx -= dx / camera2.scale; camera2.cy += dy / camera2.scale; }
      else { const { r, u } = basis(), k = camera3.distance / 800; for (let i = 0; i < 3; i++) camera3.target[i] += k * (-dx * r[i] + dy * u[i]); }
      return;
    }
    if (gesture.kind === "orbit") {
      camera3.yaw -= 0.006 * (event.clientX - gesture.x);
      camera3.pitch = Math.max(-1.5, Math.min(1.5, camera3.pitch + 0.006 * (event.clientY - gesture.y)));
      gesture.x = event.clientX; gesture.y = event.clientY;
      return;
    }
    if (state.dim === 2 && (gesture.kind === "press" || gesture.kind === "drag")) {
      gesture.now = toWorld(sx, sy);
      if (gesture.body !== undefined && gesture.body >= 0) {
        gesture.kind = "drag"; gesture.target = gesture.now;
        send({ op: "drag", target: round6(gesture.now) });
      }
      return;
    }
    if (gesture.kind === "shoot3") { gesture.now = [sx, sy]; return; }
    if (gesture.kind === "press3") {
      if (gesture.body !== undefined && gesture.body >= 0 && gesture.anchor) {
        // the drag plane: through the grabbed point, facing the camera
        const { f } = basis(), ray = pointerRay(sx, sy);
        const t = dot(sub(gesture.anchor, ray.origin), f) / dot(ray.direction, f);
        gesture.target = [0, 1, 2].map((k) => ray.origin[k] + t * ray.direction[k]);
        gesture.kind = "drag";
        send({ op: "drag", target: round6(gesture.target) });
      } else if (Math.hypot(event.clientX - gesture.x, event.clientY - gesture.y) > 3) {
        gesture = { kind: "orbit", x: event.clientX, y: event.clientY };
      }
      return;
    }
    if (gesture.kind === "drag" && state.dim === 3) {
      const { f } = basis(), ray = pointerRay(sx, sy);
      const t = dot(sub(gesture.anchor, ray.origin), f) / dot(ray.direction, f);
      gesture.target = [0, 1, 2].map((k) => ray.origin[k] + t * ray.direction[k]);
      send({ op: "drag", target: round6(gesture.target) });
    }
  }
  function onUp(event) {
    if (!gesture) return;
    const g = gesture;
    gesture = null;
    if (g.kind === "drag" || ((g.kind === "press" || g.kind === "press3") && g.body !== undefined && g.body >= 0)) { send({ op: "release" }); return; }
    if (g.kind === "press") {
      // a press in open space: a ball from where it started toward where it ended
      const d = [g.now[0] - g.start[0], g.now[1] - g.start[1]], l = Math.hypot(d[0], d[1]);
      const speed = shootSpeed(l);
      const v = l > 0 ? [(speed * d[0]) / l, (speed * d[1]) / l] : [0, 0];
      send({ op: "shoot", point: round6(g.start), velocity: round6(v) });
    } else if (g.kind === "shoot3") {
      const ray = pointerRay(g.x, g.y), H = state.shapeHeader;
      const length = Math.hypot(g.now[0] - g.x, g.now[1] - g.y) / 100 * H.size;
      const speed = Math.max(shootSpeed(length), 10 * H.size);
      const start = [0, 1, 2].map((k) => ray.origin[k] + 2 * H.size * ray.direction[k]);
      send({ op: "shoot", point: round6(start), velocity: round6(ray.direction.map((c) => c * Math.min(speed, 0.999 * H.top_speed))) });
    } else if (g.kind === "press3") send({ op: "release" });
  }
  function onWheel(event) {
    event.preventDefault();
    const k = Math.exp(-0.0015 * event.deltaY);
    if (state.dim === 2) {
      const rect = canvas.getBoundingClientRect();
      const before = toWorld(event.clientX - rect.left, event.clientY - rect.top);
      camera2.scale *= k;
      const after = toWorld(event.clientX - rect.left, event.clientY - rect.top);
      camera2.cx += before[0] - after[0]; camera2.cy += before[1] - after[1];
    } else camera3.distance /= k;
  }
  canvas.addEventListener("pointerdown", onDown);
  canvas.addEventListener("pointermove", onMove);
  canvas.addEventListener("pointerup", onUp);
  canvas.addEventListener("wheel", onWheel, { passive: false });
  canvas.addEventListener("contextmenu", (e) => e.preventDefault());

  // -- controls ----------------------------------------------------------------------------
  $("pause").onclick = () => { if (state.replay) state.replay.playing = !state.replay.playing; else send({ op: state.header && state.header.paused ? "play" : "pause" }); };
  $("step").onclick = () => { if (state.replay) state.replay.stepBy(1); else send({ op: "step" }); };
  $("reset").onclick = () => { if (state.replay) state.replay.seek(0); else send({ op: "reset" }); };
  $("slow").onchange = (e) => { if (state.replay) state.replay.slow = +e.target.value; else send({ op: "slow", factor: +e.target.value }); };
  $("scene").onchange = (e) => send({ op: "scene", name: e.target.value });
  for (const name of ["gravity", "restitution", "friction", "substeps"]) {
    const input = $(name);
    input.oninput = () => { $(name + "-out").textContent = fmt(+input.value, 3); };
    input.onchange = () => send({ op: "set", name, value: +input.value });
  }
  for (const box of document.querySelectorAll("[data-draw]")) {
    box.onchange = () => {
      const name = box.dataset.draw;
      if (box.checked) state.drawings.add(name); else state.drawings.delete(name);
      send({ op: "draw", name, on: box.checked });
    };
  }
  window.addEventListener("keydown", (e) => {
    if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") return;
    if (e.key === " ") { e.preventDefault(); $("pause").onclick(); }
    else if (e.key === "s") $("step").onclick();
    else if (e.key === "r") $("reset").onclick();
  });

  // dynamic resolution: where the browser draws slowly (no GPU: software WebGL), the view is
  // drawn with fewer pixels (down to half on each side) until it keeps up, and back up after
  let lastDraw = 0, slowSince = 0, fastSince = 0;
  function adapt(now) {
    const gap = now - lastDraw;
    const o = state.options;
    if (!o.adaptive) return;
    if (gap > 30) { fastSince = 0; slowSince = slowSince || now; } else if (gap < 20) { slowSince = 0; fastSince = fastSince || now; }
    if (slowSince && now - slowSince > 1000 && o.resolution > 0.5) { o.resolution = Math.max(0.5, 0.8 * o.resolution); slowSince = 0; }
    if (fastSince && now - fastSince > 3000 && o.resolution < 1) { o.resolution = Math.min(1, o.resolution / 0.8); fastSince = 0; }
  }

  // the view is drawn again only when something in it changed: a new frame, the camera, the
  // canvas, a gesture, a switch (a browser drawing without a GPU has no time to waste)
  let drawnKey = "", drewLast = false;
  function viewKey() {
    const g = gesture ? JSON.stringify([gesture.target, gesture.now, gesture.kind]) : "";
    return [state.framesSeen, camera2.cx, camera2.cy, camera2.scale, camera3.yaw, camera3.pitch,
      camera3.distance, ...camera3.target, canvas.clientWidth, canvas.clientHeight,
      state.options.resolution, state.options.edges, [...state.drawings].join(), g].join("|");
  }
  function render() {
    if (state.replay) state.replay.tick();
    const t0 = performance.now();
    if (drewLast) adapt(t0);  // (how long the last drawing took to reach the screen)
    const key = viewKey();
    drewLast = key !== drawnKey;
    if (drewLast) {
      lastDraw = t0;
      draw();
      drawnKey = key;
      state.drawMs = 0.9 * (state.drawMs || 0) + 0.1 * (performance.now() - t0);
    }
    if (state.status && performance.now() > state.statusUntil) { state.status = ""; $("status").textContent = ""; }
    requestAnimationFrame(render);
  }

  // -- replays: the same drawing, frames from the file instead of a server --------------------
  function decode(text) {
    const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
    return bytes.buffer;
  }
  function startReplay(data) {
    const frames = data.frames.map(decode);
    const replay = {
      index: 0, playing: true, slow: 1, clock: performance.now(), frames,
      times: frames.map((b) => unpack(b)[0].time),
      seek(i) { this.index = Math.max(0, Math.min(frames.length - 1, i)); this.clock = performance.now(); show(); },
      stepBy(k) { this.playing = false; this.seek(this.index + k); },
      tick() {
        if (!this.playing || frames.length < 2) return;
        const now = performance.now(), dt = ((now - this.clock) / 1000) * this.slow;
        const t0 = this.times[this.index];
        let i = this.index;
        while (i + 1 < frames.length && this.times[i + 1] - t0 <= dt) i++;
        if (i !== this.index) { this.index = i; this.clock = now; show(); }
        else if (i === frames.length - 1) { this.index = 0; this.clock = now; show(); }
      },
    };
    state.replay = replay;
    const scrub = $("scrub");
    $("timeline").classList.remove("hidden");
    scrub.max = String(frames.length - 1);
    scrub.oninput = () => { replay.playing = false; replay.seek(+scrub.value); };
    $("scene").disabled = true;
    $("sliders").classList.add("hidden");
    $("drawings").classList.add("hidden");
    $("help").textContent = "scrub the timeline; click a body for its speed and energy; wheel zooms; "
      + "drag pans (3D: turns the view, right-drag pans); space plays and pauses, s steps";
    function show() {
      take(frames[replay.index]);
      scrub.value = String(replay.index);
      $("frameno").textContent = `frame ${replay.index + 1} of ${frames.length}${data.note || ""}, t = ${fmt(replay.times[replay.index])} s`;
      $("pause").textContent = replay.playing ? "pause" : "play";
    }
    take(decode(data.shapes));
    show();
  }

  // a body picked in a replay: its speed and energy in the status line (2D: the body whose
  // bounding circle holds the point; 3D: the first whose bounding sphere the ray meets)
  function pickInReplay(event) {
    if (!state.replay || !state.frame || state.lastMoved > 3) return;
    const rect = canvas.getBoundingClientRect(), sx = event.clientX - rect.left, sy = event.clientY - rect.top;
    const F = state.frame, S = state.shapes, d = state.dim;
    let best = -1, depth = Infinity;
    if (d === 2) {
      const p = toWorld(sx, sy);
      for (let i = 0; i < F.speed.length; i++) {
        const gap = Math.hypot(F.x[2 * i] - p[0], F.x[2 * i + 1] - p[1]) - S.radius[i];
        if (gap <= 0 && gap < depth && !S.still[i]) { depth = gap; best = i; }
      }
    } else {
      const ray = pointerRay(sx, sy);
      for (let i = 0; i < F.speed.length; i++) {
        if (S.still[i]) continue;
        const rel = sub([F.x[3 * i], F.x[3 * i + 1], F.x[3 * i + 2]], ray.origin);
        const along = dot(rel, ray.direction), miss = dot(rel, rel) - along * along, r = S.radius[i];
        if (along > 0 && miss <= r * r && along - Math.sqrt(r * r - miss) < depth) { depth = along - Math.sqrt(r * r - miss); best = i; }
      }
    }
    if (best < 0) return;
    const m = S.mass[best], v = F.speed[best];
    state.picked = best;
    say(`body ${best}: speed ${fmt(v)} m/s, mass ${fmt(m)} kg, kinetic energy of its centre ${fmt(0.5 * m * v * v)} J`, 12);
  }
  canvas.addEventListener("click", pickInReplay);

  window.carom = {
    toScreen: (p) => { const r = canvas.getBoundingClientRect(); const s = toScreen(p); return [s[0] + r.left, s[1] + r.top]; },
    state,
    unpack,
  };

  if (window.CAROM_REPLAY) startReplay(window.CAROM_REPLAY);
  else connect();
  requestAnimationFrame(render);
})();
