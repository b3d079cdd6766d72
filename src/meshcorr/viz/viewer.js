// meshcorr viewer: linked views of coloured meshes drawn on 2-D canvases (orthographic projection,
// painter's algorithm, two-sided Lambert shading; point clouds as dots). Shared by the HTML report
// (report_viewer.js) and the landmark picker (pick_page.js). No dependencies.
//
// MeshcorrViewer.scene(camera) makes a scene: one rotation and one zoom shared by its views.
// scene.addView(canvas, mesh) adds a view of {vertices, faces, colors} (flat arrays); dragging any
// view turns all of them, the wheel zooms all of them. While a drag or zoom lasts, a view draws at
// most FAST_FACES faces (large meshes stay interactive), then all of them once it pauses. Markers a
// page draws over the mesh (view.overlay) are redrawn alone by scene.refresh().
// A press and release without movement is a click: scene.onClick(view, vertex, event), with the
// vertex under the pointer (-1: none). scene.onHover(view, vertex) follows the pointer.
(function () {
  "use strict";
  var FAST_FACES = 6000;
  var CLICK_SLOP = 4;  // pixels the pointer may move between press and release of a click

  function normalised(v) {
    var n = Math.hypot(v[0], v[1], v[2]);
    return v.map(function (x) { return x / n; });
  }
  var LIGHT = normalised([-0.35, 0.45, 1.0]);

  function bounds(V, n) {
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
    return { centre: centre, radius: radius || 1 };
  }

  function makeView(scene, canvas, mesh) {
    var V = mesh.vertices, F = mesh.faces;
    var n = V.length / 3, m = F.length / 3;
    var box = bounds(V, n);
    var P = new Float32Array(3 * n), depth = new Float32Array(m);
    var order = new Array(m);
    var view = { canvas: canvas, colors: mesh.colors, matrix: null, drawn: 0, n: n, m: m, overlay: null };

    function project() {
      var R = scene.R, w = canvas.width, h = canvas.height, c = box.centre;
      var s = scene.zoom * 0.46 * Math.min(w, h) / box.radius;
      for (var i = 0; i < n; i++) {
        var x = V[3 * i] - c[0], y = V[3 * i + 1] - c[1], z = V[3 * i + 2] - c[2];
        P[3 * i] = w / 2 + s * (R[0] * x + R[1] * y + R[2] * z);
        P[3 * i + 1] = h / 2 - s * (R[3] * x + R[4] * y + R[5] * z);
        P[3 * i + 2] = R[6] * x + R[7] * y + R[8] * z;
      }
      return s;
    }

    function drawCloud(ctx, C) {  // dots sorted back to front, brighter when nearer
      var pts = new Array(n), zlo = Infinity, zhi = -Infinity, i;
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

    function drawFaces(ctx, C, s, stride) {
      var count = 0, f, k;
      for (f = 0; f < m; f += stride) {
        order[count++] = f;
        depth[f] = P[3 * F[3 * f] + 2] + P[3 * F[3 * f + 1] + 2] + P[3 * F[3 * f + 2] + 2];
      }
      var list = order.slice(0, count);
      list.sort(function (p, q) { return depth[p] - depth[q]; });
      ctx.lineWidth = stride > 1 ? 1.5 : 0.6;
      for (k = 0; k < count; k++) {
        f = list[k];
        var i0 = F[3 * f], i1 = F[3 * f + 1], i2 = F[3 * f + 2];
        // Screen-space normal (y flipped back to a right-handed frame).
        var ux = P[3 * i1] - P[3 * i0], uy = P[3 * i0 + 1] - P[3 * i1 + 1], uz = s * (P[3 * i1 + 2] - P[3 * i0 + 2]);
        var vx = P[3 * i2] - P[3 * i0], vy = P[3 * i0 + 1] - P[3 * i2 + 1], vz = s * (P[3 * i2 + 2] - P[3 * i0 + 2]);
        var nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
        var nn = Math.hypot(nx, ny, nz) || 1;
        var shade = 0.35 + 0.65 * Math.abs((nx * LIGHT[0] + ny * LIGHT[1] + nz * LIGHT[2]) / nn);
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
        ctx.fill();
        ctx.stroke();
      }
    }

    // The mesh is drawn into an off-screen canvas; the markers (view.overlay) on a copy of it, so that
    // they move without drawing the mesh again (view.refresh).
    var base = document.createElement("canvas");
    view.refresh = function () {
      var ctx = canvas.getContext("2d");
      ctx.drawImage(base, 0, 0);
      if (view.overlay) { view.overlay(ctx, view); }
    };
    view.draw = function (fast) {
      var started = performance.now();
      base.width = canvas.width; base.height = canvas.height;
      var ctx = base.getContext("2d");
      ctx.fillStyle = "#f4f4f4";
      ctx.fillRect(0, 0, canvas.width, canvas.height);
      var s = project();
      if (m === 0) { drawCloud(ctx, view.colors); }
      drawFaces(ctx, view.colors, s, fast ? Math.max(1, Math.ceil(m / FAST_FACES)) : 1);
      view.refresh();
      view.matrix = scene.R.slice();
      view.drawn += 1;
      view.ms = performance.now() - started;
      canvas.dataset.drawMs = view.ms.toFixed(1);
    };

    // Canvas pixel position and depth (larger: nearer) of vertex i in the last drawing.
    view.project = function (i) { return [P[3 * i], P[3 * i + 1], P[3 * i + 2]]; };

    // The vertex under canvas pixel (x, y): the nearest corner of the front-most face that covers
    // it; for a point cloud (or off the faces) the nearest point within 10 pixels, nearer ones first.
    view.pick = function (x, y) {
      var best = -1, bestDepth = -Infinity, f;
      for (f = 0; f < m; f++) {
        var a = F[3 * f], b = F[3 * f + 1], c = F[3 * f + 2];
        var x0 = P[3 * a], y0 = P[3 * a + 1], x1 = P[3 * b], y1 = P[3 * b + 1], x2 = P[3 * c], y2 = P[3 * c + 1];
        var det = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2);
        if (det === 0) { continue; }
        var l0 = ((y1 - y2) * (x - x2) + (x2 - x1) * (y - y2)) / det;
        var l1 = ((y2 - y0) * (x - x2) + (x0 - x2) * (y - y2)) / det;
        var l2 = 1 - l0 - l1;
        if (l0 < 0 || l1 < 0 || l2 < 0) { continue; }
        var z = l0 * P[3 * a + 2] + l1 * P[3 * b + 2] + l2 * P[3 * c + 2];
        if (z > bestDepth) {
          bestDepth = z;
          best = l0 >= l1 && l0 >= l2 ? a : (l1 >= l2 ? b : c);
        }
      }
      if (best >= 0) { return best; }
      var reach = 100, score = Infinity;
      for (var i = 0; i < n; i++) {
        var d2 = (P[3 * i] - x) * (P[3 * i] - x) + (P[3 * i + 1] - y) * (P[3 * i + 1] - y);
        if (d2 <= reach && d2 - 1e-3 * P[3 * i + 2] < score) { score = d2 - 1e-3 * P[3 * i + 2]; best = i; }
      }
      return best;
    };
    return view;
  }

  function rotation(R, ax, ay) {
    // Ry(ax) Rx(ay) R: turn about the screen's up axis, then its right axis.
    var cy = Math.cos(ax), sy = Math.sin(ax), cx = Math.cos(ay), sx = Math.sin(ay);
    var M = [cy, sy * sx, sy * cx, 0, cx, -sx, -sy, cy * sx, cy * cx];
    var out = new Array(9);
    for (var i = 0; i < 3; i++) {
      for (var j = 0; j < 3; j++) {
        out[3 * i + j] = M[3 * i] * R[j] + M[3 * i + 1] * R[3 + j] + M[3 * i + 2] * R[6 + j];
      }
    }
    return out;
  }

  function scene(camera) {
    var sc = { R: camera.slice(), zoom: 1, views: [], dragging: false, onClick: null, onHover: null };
    var pending = false, pendingFast = false, settle = null;
    // fast: at most FAST_FACES faces now, and every face once the interaction has paused for 250 ms.
    sc.redraw = function (fast) {
      pendingFast = pending ? pendingFast && !!fast : !!fast;
      if (settle !== null) { clearTimeout(settle); settle = null; }
      if (fast) { settle = setTimeout(function () { settle = null; if (!sc.dragging) { sc.redraw(false); } }, 250); }
      if (pending) { return; }
      pending = true;
      window.requestAnimationFrame(function () {
        pending = false;
        sc.views.forEach(function (v) { v.draw(pendingFast); });
      });
    };
    sc.refresh = function () { sc.views.forEach(function (v) { v.refresh(); }); };  // the markers only
    sc.drawNow = function () { sc.views.forEach(function (v) { v.draw(false); }); };
    sc.rotate = function (ax, ay) { sc.R = rotation(sc.R, ax, ay); };
    sc.reset = function () { sc.R = camera.slice(); sc.zoom = 1; sc.redraw(); };
    sc.addView = function (canvas, mesh) {
      var view = makeView(sc, canvas, mesh);
      sc.views.push(view);
      attach(sc, view);
      return view;
    };
    return sc;
  }

  function pixel(canvas, e) {  // event position in canvas pixels
    var box = canvas.getBoundingClientRect();
    return [(e.clientX - box.left) * canvas.width / box.width, (e.clientY - box.top) * canvas.height / box.height];
  }

  function attach(sc, view) {
    var canvas = view.canvas, last = null, start = null;
    canvas.addEventListener("mousedown", function (e) {
      last = start = [e.clientX, e.clientY]; e.preventDefault();
    });
    window.addEventListener("mousemove", function (e) {
      if (!last) {
        if (sc.onHover && !sc.dragging && e.target === canvas) { var p = pixel(canvas, e); sc.onHover(view, view.pick(p[0], p[1])); }
        return;
      }
      if (!sc.dragging && Math.hypot(e.clientX - start[0], e.clientY - start[1]) <= CLICK_SLOP) { return; }
      sc.dragging = true;
      sc.rotate(0.01 * (e.clientX - last[0]), 0.01 * (e.clientY - last[1]));
      last = [e.clientX, e.clientY];
      sc.redraw(true);
    });
    window.addEventListener("mouseup", function (e) {
      if (!last) { return; }
      var wasDrag = sc.dragging;
      last = null; sc.dragging = false;
      if (wasDrag) { sc.redraw(false); return; }
      if (sc.onClick) { var p = pixel(canvas, e); sc.onClick(view, view.pick(p[0], p[1]), e); }
    });
    canvas.addEventListener("wheel", function (e) {
      sc.zoom = Math.min(20, Math.max(0.2, sc.zoom * Math.exp(-0.0015 * e.deltaY)));
      sc.redraw(true);
      e.preventDefault();
    }, { passive: false });
    canvas.addEventListener("touchstart", function (e) {
      last = [e.touches[0].clientX, e.touches[0].clientY]; e.preventDefault();
    }, { passive: false });
    canvas.addEventListener("touchmove", function (e) {
      if (!last) { return; }
      var t = e.touches[0];
      sc.rotate(0.01 * (t.clientX - last[0]), 0.01 * (t.clientY - last[1]));
      last = [t.clientX, t.clientY];
      sc.redraw(true);
      e.preventDefault();
    }, { passive: false });
    canvas.addEventListener("touchend", function () { last = null; sc.redraw(false); });
  }

  // Synthetic drag through the real handlers (the pages' #selftest).
  function drag(canvas, dx, dy) {
    var box = canvas.getBoundingClientRect();
    var x = box.left + box.width / 2, y = box.top + box.height / 2;
    canvas.dispatchEvent(new MouseEvent("mousedown", { clientX: x, clientY: y, bubbles: true }));
    window.dispatchEvent(new MouseEvent("mousemove", { clientX: x + dx, clientY: y + dy }));
    window.dispatchEvent(new MouseEvent("mouseup", { clientX: x + dx, clientY: y + dy }));
  }

  // Errors of the page go to <pre id="errors"> and body[data-status="error"].
  function reportErrors() {
    var errors = document.getElementById("errors");
    function fail(message) {
      document.body.dataset.status = "error";
      errors.textContent += message + "\n";
      errors.style.display = "block";
    }
    window.onerror = function (message, source, line) { fail(message + " (line " + line + ")"); };
    return fail;
  }

  window.MeshcorrViewer = { scene: scene, drag: drag, reportErrors: reportErrors, FAST_FACES: FAST_FACES };
})();
