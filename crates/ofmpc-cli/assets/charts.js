// ofmpc report: draws the interactive figures with uPlot (vendored, MIT, assets/uplot/).
// Each figure element of kind "chart" holds its data in a <script type="application/json"> element
// (see crates/ofmpc-cli/src/output/chart.rs for the encoding: 16-bit values over [lo, hi]).
// Drag a box: zoom; double-click: reset; shift + drag: pan; wheel: zoom x about the cursor.
(function () {
  'use strict';
  var GAP = 65535;
  function decode(q, log) {
    var bin = atob(q.d), n = bin.length >> 1, out = new Array(n);
    var lo = q.lo, span = q.hi - q.lo;
    for (var i = 0; i < n; i++) {
      var k = bin.charCodeAt(2 * i) | (bin.charCodeAt(2 * i + 1) << 8);
      if (k === GAP) { out[i] = null; continue; }
      var v = lo + span * k / (GAP - 1);
      out[i] = log ? Math.pow(10, v) : v;
    }
    return out;
  }
  function fmt(v) {
    if (v == null || !isFinite(v)) { return '–'; }
    var a = Math.abs(v);
    return (a !== 0 && (a < 1e-3 || a >= 1e5)) ? v.toExponential(3) : String(+v.toPrecision(4));
  }
  // Log axes: powers of ten as 1e-6; the decades are many, so only every other is labelled
  // when there are more than eight.
  function fmtLog(v, i, all) {
    if (v == null || v <= 0) { return ''; }
    var e = Math.round(Math.log10(v));
    if (Math.abs(Math.log10(v) - e) > 1e-6) { return ''; }
    return '1e' + e;
  }
  function panPlugin() {
    return { hooks: { ready: function (u) {
      var over = u.over, start = null;
      over.addEventListener('mousedown', function (e) {
        if (!e.shiftKey) { return; }
        e.stopPropagation(); e.preventDefault();
        var sx = u.scales.x, sy = u.scales.y;
        start = { x: e.clientX, y: e.clientY, x0: sx.min, x1: sx.max, y0: sy.min, y1: sy.max };
        function move(ev) {
          var w = over.clientWidth, h = over.clientHeight;
          var dx = (ev.clientX - start.x) / w * (start.x1 - start.x0);
          u.setScale('x', { min: start.x0 - dx, max: start.x1 - dx });
          if (u.scales.y.distr !== 3) {
            var dy = (ev.clientY - start.y) / h * (start.y1 - start.y0);
            u.setScale('y', { min: start.y0 + dy, max: start.y1 + dy });
          }
        }
        function up() { document.removeEventListener('mousemove', move); document.removeEventListener('mouseup', up); }
        document.addEventListener('mousemove', move);
        document.addEventListener('mouseup', up);
      }, true);
      over.addEventListener('wheel', function (e) {
        e.preventDefault();
        var r = over.getBoundingClientRect(), f = e.deltaY < 0 ? 0.8 : 1.25;
        var x = u.posToVal(e.clientX - r.left, 'x'), s = u.scales.x;
        u.setScale('x', { min: x - (x - s.min) * f, max: x + (s.max - x) * f });
      }, { passive: false });
    } } };
  }
  // The y axis as wide as its widest tick label (uPlot's axis autosize): a fixed width cuts
  // labels such as -1.235e-4 at the canvas edge.
  function axisSize(u, values, i, cycle) {
    var a = u.axes[i];
    var w = 0;
    u.ctx.font = a.font[0];
    (values || []).forEach(function (v) { if (v != null) { w = Math.max(w, u.ctx.measureText(String(v)).width); } });
    return Math.ceil(a.ticks.size + a.gap + w / (uPlot.pxRatio || 1) + 2);
  }
  // Text drawn on the canvas that does not fit (the page's clipped-text check reads it): a
  // y tick label wider than its axis, an x tick label past the canvas edge, an axis title
  // longer than its side.
  function clipped(u) {
    var bad = [], ctx = u.ctx, pr = uPlot.pxRatio || 1;
    function width(font, s) { ctx.font = font; return ctx.measureText(String(s)).width / pr; }
    u.axes.forEach(function (a, i) {
      if (!a.show || !a._values) { return; }
      var vertical = a.side === 1 || a.side === 3;
      a._values.forEach(function (s, j) {
        if (s == null || s === '') { return; }
        var w = width(a.font[0], s);
        if (vertical) {
          if (w + a.ticks.size + a.gap > a._size + 0.5) { bad.push('y tick label ' + s + ' (' + w.toFixed(0) + ' px) wider than its axis (' + a._size + ' px)'); }
        } else {
          var x = u.bbox.left / pr + u.valToPos(a._splits[j], 'x');
          if (x - w / 2 < -0.5 || x + w / 2 > u.width + 0.5) { bad.push('x tick label ' + s + ' cut at the canvas edge'); }
        }
      });
      if (a.label) {
        var lw = width(a.labelFont[0], a.label);
        if (lw > (vertical ? u.height : u.width)) { bad.push('axis title ' + a.label + ' longer than its side'); }
      }
    });
    return bad;
  }
  function panel(fig, host, p, width) {
    var groups = p.x.map(function (q) { return [decode(q, false)]; });
    p.s.forEach(function (s) { groups[s.g].push(decode(s.y, p.log)); });
    var data = groups.length === 1 ? groups[0] : uPlot.join(groups);
    // Series in the order of the joined table: group by group.
    var order = [];
    groups.forEach(function (_, g) { p.s.forEach(function (s) { if (s.g === g) { order.push(s); } }); });
    var series = [{ label: p.xl, value: function (u, v) { return fmt(v); } }];
    order.forEach(function (s) {
      var o = { label: s.l, stroke: s.c, width: 1.5, value: function (u, v) { return fmt(v); } };
      if (s.k === 'd') { o.dash = [7, 5]; o.width = 2; }
      if (s.k === 'm') { o.paths = function () { return null; }; o.points = { show: true, size: 8, fill: s.c, stroke: s.c }; }
      else { o.points = { show: false }; }
      if (groups.length > 1) { o.spanGaps = false; }
      series.push(o);
    });
    var div = document.createElement('div');
    div.className = 'chart-panel';
    host.appendChild(div);
    var opts = {
      title: p.t, width: width, height: 260, series: series,
      scales: { x: { time: false }, y: p.log ? { distr: 3 } : {} },
      axes: [{ label: p.xl, values: function (u, vs) { return vs.map(fmt); } },
             { label: p.yl, size: axisSize, space: p.log ? 18 : 30, values: function (u, vs) { return vs.map(p.log ? fmtLog : fmt); } }],
      cursor: { drag: { x: true, y: true, uni: 20 } },
      legend: { live: true },
      plugins: [panPlugin()],
      hooks: { draw: [function (u) {
        var bad = clipped(u);
        div.setAttribute('data-clipped', String(bad.length));
        div.setAttribute('data-clipped-what', bad.slice(0, 5).join('; '));
      }] }
    };
    return new uPlot(opts, data, div);
  }
  function draw(fig) {
    var el = fig.querySelector('script.chart-data');
    if (!el || fig.getAttribute('data-drawn')) { return; }
    var spec = JSON.parse(el.textContent);
    var host = fig.querySelector('div.chart');
    var cols = Math.max(1, Math.min(spec.c, 2));
    var avail = Math.max(640, host.clientWidth || document.querySelector('main').clientWidth || 1100);
    var width = Math.floor(avail / cols) - 12;
    var ok = 0;
    spec.p.forEach(function (p) { if (panel(fig, host, p, width)) { ok++; } });
    fig.setAttribute('data-drawn', ok === spec.p.length ? 'yes' : 'no');
  }
  var figs = document.querySelectorAll('figure[data-kind="chart"]');
  for (var i = 0; i < figs.length; i++) {
    try { draw(figs[i]); } catch (e) { figs[i].setAttribute('data-drawn', 'no'); figs[i].setAttribute('data-error', String(e)); }
  }
})();
