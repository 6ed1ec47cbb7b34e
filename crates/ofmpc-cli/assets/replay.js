// ofmpc report: 3-D replay of the runs with raw WebGL (no library, no network).
// The robot is drawn from its URDF's visual meshes where the data has them (robot.meshes: per
// body, 16-bit positions in the body's frame and triangles, crates/ofmpc-cli/src/output/mesh/),
// flat-shaded with per-face normals computed here, at the body's pose T_body from forward
// kinematics; bodies without a mesh (robot.capsules) as capsules between their joint frames,
// computed here by forward kinematics
// from the placements and axes in the data (crates/ofmpc-cli/src/output/replay.rs); the
// reference flange path in grey; the flange trace coloured by the Cartesian tracking error
// (log scale). Play/pause, a time slider, one run at a time (the menu). Drag: orbit; wheel: zoom.
// The scene's state is exposed for tests: window.ofmpcReplay and the data-* attributes of
// #replay-state (data-k: sample index of the record, data-t, data-q: joint angles drawn,
// data-flange: flange position from the forward kinematics). With the URL hash #replay-check
// (or a hash containing it) the page moves the slider itself and writes what it drew into #replay's data-check.
(function () {
  'use strict';
  var root = document.getElementById('replay');
  var dataEl = document.getElementById('replay-data');
  if (!root || !dataEl) { return; }
  // Errors (a script exception, a shader that does not compile, a GL error after a check
  // frame) are listed in #replay's data-errors for the tests.
  var errors = [];
  function fail(what) { errors.push(String(what)); root.setAttribute('data-errors', JSON.stringify(errors)); }
  window.addEventListener('error', function (e) { fail(e.message); });
  var D = JSON.parse(dataEl.textContent);
  var GAP = 65535;
  function decode(q) {
    var bin = atob(q.d), n = bin.length >> 1, out = new Float64Array(n);
    for (var i = 0; i < n; i++) {
      var k = bin.charCodeAt(2 * i) | (bin.charCodeAt(2 * i + 1) << 8);
      out[i] = k === GAP ? NaN : q.lo + (q.hi - q.lo) * k / (GAP - 1);
    }
    return out;
  }
  // ---- small linear algebra: 4x4 column-major matrices (WebGL order) ----
  function ident() { return [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]; }
  function mul(a, b) {
    var o = new Array(16);
    for (var c = 0; c < 4; c++) { for (var r = 0; r < 4; r++) {
      var s = 0; for (var k = 0; k < 4; k++) { s += a[k * 4 + r] * b[c * 4 + k]; } o[c * 4 + r] = s;
    } }
    return o;
  }
  function fromRp(R, p) { // R row-major 3x3
    return [R[0], R[3], R[6], 0, R[1], R[4], R[7], 0, R[2], R[5], R[8], 0, p[0], p[1], p[2], 1];
  }
  function axisAngle(a, q) { // Rodrigues
    var c = Math.cos(q), s = Math.sin(q), t = 1 - c, x = a[0], y = a[1], z = a[2];
    return fromRp([t * x * x + c, t * x * y - s * z, t * x * z + s * y,
                   t * x * y + s * z, t * y * y + c, t * y * z - s * x,
                   t * x * z - s * y, t * y * z + s * x, t * z * z + c], [0, 0, 0]);
  }
  function origin(m) { return [m[12], m[13], m[14]]; }
  var J = D.robot.joints;
  var placements = J.map(function (j) { return fromRp(j.t.r, j.t.p); });
  var flangeT = fromRp(D.robot.flange.r, D.robot.flange.p);
  // Joint frame origins (base, joint 1..n) and the flange, for angles q; pts.mats: the body
  // frames (0: base, i: after joint i's motion), 4x4 column-major.
  function fk(q) {
    var T = ident(), pts = [[0, 0, 0]], mats = [T];
    for (var i = 0; i < J.length; i++) {
      T = mul(T, placements[i]);
      var m = J[i].prismatic
        ? fromRp([1, 0, 0, 0, 1, 0, 0, 0, 1], [J[i].axis[0] * q[i], J[i].axis[1] * q[i], J[i].axis[2] * q[i]])
        : axisAngle(J[i].axis, q[i]);
      T = mul(T, m);
      pts.push(origin(T));
      mats.push(T);
    }
    pts.push(origin(mul(T, flangeT)));
    pts.mats = mats;
    return pts;
  }
  // ---- runs ----
  var runs = D.runs.map(function (r) {
    var q = r.q.map(decode), t = decode(r.t), e = decode(r.err), n = t.length;
    var trace = new Float32Array(n * 3), col = new Float32Array(n * 3);
    var elo = -6, ehi = 3; // log10 mm: 1 nm … 1 m
    for (var k = 0; k < n; k++) {
      var qa = q.map(function (c) { return c[k]; });
      var f = fk(qa)[J.length + 1];
      trace[3 * k] = f[0]; trace[3 * k + 1] = f[1]; trace[3 * k + 2] = f[2];
      var u = Math.max(0, Math.min(1, (e[k] - elo) / (ehi - elo)));
      // dark blue (small) → green → orange → red (large)
      col[3 * k] = Math.min(1, 2 * u); col[3 * k + 1] = u < 0.5 ? 0.3 + u : 1.3 - u; col[3 * k + 2] = Math.max(0, 0.8 - 1.6 * u);
    }
    // The predicted horizons: per recorded sample k, the flange at k (forward kinematics of
    // the recorded joints there) and at the N predicted joint positions: a polyline of N + 1
    // points in one buffer.
    var hz = null;
    if (r.horizon) {
      var hk = r.horizon.k, hn = r.horizon.n, hq = r.horizon.q.map(decode), nh = hk.length;
      var pts = new Float32Array(nh * (hn + 1) * 3), hc = new Float32Array(nh * (hn + 1) * 3);
      for (var h = 0; h < nh; h++) {
        var fr = Math.min(n - 1, Math.round(hk[h] / r.stride)), o = h * (hn + 1) * 3;
        pts[o] = trace[3 * fr]; pts[o + 1] = trace[3 * fr + 1]; pts[o + 2] = trace[3 * fr + 2];
        for (var j = 0; j < hn; j++) {
          var qj = hq.map(function (c) { return c[h * hn + j]; });
          var p = fk(qj)[J.length + 1], oj = o + 3 * (j + 1);
          pts[oj] = p[0]; pts[oj + 1] = p[1]; pts[oj + 2] = p[2];
        }
      }
      for (var c = 0; c < hc.length; c += 3) { hc[c] = 0.85; hc[c + 1] = 0.1; hc[c + 2] = 0.75; }
      hz = { k: hk, n: hn, count: nh, pts: pts, col: hc };
    }
    return { name: r.name, status: r.status, q: q, t: t, e: e, n: n, stride: r.stride, len: r.len, trace: trace, col: col, hz: hz };
  });
  // The latest recorded horizon at or before sample k (-1: none).
  function horizonAt(r, k) {
    if (!r.hz) { return -1; }
    var lo = 0, hi = r.hz.count - 1, best = -1;
    while (lo <= hi) { var mid = (lo + hi) >> 1; if (r.hz.k[mid] <= k) { best = mid; lo = mid + 1; } else { hi = mid - 1; } }
    return best;
  }
  var ref = D.reference ? D.reference.map(decode) : null;
  // ---- WebGL ----
  var canvas = document.getElementById('replay-canvas');
  var gl = canvas.getContext('webgl', { antialias: false, preserveDrawingBuffer: false });
  var stateEl = document.getElementById('replay-state');
  if (!gl) { stateEl.textContent = 'WebGL is not available in this browser: no 3-D replay.'; root.setAttribute('data-ready', 'no-webgl'); return; }
  function shader(type, src) {
    var s = gl.createShader(type); gl.shaderSource(s, src); gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) { fail('shader: ' + gl.getShaderInfoLog(s)); }
    return s;
  }
  function program(vs, fs) {
    var p = gl.createProgram();
    gl.attachShader(p, shader(gl.VERTEX_SHADER, vs)); gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fs));
    gl.linkProgram(p); return p;
  }
  var lit = program(
    'attribute vec3 p; attribute vec3 n; uniform mat4 M, VP; varying vec3 vn;' +
    'void main(){ vn = mat3(M) * n; gl_Position = VP * M * vec4(p, 1.0); }',
    'precision mediump float; varying vec3 vn; uniform vec3 c;' +
    'void main(){ vec3 nn = normalize(vn); if (!gl_FrontFacing) { nn = -nn; } float d = max(dot(nn, normalize(vec3(0.4, -0.5, 0.8))), 0.0); gl_FragColor = vec4(c * (0.35 + 0.65 * d), 1.0); }');
  var flat = program(
    'attribute vec3 p; attribute vec3 c; uniform mat4 VP; varying vec3 vc; uniform float ps;' +
    'void main(){ vc = c; gl_PointSize = ps; gl_Position = VP * vec4(p, 1.0); }',
    'precision mediump float; varying vec3 vc; void main(){ gl_FragColor = vec4(vc, 1.0); }');
  function buffer(data) { var b = gl.createBuffer(); gl.bindBuffer(gl.ARRAY_BUFFER, b); gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW); return b; }
  // Unit cylinder along z (0..1, radius 1) and unit sphere.
  function cylinder(seg) {
    var p = [], n = [];
    for (var i = 0; i < seg; i++) {
      var a0 = 2 * Math.PI * i / seg, a1 = 2 * Math.PI * (i + 1) / seg;
      var c0 = Math.cos(a0), s0 = Math.sin(a0), c1 = Math.cos(a1), s1 = Math.sin(a1);
      p.push(c0, s0, 0, c1, s1, 0, c1, s1, 1, c0, s0, 0, c1, s1, 1, c0, s0, 1);
      n.push(c0, s0, 0, c1, s1, 0, c1, s1, 0, c0, s0, 0, c1, s1, 0, c0, s0, 0);
    }
    return { p: buffer(new Float32Array(p)), n: buffer(new Float32Array(n)), count: p.length / 3 };
  }
  function sphere(seg) {
    var p = [];
    function v(i, j) { var th = Math.PI * i / seg, ph = 2 * Math.PI * j / seg; return [Math.sin(th) * Math.cos(ph), Math.sin(th) * Math.sin(ph), Math.cos(th)]; }
    for (var i = 0; i < seg; i++) { for (var j = 0; j < seg; j++) {
      var a = v(i, j), b = v(i + 1, j), c = v(i + 1, j + 1), d = v(i, j + 1);
      p.push.apply(p, a.concat(b, c, a, c, d));
    } }
    var f = new Float32Array(p);
    return { p: buffer(f), n: buffer(f), count: p.length / 3 };
  }
  var cyl = cylinder(18), sph = sphere(10);
  // The robot's meshes: per body, triangles with per-face normals (flat shading) in the body's
  // frame; decoded from 16-bit positions in the mesh's box and 16-bit triangle corners.
  function bytes16(b64) {
    var bin = atob(b64), out = new Uint16Array(bin.length >> 1);
    for (var i = 0; i < out.length; i++) { out[i] = bin.charCodeAt(2 * i) | (bin.charCodeAt(2 * i + 1) << 8); }
    return out;
  }
  var meshes = (D.robot.meshes || []).map(function (m) {
    var v = bytes16(m.v), idx = bytes16(m.i), nt = idx.length / 3;
    var pos = new Float32Array(nt * 9), nor = new Float32Array(nt * 9);
    function P(k, c) { return m.lo[c] + (m.hi[c] - m.lo[c]) * v[3 * k + c] / 65535; }
    for (var t = 0; t < nt; t++) {
      var a = idx[3 * t], b = idx[3 * t + 1], c = idx[3 * t + 2], o = 9 * t;
      for (var x = 0; x < 3; x++) { pos[o + x] = P(a, x); pos[o + 3 + x] = P(b, x); pos[o + 6 + x] = P(c, x); }
      var u = [pos[o + 3] - pos[o], pos[o + 4] - pos[o + 1], pos[o + 5] - pos[o + 2]];
      var w = [pos[o + 6] - pos[o], pos[o + 7] - pos[o + 1], pos[o + 8] - pos[o + 2]];
      var nx = u[1] * w[2] - u[2] * w[1], ny = u[2] * w[0] - u[0] * w[2], nz = u[0] * w[1] - u[1] * w[0];
      var nl = Math.hypot(nx, ny, nz) || 1;
      for (var k = 0; k < 3; k++) { nor[o + 3 * k] = nx / nl; nor[o + 3 * k + 1] = ny / nl; nor[o + 3 * k + 2] = nz / nl; }
    }
    return { body: m.body, color: m.color, mesh: { p: buffer(pos), n: buffer(nor), count: nt * 3 } };
  });
  var capsule = D.robot.capsules || null; // per body: drawn as a capsule (null: all)
  // Grid on the floor (z = 0), 1 m square, 0.1 m spacing.
  var grid = [], gridC = [];
  for (var g = -10; g <= 10; g++) {
    grid.push(g / 10, -1, 0, g / 10, 1, 0, -1, g / 10, 0, 1, g / 10, 0);
    for (var h = 0; h < 4; h++) { gridC.push(0.85, 0.85, 0.85); }
  }
  grid.push(0, 0, 0, 0.2, 0, 0, 0, 0, 0, 0, 0.2, 0, 0, 0, 0, 0, 0, 0.2);
  gridC.push(0.9, 0.1, 0.1, 0.9, 0.1, 0.1, 0.1, 0.7, 0.1, 0.1, 0.7, 0.1, 0.1, 0.2, 0.9, 0.1, 0.2, 0.9);
  var gridB = buffer(new Float32Array(grid)), gridCB = buffer(new Float32Array(gridC)), gridN = grid.length / 3;
  var refB = null, refCB = null, refN = 0;
  if (ref) {
    refN = ref[0].length;
    var rp = new Float32Array(refN * 3), rc = new Float32Array(refN * 3);
    for (var k = 0; k < refN; k++) { rp[3 * k] = ref[0][k]; rp[3 * k + 1] = ref[1][k]; rp[3 * k + 2] = ref[2][k]; rc[3 * k] = rc[3 * k + 1] = rc[3 * k + 2] = 0.55; }
    refB = buffer(rp); refCB = buffer(rc);
  }
  runs.forEach(function (r) {
    r.traceB = buffer(r.trace); r.colB = buffer(r.col);
    if (r.hz) { r.hzB = buffer(r.hz.pts); r.hzCB = buffer(r.hz.col); }
  });
  // ---- camera ----
  var cam = { yaw: -0.9, pitch: 0.45, dist: 2.2, target: [0.4, 0, 0.5] };
  function viewProj() {
    var w = canvas.width, h = canvas.height, f = 1 / Math.tan(0.4), near = 0.05, far = 20;
    var P = [f * h / w, 0, 0, 0, 0, f, 0, 0, 0, 0, (far + near) / (near - far), -1, 0, 0, 2 * far * near / (near - far), 0];
    var cp = Math.cos(cam.pitch), eye = [cam.target[0] + cam.dist * cp * Math.cos(cam.yaw), cam.target[1] + cam.dist * cp * Math.sin(cam.yaw), cam.target[2] + cam.dist * Math.sin(cam.pitch)];
    var z = [eye[0] - cam.target[0], eye[1] - cam.target[1], eye[2] - cam.target[2]];
    var zl = Math.hypot(z[0], z[1], z[2]); z = [z[0] / zl, z[1] / zl, z[2] / zl];
    var x = [-z[1], z[0], 0]; var xl = Math.hypot(x[0], x[1]) || 1; x = [x[0] / xl, x[1] / xl, 0];
    var y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]];
    var dot = function (a, b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    var V = [x[0], y[0], z[0], 0, x[1], y[1], z[1], 0, x[2], y[2], z[2], 0, -dot(x, eye), -dot(y, eye), -dot(z, eye), 1];
    return mul(P, V);
  }
  // Model matrix of a capsule body from a to b with radius r.
  function linkMatrix(a, b, r) {
    var d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], L = Math.hypot(d[0], d[1], d[2]);
    var z = [d[0] / L, d[1] / L, d[2] / L];
    var t = Math.abs(z[2]) < 0.9 ? [0, 0, 1] : [1, 0, 0];
    var x = [t[1] * z[2] - t[2] * z[1], t[2] * z[0] - t[0] * z[2], t[0] * z[1] - t[1] * z[0]];
    var xl = Math.hypot(x[0], x[1], x[2]); x = [x[0] / xl, x[1] / xl, x[2] / xl];
    var y = [z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]];
    return [x[0] * r, x[1] * r, x[2] * r, 0, y[0] * r, y[1] * r, y[2] * r, 0, d[0], d[1], d[2], 0, a[0], a[1], a[2], 1];
  }
  function sphereMatrix(a, r) { return [r, 0, 0, 0, 0, r, 0, 0, 0, 0, r, 0, a[0], a[1], a[2], 1]; }
  var locLit = { p: gl.getAttribLocation(lit, 'p'), n: gl.getAttribLocation(lit, 'n'), M: gl.getUniformLocation(lit, 'M'), VP: gl.getUniformLocation(lit, 'VP'), c: gl.getUniformLocation(lit, 'c') };
  var locFlat = { p: gl.getAttribLocation(flat, 'p'), c: gl.getAttribLocation(flat, 'c'), VP: gl.getUniformLocation(flat, 'VP'), ps: gl.getUniformLocation(flat, 'ps') };
  function drawMesh(mesh, M, color, VP) {
    gl.bindBuffer(gl.ARRAY_BUFFER, mesh.p); gl.vertexAttribPointer(locLit.p, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, mesh.n); gl.vertexAttribPointer(locLit.n, 3, gl.FLOAT, false, 0, 0);
    gl.uniformMatrix4fv(locLit.M, false, new Float32Array(M)); gl.uniform3fv(locLit.c, color);
    gl.drawArrays(gl.TRIANGLES, 0, mesh.count);
  }
  function drawLines(pb, cb, mode, first, count, VP) {
    gl.bindBuffer(gl.ARRAY_BUFFER, pb); gl.vertexAttribPointer(locFlat.p, 3, gl.FLOAT, false, 0, 0);
    gl.bindBuffer(gl.ARRAY_BUFFER, cb); gl.vertexAttribPointer(locFlat.c, 3, gl.FLOAT, false, 0, 0);
    gl.drawArrays(mode, first, count);
  }
  // ---- state and drawing ----
  var slider = document.getElementById('replay-slider'), timeEl = document.getElementById('replay-time');
  var sel = document.getElementById('replay-run'), playBtn = document.getElementById('replay-play');
  var cur = 0, frame = 0, playing = false, lastText = 0;
  runs.forEach(function (r, i) { var o = document.createElement('option'); o.value = String(i); o.textContent = r.name + ' (' + r.status + ')'; sel.appendChild(o); });
  var S = window.ofmpcReplay = { frames: 0, k: 0, t: 0, q: [], flange: [], run: '', draws: 0, horizon: null, horizonNote: D.horizon_note, meshes: meshes.length };
  // For tests: each mesh drawn alone at the pose shown; the pixels of its colour (shaded:
  // colour × 0.3 … 1) inside and outside the screen box of its 8 projected box corners.
  var only = -1;
  function meshProbe(px) {
    var w = canvas.width, h = canvas.height, out = [];
    for (var i = 0; i < meshes.length; i++) {
      only = i; draw();
      gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
      var m = meshes[i], d = D.robot.meshes[i], M = mul(viewProj(), fk(S.q).mats[m.body]);
      var x0 = w, x1 = -1, y0 = h, y1 = -1;
      for (var c = 0; c < 8; c++) {
        var p = [c & 1 ? d.hi[0] : d.lo[0], c & 2 ? d.hi[1] : d.lo[1], c & 4 ? d.hi[2] : d.lo[2]];
        var cl = [0, 1, 2, 3].map(function (r) { return M[r] * p[0] + M[4 + r] * p[1] + M[8 + r] * p[2] + M[12 + r]; });
        var sx = (cl[0] / cl[3] + 1) / 2 * w, sy = (cl[1] / cl[3] + 1) / 2 * h;
        x0 = Math.min(x0, sx); x1 = Math.max(x1, sx); y0 = Math.min(y0, sy); y1 = Math.max(y1, sy);
      }
      var inside = 0, outside = 0, cs = 255 * (m.color[0] + m.color[1] + m.color[2]);
      for (var o = 0; o < px.length && cs > 0; o += 4) {
        var f = (px[o] + px[o + 1] + px[o + 2]) / cs, ok = f > 0.3 && f < 1.02;
        for (var k = 0; k < 3 && ok; k++) { ok = Math.abs(px[o + k] - 255 * m.color[k] * f) < 8; }
        if (!ok) { continue; }
        var x = (o >> 2) % w, y = Math.floor((o >> 2) / w);
        if (x >= x0 - 1 && x <= x1 + 1 && y >= y0 - 1 && y <= y1 + 1) { inside++; } else { outside++; }
      }
      out.push({ body: m.body, inside: inside, outside: outside, box: [x0, y0, x1, y1].map(Math.round) });
    }
    only = -1; draw();
    return out;
  }
  function draw() {
    var r = runs[cur]; if (!r || r.n === 0) { return; }
    var q = r.q.map(function (c) { return c[frame]; });
    var pts = fk(q);
    gl.viewport(0, 0, canvas.width, canvas.height);
    gl.clearColor(0.984, 0.984, 0.984, 1); gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.enable(gl.DEPTH_TEST);
    var VP = viewProj();
    gl.useProgram(flat);
    gl.enableVertexAttribArray(locFlat.p); gl.enableVertexAttribArray(locFlat.c);
    gl.uniformMatrix4fv(locFlat.VP, false, new Float32Array(VP)); gl.uniform1f(locFlat.ps, 5.0);
    drawLines(gridB, gridCB, gl.LINES, 0, gridN, VP);
    if (refB) { drawLines(refB, refCB, gl.LINE_STRIP, 0, refN, VP); }
    drawLines(r.traceB, r.colB, gl.LINE_STRIP, 0, frame + 1, VP);
    // The trace thick enough to read (WebGL draws lines 1 px wide): its samples as 3 px dots.
    gl.uniform1f(locFlat.ps, 3.0);
    drawLines(r.traceB, r.colB, gl.POINTS, 0, frame + 1, VP);
    gl.uniform1f(locFlat.ps, 5.0);
    drawLines(r.traceB, r.colB, gl.POINTS, frame, 1, VP);
    var k = Math.min(frame * r.stride, r.len - 1), hi = horizonAt(r, k);
    if (hi >= 0) {
      // The predicted horizon: its polyline and its points, over the trace.
      var hn1 = r.hz.n + 1;
      gl.uniform1f(locFlat.ps, 4.0);
      drawLines(r.hzB, r.hzCB, gl.LINE_STRIP, hi * hn1, hn1, VP);
      drawLines(r.hzB, r.hzCB, gl.POINTS, hi * hn1, hn1, VP);
      S.horizon = { k: r.hz.k[hi], pts: Array.prototype.slice.call(r.hz.pts, 3 * hi * hn1, 3 * (hi + 1) * hn1) };
    } else {
      S.horizon = null;
    }
    gl.disableVertexAttribArray(locFlat.c);
    gl.useProgram(lit);
    gl.enableVertexAttribArray(locLit.p); gl.enableVertexAttribArray(locLit.n);
    gl.uniformMatrix4fv(locLit.VP, false, new Float32Array(VP));
    var radius = 0.045;
    for (var mi = 0; mi < meshes.length; mi++) { if (only >= 0 && mi !== only) { continue; } drawMesh(meshes[mi].mesh, pts.mats[meshes[mi].body], meshes[mi].color, VP); }
    // Capsules: segment i (joint frame i to i + 1, the flange last) is rigid in body i.
    for (var i = 0; i + 1 < pts.length; i++) {
      if (capsule && !capsule[Math.min(i, capsule.length - 1)]) { continue; }
      var a = pts[i], b = pts[i + 1];
      if (Math.hypot(b[0] - a[0], b[1] - a[1], b[2] - a[2]) > 1e-6) { drawMesh(cyl, linkMatrix(a, b, radius * (i === pts.length - 2 ? 0.5 : 1)), [0.93, 0.55, 0.1], VP); }
      drawMesh(sph, sphereMatrix(a, radius * 1.15), [0.3, 0.3, 0.35], VP);
    }
    if (!capsule || capsule[capsule.length - 1]) { drawMesh(sph, sphereMatrix(pts[pts.length - 1], radius * 0.6), [0.1, 0.1, 0.1], VP); }
    gl.disableVertexAttribArray(locLit.n);
    S.frames = r.n; S.k = k; S.t = r.t[frame]; S.q = q; S.flange = pts[pts.length - 1]; S.run = r.name; S.draws++;
    stateEl.setAttribute('data-k', String(k));
    stateEl.setAttribute('data-t', String(r.t[frame]));
    // The words under the canvas at most 10 times a second while playing (layout is dear).
    var now = performance.now();
    if (playing && now - lastText < 100) { return; }
    lastText = now;
    var e = Math.pow(10, r.e[frame]);
    timeEl.textContent = 't = ' + r.t[frame].toFixed(3) + ' s';
    stateEl.textContent = r.name + ' (' + r.status + '), sample ' + k + ': |e| = ' + (e < 1e-3 ? e.toExponential(2) : e.toPrecision(3)) + ' mm; q = [' +
      q.map(function (v) { return v.toFixed(4); }).join(', ') + '] rad. Trace colour: |e| from 1 nm (blue) to 1 m (red), log scale. ' + D.horizon_note;
    stateEl.setAttribute('data-q', q.join(','));
    stateEl.setAttribute('data-flange', S.flange.join(','));
    stateEl.setAttribute('data-run', r.name);
  }
  function setFrame(f) { frame = Math.max(0, Math.min(runs[cur].n - 1, f | 0)); slider.value = String(frame); draw(); }
  function selectRun(i) { cur = i; slider.max = String(runs[cur].n - 1); setFrame(Math.min(frame, runs[cur].n - 1)); }
  slider.addEventListener('input', function () { setFrame(+slider.value); });
  sel.addEventListener('change', function () { selectRun(+sel.value); });
  var last = null, tPlay = 0, slow = document.getElementById('replay-follow');
  var speedSel = document.getElementById('replay-speed');
  S.stamps = [];
  function tick(ts) {
    if (!playing) { last = null; return; }
    if (S.stamps.length < 100000) { S.stamps.push(ts); }
    if (last !== null) {
      var r = runs[cur];
      var speed = speedSel ? +speedSel.value || 1 : 1;
      tPlay += (ts - last) / 1000 * speed * (slow.checked ? 0.1 : 1);
      var f = frame;
      while (f + 1 < r.n && r.t[f + 1] <= tPlay) { f++; }
      if (f >= r.n - 1 && r.t[r.n - 1] <= tPlay) { tPlay = r.t[0]; f = 0; }
      setFrame(f);
    }
    last = ts; requestAnimationFrame(tick);
  }
  function play(on) { playing = on; playBtn.textContent = on ? 'Pause' : 'Play'; if (on) { tPlay = runs[cur].t[frame]; requestAnimationFrame(tick); } }
  S.play = play; S.setFrame = setFrame; S.selectRun = selectRun;
  playBtn.addEventListener('click', function () { play(!playing); });
  var drag = null;
  canvas.addEventListener('mousedown', function (e) { drag = [e.clientX, e.clientY]; });
  document.addEventListener('mouseup', function () { drag = null; });
  document.addEventListener('mousemove', function (e) {
    if (!drag) { return; }
    cam.yaw -= (e.clientX - drag[0]) * 0.01; cam.pitch = Math.max(-1.4, Math.min(1.4, cam.pitch + (e.clientY - drag[1]) * 0.01));
    drag = [e.clientX, e.clientY]; draw();
  });
  canvas.addEventListener('wheel', function (e) { e.preventDefault(); cam.dist *= e.deltaY < 0 ? 0.9 : 1.1; draw(); }, { passive: false });
  if (runs.length === 0) { return; }
  selectRun(0);
  root.setAttribute('data-ready', 'yes');
  // Self-check for headless tests: move the slider as a user would and record the scene.
  if (location.hash.indexOf('replay-check') >= 0) {
    var out = [], px = new Uint8Array(canvas.width * canvas.height * 4);
    runs.forEach(function (r, ri) {
      sel.value = String(ri); sel.dispatchEvent(new Event('change'));
      [0, Math.floor(r.n / 3), Math.floor(2 * r.n / 3), r.n - 1].forEach(function (f) {
        slider.value = String(f); slider.dispatchEvent(new Event('input'));
        gl.readPixels(0, 0, canvas.width, canvas.height, gl.RGBA, gl.UNSIGNED_BYTE, px);
        var glErr = gl.getError(); if (glErr !== gl.NO_ERROR) { fail('WebGL error ' + glErr); }
        var ink = 0, sum = 0;
        for (var i = 0; i < px.length; i += 4) {
          if (px[i] < 200 || px[i + 1] < 200 || px[i + 2] < 200) { ink++; }
          sum = (sum * 31 + px[i] + 7 * px[i + 1] + 13 * px[i + 2]) % 1000000007;
        }
        out.push({ run: r.name, k: S.k, t: S.t, q: S.q, flange: S.flange, ink: ink, hash: sum, meshes: meshProbe(px) });
      });
    });
    root.setAttribute('data-check', JSON.stringify(out));
    // And at the frame of each run's middle recorded horizon: the horizon drawn there.
    var hout = [];
    runs.forEach(function (r, ri) {
      if (!r.hz) { return; }
      sel.value = String(ri); sel.dispatchEvent(new Event('change'));
      var f = Math.min(r.n - 1, Math.round(r.hz.k[r.hz.count >> 1] / r.stride));
      slider.value = String(f); slider.dispatchEvent(new Event('input'));
      hout.push({ run: r.name, k: S.k, flange: S.flange, horizon: S.horizon });
    });
    root.setAttribute('data-horizon-check', JSON.stringify(hout));
  }
})();
