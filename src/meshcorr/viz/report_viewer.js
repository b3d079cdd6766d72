// meshcorr report viewer: linked, rotatable views of coloured meshes drawn on 2-D canvases
// (orthographic projection, painter's algorithm, two-sided Lambert shading; point clouds as dots).
// No dependencies.
(function () {
  "use strict";
  var errors = document.getElementById("errors");
  function fail(message) {
    document.body.dataset.status = "error";
    errors.textContent += message + "\n";
    errors.style.display = "block";
  }
  window.onerror = function (message, source, line) { fail(message + " (line " + line + ")"); };

  var data = JSON.parse(document.getElementById("report-data").textContent);
  // Shared rotation (row-major 3x3): rows are screen right, screen up, towards the viewer.
  var R = data.camera.slice();
  var light = [-0.35, 0.45, 1.0];
  var ln = Math.hypot(light[0], light[1], light[2]);
  light = light.map(function (x) { return x / ln; });

  function makeView(canvas, mesh) {
    var V = mesh.vertices, F = mesh.faces, C = mesh.colors;
    var n = V.length / 3, m = F.length / 3;
    var lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
    for (var i = 0; i < n; i++) {
      for (var a = 0; a < 3; a++) {
        lo[a] = Math.min(lo[a], V[3 * i + a]);
        hi[a] = Math.max(hi[a], V[3 * i + a]);
      }
    }
    var centre = [0, 1, 2].map(function (a) { return (lo[a] + hi[a]) / 2; });
    // Largest distance from the centre: the mesh fits the canvas at every rotation.
    var radius = 0;
    for (i = 0; i < n; i++) {
      radius = Math.max(radius, Math.hypot(V[3 * i] - centre[0], V[3 * i + 1] - centre[1], V[3 * i + 2] - centre[2]));
    }
    radius = radius || 1;
    var P = new Float32Array(3 * n), depth = new Float32Array(m);
    var order = new Array(m);
    var faceColor = new Array(m);
    var view = { canvas: canvas, matrix: null, drawn: 0 };
    view.draw = function () {
      var started = performance.now();
      var ctx = canvas.getContext("2d");
      var w = canvas.width, h = canvas.height;
      var s = 0.46 * Math.min(w, h) / radius;
      ctx.fillStyle = "#f4f4f4";
      ctx.fillRect(0, 0, w, h);
      for (var i = 0; i < n; i++) {
        var x = V[3 * i] - centre[0], y = V[3 * i + 1] - centre[1], z = V[3 * i + 2] - centre[2];
        P[3 * i] = w / 2 + s * (R[0] * x + R[1] * y + R[2] * z);
        P[3 * i + 1] = h / 2 - s * (R[3] * x + R[4] * y + R[5] * z);
        P[3 * i + 2] = R[6] * x + R[7] * y + R[8] * z;
      }
      if (m === 0) {  // a point cloud: dots sorted back to front, brighter when nearer
        var pts = new Array(n), zlo = Infinity, zhi = -Infinity;
        for (i = 0; i < n; i++) { pts[i] = i; zlo = Math.min(zlo, P[3 * i + 2]); zhi = Math.max(zhi, P[3 * i + 2]); }
        pts.sort(function (p, q) { return P[3 * p + 2] - P[3 * q + 2]; });
        var size = Math.max(1.5, Math.min(5, 2200 / Math.sqrt(n) / 10));
        for (var t = 0; t < n; t++) {
          i = pts[t];
          var cue = 0.55 + 0.45 * (P[3 * i + 2] - zlo) / ((zhi - zlo) || 1);
          ctx.fillStyle = "rgb(" + ((cue * C[3 * i]) | 0) + "," + ((cue * C[3 * i + 1]) | 0) + "," + ((cue * C[3 * i + 2]) | 0) + ")";
          ctx.fillRect(P[3 * i] - size / 2, P[3 * i + 1] - size / 2, size, size);
        }
      }
      for (var f = 0; f < m; f++) {
        order[f] = f;
        depth[f] = P[3 * F[3 * f] + 2] + P[3 * F[3 * f + 1] + 2] + P[3 * F[3 * f + 2] + 2];
      }
      order.sort(function (p, q) { return depth[p] - depth[q]; });
      for (var k = 0; k < m; k++) {
        f = order[k];
        var i0 = F[3 * f], i1 = F[3 * f + 1], i2 = F[3 * f + 2];
        // Screen-space normal (y flipped back to a right-handed frame).
        var ux = P[3 * i1] - P[3 * i0], uy = P[3 * i0 + 1] - P[3 * i1 + 1], uz = s * (P[3 * i1 + 2] - P[3 * i0 + 2]);
        var vx = P[3 * i2] - P[3 * i0], vy = P[3 * i0 + 1] - P[3 * i2 + 1], vz = s * (P[3 * i2 + 2] - P[3 * i0 + 2]);
        var nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        var nn = Math.hypot(nx, ny, nz) || 1;
        var shade = 0.35 + 0.65 * Math.abs((nx * light[0] + ny * light[1] + nz * light[2]) / nn);
        var r = shade * (C[3 * i0] + C[3 * i1] + C[3 * i2]) / 3;
        var g = shade * (C[3 * i0 + 1] + C[3 * i1 + 1] + C[3 * i2 + 1]) / 3;
        var b = shade * (C[3 * i0 + 2] + C[3 * i1 + 2] + C[3 * i2 + 2]) / 3;
        var colour = "rgb(" + (r | 0) + "," + (g | 0) + "," + (b | 0) + ")";
        ctx.beginPath();
        ctx.moveTo(P[3 * i0], P[3 * i0 + 1]);
        ctx.lineTo(P[3 * i1], P[3 * i1 + 1]);
        ctx.lineTo(P[3 * i2], P[3 * i2 + 1]);
        ctx.closePath();
        ctx.fillStyle = colour;
        ctx.strokeStyle = colour;
        ctx.lineWidth = 0.6;
        ctx.fill();
        ctx.stroke();
      }
      view.matrix = R.slice();
      view.drawn += 1;
      view.ms = performance.now() - started;
      canvas.dataset.drawMs = view.ms.toFixed(1);
    };
    return view;
  }

  function rotate(ax, ay) {
    // R <- Ry(ax) Rx(ay) R: turn about the screen's up axis, then its right axis.
    var cy = Math.cos(ax), sy = Math.sin(ax), cx = Math.cos(ay), sx = Math.sin(ay);
    var M = [cy, sy * sx, sy * cx, 0, cx, -sx, -sy, cy * sx, cy * cx];
    var out = new Array(9);
    for (var i = 0; i < 3; i++) {
      for (var j = 0; j < 3; j++) {
        out[3 * i + j] = M[3 * i] * R[j] + M[3 * i + 1] * R[3 + j] + M[3 * i + 2] * R[6 + j];
      }
    }
    R = out;
  }

  var views = [];
  var pending = false;
  function redraw() {
    if (pending) { return; }
    pending = true;
    window.requestAnimationFrame(function () {
      pending = false;
      views.forEach(function (v) { v.draw(); });
    });
  }

  function attach(view) {
    var canvas = view.canvas, last = null;
    canvas.addEventListener("mousedown", function (e) { last = [e.clientX, e.clientY]; e.preventDefault(); });
    window.addEventListener("mousemove", function (e) {
      if (!last) { return; }
      rotate(0.01 * (e.clientX - last[0]), 0.01 * (e.clientY - last[1]));
      last = [e.clientX, e.clientY];
      redraw();
    });
    window.addEventListener("mouseup", function () { last = null; });
    canvas.addEventListener("touchstart", function (e) {
      last = [e.touches[0].clientX, e.touches[0].clientY]; e.preventDefault();
    }, { passive: false });
    canvas.addEventListener("touchmove", function (e) {
      if (!last) { return; }
      var t = e.touches[0];
      rotate(0.01 * (t.clientX - last[0]), 0.01 * (t.clientY - last[1]));
      last = [t.clientX, t.clientY];
      redraw();
      e.preventDefault();
    }, { passive: false });
    canvas.addEventListener("touchend", function () { last = null; });
  }

  function drag(canvas, dx, dy) {
    // Synthetic drag through the real handlers (self-test: #selftest in the address).
    var box = canvas.getBoundingClientRect();
    var x = box.left + box.width / 2, y = box.top + box.height / 2;
    canvas.dispatchEvent(new MouseEvent("mousedown", { clientX: x, clientY: y, bubbles: true }));
    window.dispatchEvent(new MouseEvent("mousemove", { clientX: x + dx, clientY: y + dy }));
    window.dispatchEvent(new MouseEvent("mouseup", { clientX: x + dx, clientY: y + dy }));
  }

  try {
    views.push(makeView(document.getElementById("view-source"), data.source));
    views.push(makeView(document.getElementById("view-target"), data.target));
    views.forEach(attach);
    views.forEach(function (v) { v.draw(); });
    document.getElementById("reset").addEventListener("click", function () {
      R = data.camera.slice(); redraw();
    });
    if (window.location.hash === "#selftest") {
      var before = views[1].matrix.slice();
      drag(views[0].canvas, 40, 25);
      views.forEach(function (v) { v.draw(); });
      var same = views[0].matrix.every(function (x, i) { return x === views[1].matrix[i]; });
      var moved = before.some(function (x, i) { return Math.abs(x - views[1].matrix[i]) > 1e-3; });
      document.body.dataset.linked = same && moved ? "yes" : "no";
    }
    if (document.body.dataset.status !== "error") { document.body.dataset.status = "ok"; }
  } catch (e) {
    fail(String(e && e.stack || e));
  }
})();
