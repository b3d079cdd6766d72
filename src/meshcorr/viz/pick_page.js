// meshcorr pick: click landmark pairs on the two views of viewer.js (loaded before this script).
// The page talks to its server only (meshcorr.viz.pick): every request carries the session's token.
// Test hooks: body[data-status] ("ok" once drawn), [data-pairs], [data-saved], [data-match],
// [data-version]; window.meshcorrPick.screen(side, vertex) gives a vertex's position in the window.
(function () {
  "use strict";
  var fail = MeshcorrViewer.reportErrors();
  var config = JSON.parse(document.getElementById("pick-config").textContent);
  var PALETTE = ["#e6194b", "#3cb44b", "#4363d8", "#f58231", "#911eb4", "#42d4f4", "#f032e6", "#9a6324",
                 "#000075", "#808000"];
  var NEUTRAL = 200;
  var body = document.body;
  var message = document.getElementById("message");
  var progress = document.getElementById("progress");
  var state = { pairs: [], pending: null, moving: null, hover: -1, map: null, colors: null,
                suggestions: [], low: false, margin: null, version: 0, ids: null };
  var scene, views = {};

  function api(method, path, payload) {
    var options = { method: method, headers: { "X-Meshcorr-Token": config.token } };
    if (payload !== undefined) {
      options.headers["Content-Type"] = "application/json";
      options.body = JSON.stringify(payload);
    }
    return fetch(path, options).then(function (r) {
      return r.json().then(function (data) {
        if (!r.ok) { throw new Error(data.error || ("HTTP " + r.status)); }
        return data;
      });
    });
  }

  function say(text, bad) { message.textContent = text; message.className = bad ? "bad" : ""; }

  // ------------------------------------------------------------ pairs (drawn numbering in state)

  function inputPairs() {  // the pairs in the input files' numbering
    return state.pairs.map(function (p) { return [state.ids[0][p[0]], state.ids[1][p[1]]]; });
  }

  function changed() {
    body.dataset.pairs = String(state.pairs.length);
    renderTable();
    scene.refresh();
    api("POST", "/api/landmarks", { pairs: inputPairs() }).catch(function (e) { say(e.message, true); });
  }

  function renderTable() {
    var rows = document.querySelector("#pairs tbody");
    rows.innerHTML = "";
    state.pairs.forEach(function (p, k) {
      var tr = document.createElement("tr");
      if (state.moving === k) { tr.className = "moving"; }
      tr.innerHTML = '<td><span class="swatch" style="background:' + PALETTE[k % PALETTE.length] + '"></span> ' +
        (k + 1) + "</td><td>" + state.ids[0][p[0]] + "</td><td>" + state.ids[1][p[1]] + "</td>" +
        '<td><button class="move">move</button> <button class="delete">delete</button></td>';
      tr.querySelector(".move").addEventListener("click", function () {
        state.moving = state.moving === k ? null : k; state.pending = null;
        say(state.moving === null ? "" : "Click the new place of pair " + (k + 1) + " on either view (Esc: cancel).");
        renderTable(); scene.refresh();
      });
      tr.querySelector(".delete").addEventListener("click", function () {
        state.pairs.splice(k, 1); state.moving = null;
        say("Deleted pair " + (k + 1) + "."); changed();
      });
      rows.appendChild(tr);
    });
  }

  function click(view, vertex) {
    if (vertex < 0) { return; }
    var side = view === views.source ? 0 : 1;
    if (state.moving !== null) {
      var pair = state.pairs[state.moving];
      var clash = side === 0 && state.pairs.some(function (p, k) { return k !== state.moving && p[0] === vertex; });
      if (clash) { say("Source vertex " + state.ids[0][vertex] + " has a pair already.", true); return; }
      pair[side] = vertex;
      say("Moved the " + (side ? "target" : "source") + " end of pair " + (state.moving + 1) + ".");
      state.moving = null; changed(); return;
    }
    if (state.pending && state.pending.side !== side) {
      var p = side === 0 ? [vertex, state.pending.vertex] : [state.pending.vertex, vertex];
      state.pending = null;
      var old = state.pairs.findIndex(function (q) { return q[0] === p[0]; });
      if (old >= 0) { state.pairs[old] = p; say("Replaced pair " + (old + 1) + "."); }
      else { state.pairs.push(p); say("Pair " + state.pairs.length + " made."); }
      changed(); return;
    }
    state.pending = { side: side, vertex: vertex };
    say("Now click its partner on the " + (side ? "source" : "target") + ".");
    scene.refresh();
  }

  // --------------------------------------------------------------------------- drawing

  function ring(ctx, xy, radius, colour, dashed, label) {
    ctx.save();
    ctx.beginPath();
    ctx.arc(xy[0], xy[1], radius, 0, 2 * Math.PI);
    ctx.setLineDash(dashed ? [4, 3] : []);
    ctx.lineWidth = 2.5; ctx.strokeStyle = colour; ctx.stroke();
    if (label) { ctx.font = "bold 12px sans-serif"; ctx.fillStyle = colour; ctx.fillText(label, xy[0] + radius + 2, xy[1] - radius); }
    ctx.restore();
  }

  function dot(ctx, xy, colour, label) {
    ctx.beginPath();
    ctx.arc(xy[0], xy[1], 8, 0, 2 * Math.PI);
    ctx.fillStyle = colour; ctx.fill();
    ctx.lineWidth = 2; ctx.strokeStyle = "#fff"; ctx.stroke();
    ctx.font = "bold 10px sans-serif"; ctx.fillStyle = "#fff"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
    ctx.fillText(label, xy[0], xy[1] + 0.5);
    ctx.textAlign = "start"; ctx.textBaseline = "alphabetic";
  }

  function overlay(side) {
    return function (ctx, view) {
      state.suggestions.forEach(function (s) {
        if (side === 0) { ring(ctx, view.project(s.source), 15, "#d97a00", true, "?"); }
        else { ring(ctx, view.project(s.chosen), 15, "#d97a00", true, "a"); ring(ctx, view.project(s.rival), 15, "#7a00d9", true, "b"); }
      });
      if (state.hover >= 0 && state.map) {
        var v = side === 0 ? state.hover : state.map[state.hover];
        if (v >= 0) { ring(ctx, view.project(v), 6, "#000", false); }
      }
      state.pairs.forEach(function (p, k) { dot(ctx, view.project(p[side]), PALETTE[k % PALETTE.length], String(k + 1)); });
      if (state.pending && state.pending.side === side) { ring(ctx, view.project(state.pending.vertex), 9, "#000", true); }
    };
  }

  function recolour() {
    var n1 = views.source.n, n2 = views.target.n, i, a;
    var C1 = new Array(3 * n1), C2 = state.map ? state.colors : new Array(3 * n2).fill(NEUTRAL);
    for (i = 0; i < n1; i++) {
      var j = state.map ? state.map[i] : -1;
      for (a = 0; a < 3; a++) { C1[3 * i + a] = j >= 0 ? C2[3 * j + a] : (state.map ? 170 : NEUTRAL); }
    }
    views.source.colors = C1; views.target.colors = C2;
  }

  function showSuggestions() {
    var box = document.getElementById("suggestions");
    if (!state.suggestions.length) { box.textContent = ""; box.className = "note"; return; }
    var where = state.suggestions.map(function (s) {
      return "source " + state.ids[0][s.source] + " (a: target " + state.ids[1][s.chosen] + ", b: " + state.ids[1][s.rival] + ")";
    }).join("; ");
    box.className = "note" + (state.low ? " low" : "");
    box.textContent = (state.low ? "The map's global choice is unsure" : "The map's global choice is fairly sure") +
      (state.margin === null ? "" : " (margin " + state.margin.toFixed(2) + ")") +
      ". Landmarks at the dashed rings would settle it: " + where + ".";
  }

  function loadMap() {
    return api("GET", "/api/map").then(function (data) {
      state.map = data.map; state.colors = data.target_colors; state.version = data.version;
      state.suggestions = data.suggestions; state.low = data.low; state.margin = data.margin;
      body.dataset.version = String(data.version);
      recolour(); showSuggestions(); scene.redraw();
    });
  }

  // ------------------------------------------------------------------------- buttons

  function save() {
    return api("POST", "/api/save", { pairs: inputPairs() }).then(function (r) {
      body.dataset.saved = String(r.saved);
      say(r.output ? "Saved " + r.saved + " pairs to " + r.output + "." : "Kept " + r.saved + " pairs.");
    }).catch(function (e) { say(e.message, true); });
  }

  function poll() {
    api("GET", "/api/status").then(function (s) {
      progress.hidden = s.state !== "running";
      progress.value = s.fraction;
      if (s.state === "running") {
        say("Matching: " + s.stage + ", " + Math.round(100 * s.fraction) + "%" +
            (s.seconds_left === null ? "" : ", ~" + Math.ceil(s.seconds_left) + " s left") + "...");
        setTimeout(poll, 250); return;
      }
      matchButton().disabled = false;
      var warned = s.warnings.length ? " Warning: " + s.warnings.join(" Warning: ") : "";
      if (s.state === "error") { body.dataset.match = "error"; say("Match failed: " + s.error, true); return; }
      loadMap().then(function () {
        say("New map with " + s.landmarks + " landmark pairs." + warned, warned !== "");
        body.dataset.match = "done";
      });
    }).catch(function (e) { say(e.message, true); body.dataset.match = "error"; });
  }

  function matchButton() { return document.getElementById("match"); }

  function matchAgain() {
    body.dataset.match = "running";
    matchButton().disabled = true;
    api("POST", "/api/match", { pairs: inputPairs() }).then(function () {
      progress.hidden = false; say("Matching..."); poll();
    }).catch(function (e) { body.dataset.match = "error"; matchButton().disabled = false; say(e.message, true); });
  }

  function closePicker() {
    navigator.sendBeacon("/api/close?token=" + encodeURIComponent(config.token));
    say("The picker has stopped; you may close this page.");
    document.querySelectorAll("button").forEach(function (b) { b.disabled = true; });
    body.dataset.closed = "yes";
  }

  function start(meshes) {
    state.ids = meshes.ids.map(function (ids, side) {  // null: the input's own numbering
      var n = meshes[side ? "target" : "source"].vertices.length / 3;
      return ids || Array.from({ length: n }, function (_, i) { return i; });
    });
    scene = MeshcorrViewer.scene(meshes.camera);
    views.source = scene.addView(document.getElementById("view-source"), meshes.source);
    views.target = scene.addView(document.getElementById("view-target"), meshes.target);
    views.source.overlay = overlay(0); views.target.overlay = overlay(1);
    document.getElementById("n-source").textContent = views.source.n;
    document.getElementById("n-target").textContent = views.target.n;
    scene.onClick = click;
    scene.onHover = function (view, vertex) {
      var v = view === views.source ? vertex : -1;
      if (v !== state.hover) { state.hover = v; if (state.map) { scene.refresh(); } }
    };
    document.getElementById("save").addEventListener("click", save);
    var matchButton = document.getElementById("match");
    matchButton.disabled = !config.can_match;
    matchButton.addEventListener("click", matchAgain);
    document.getElementById("reset").addEventListener("click", function () { scene.reset(); });
    document.getElementById("close").addEventListener("click", closePicker);
    document.addEventListener("keydown", function (e) {
      if (e.key === "Escape") { state.moving = null; state.pending = null; say(""); renderTable(); scene.refresh(); }
    });
    window.addEventListener("pagehide", function () {
      if (body.dataset.closed !== "yes") { navigator.sendBeacon("/api/close?token=" + encodeURIComponent(config.token)); }
    });
    window.meshcorrPick = {
      state: state, views: views, scene: scene,
      screen: function (side, vertex) {  // window coordinates of a vertex in the last drawing
        var view = side === "source" ? views.source : views.target, xy = view.project(vertex);
        var box = view.canvas.getBoundingClientRect();
        return [box.left + xy[0] * box.width / view.canvas.width, box.top + xy[1] * box.height / view.canvas.height];
      }
    };
    return Promise.all([loadMap(), api("GET", "/api/landmarks")]).then(function (r) {
      var lookup = [{}, {}];
      state.ids.forEach(function (ids, side) { ids.forEach(function (v, i) { lookup[side][v] = i; }); });
      state.pairs = r[1].pairs.map(function (p) { return [lookup[0][p[0]], lookup[1][p[1]]]; });
      body.dataset.pairs = String(state.pairs.length);
      renderTable(); scene.drawNow();
      if (meshes.thinned > 1) { say("Large meshes: the views draw every " + meshes.thinned + "-th face."); }
      if (body.dataset.status !== "error") { body.dataset.status = "ok"; }
    });
  }

  api("GET", "/api/meshes").then(start).catch(function (e) { fail(String(e && e.stack || e)); });
})();
