// The HTML report's own stylesheet and script (internal to src/report/): the
// script turns the inlined data into uPlot charts, links the time axes and
// cursors of one run's charts, and checks the page (every canvas drew, no
// script error) into #pneumaid-status.
#pragma once

namespace pneumaid::report_internal {

inline constexpr const char kPageStyle[] = R"PNEUMAID_PAGE(
body { font-family: system-ui, sans-serif; margin: 1.5em; color: #222; max-width: 1200px; }
h1 { font-size: 1.5em; } h2 { font-size: 1.2em; margin-top: 1.6em; } h3 { font-size: 1.05em; }
table { border-collapse: collapse; font-size: 0.85em; margin: 0.5em 0; }
td, th { border: 1px solid #ccc; padding: 2px 6px; text-align: right; }
th { background: #f0f0f0; } td.l, th.l { text-align: left; }
.prior { color: #888; } .note { color: #555; font-size: 0.9em; }
.plots { display: flex; flex-wrap: wrap; gap: 8px; }
#pneumaid-status { font-family: monospace; padding: 4px; }
tr.outlier td { background: #ffe2b0; } tr.failed td { background: #fdd; }
.named { font-size: 1.1em; padding: 6px; margin: 0.6em 0; background: #eef4ff; border-left: 4px solid #1f77b4; }
pre { background: #f6f6f6; padding: 6px; font-size: 0.85em; overflow-x: auto; }
a { color: #1f5fa0; }
#pneumaid-status.ok { background: #dfd; } #pneumaid-status.fail { background: #fdd; }
)PNEUMAID_PAGE";

inline constexpr const char kPageScript[] = R"PNEUMAID_PAGE(
(function () {
  var status = document.getElementById('pneumaid-status');
  var failures = [];
  function fail(message) {
    failures.push(message);
    status.textContent = 'FAIL: ' + failures.join('; ');
    status.className = 'fail';
  }
  window.onerror = function (message, source, line) { fail('script error: ' + message + ' at line ' + line); };
  var groups = {};
  var charts = [];
  function linkScales(group, chart) {
    (groups[group] = groups[group] || []).push(chart);
  }
  function onScale(group) {
    return function (u, key) {
      if (key !== 'x' || u._pneumaidSyncing) return;
      var min = u.scales.x.min, max = u.scales.x.max;
      (groups[group] || []).forEach(function (other) {
        if (other === u) return;
        other._pneumaidSyncing = true;
        other.setScale('x', {min: min, max: max});
        other._pneumaidSyncing = false;
      });
    };
  }
  try {
    PNEUMAID_DATA.plots.forEach(function (p) {
      var holder = document.getElementById(p.id);
      var series = [{label: p.x_label}];
      var axes = [{label: p.x_label}, {label: p.y_label}];
      var scales = {x: {time: false}};
      p.series.forEach(function (s) {
        var spec = {label: s.label, stroke: s.color, width: 1.5, scale: s.axis === 2 ? 'y2' : 'y'};
        if (s.points) { spec.paths = function () { return null; }; spec.points = {show: true, size: 5, fill: s.color}; }
        series.push(spec);
      });
      if (p.series.some(function (s) { return s.axis === 2; })) {
        axes.push({scale: 'y2', side: 1, label: p.y2_label, grid: {show: false}});
      }
      var opts = {
        title: p.title, width: p.width || 560, height: 260, series: series, axes: axes, scales: scales,
        cursor: p.group ? {sync: {key: p.group}} : {},
        hooks: p.group ? {setScale: [onScale(p.group)]} : {}
      };
      var data = [p.x].concat(p.series.map(function (s) { return s.values; }));
      var chart = new uPlot(opts, data, holder);
      if (p.group) linkScales(p.group, chart);
      charts.push(chart);
    });
  } catch (e) {
    fail('building the plots: ' + e.message);
  }
  // The page's own check: every canvas drew something.
  function check() {
    var canvases = document.querySelectorAll('canvas');
    if (canvases.length !== PNEUMAID_DATA.plots.length) fail(canvases.length + ' canvases for ' + PNEUMAID_DATA.plots.length + ' plots');
    canvases.forEach(function (canvas, k) {
      var pixels = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
      var drawn = 0;
      for (var i = 3; i < pixels.length; i += 4) if (pixels[i] !== 0) { drawn++; if (drawn > 50) break; }
      if (drawn <= 50) fail('plot ' + (k + 1) + ' drew nothing');
    });
    if (failures.length === 0) {
      status.textContent = 'OK: ' + charts.length + ' plots';
      status.className = 'ok';
    }
  }
  window.addEventListener('load', function () { setTimeout(check, 100); });
})();
)PNEUMAID_PAGE";

}  // namespace pneumaid::report_internal
