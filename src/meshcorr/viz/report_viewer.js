// meshcorr report: the two linked views of viewer.js (loaded before this script) on the report's data.
(function () {
  "use strict";
  var fail = MeshcorrViewer.reportErrors();
  try {
    var data = JSON.parse(document.getElementById("report-data").textContent);
    var scene = MeshcorrViewer.scene(data.camera);
    var views = [scene.addView(document.getElementById("view-source"), data.source),
                 scene.addView(document.getElementById("view-target"), data.target)];
    scene.drawNow();
    document.getElementById("reset").addEventListener("click", function () { scene.reset(); });
    if (window.location.hash === "#selftest") {
      var before = views[1].matrix.slice();
      MeshcorrViewer.drag(views[0].canvas, 40, 25);
      scene.drawNow();
      var same = views[0].matrix.every(function (x, i) { return x === views[1].matrix[i]; });
      var moved = before.some(function (x, i) { return Math.abs(x - views[1].matrix[i]) > 1e-3; });
      document.body.dataset.linked = same && moved ? "yes" : "no";
    }
    if (document.body.dataset.status !== "error") { document.body.dataset.status = "ok"; }
  } catch (e) {
    fail(String(e && e.stack || e));
  }
})();
