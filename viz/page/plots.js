// kanesim viewer: the time plots (viz/page/plots.js).
//
// A picker of the scene's signals (a filter box and a check box per signal) and one dygraphs
// plot per chosen signal, each with a red cursor line at the animation time. Clicking a plot
// (without dragging: a drag zooms, a double click unzooms) seeks the animation to the time
// under the mouse.
(function (K) {
  'use strict';

  // Plots draw at most 2 · kBuckets points per signal: above that each bucket of instants is
  // drawn as its minimum and maximum, in time order, so spikes stay visible.
  const kBuckets = 10000;

  function rowsOf(times, values) {
    const n = times.length;
    const value = (k) => (Number.isFinite(values[k]) ? values[k] : null);  // null: a gap
    if (n <= 2 * kBuckets) {
      const rows = new Array(n);
      for (let k = 0; k < n; ++k) rows[k] = [times[k], value(k)];
      return rows;
    }
    const rows = [];
    const size = Math.ceil(n / kBuckets);
    for (let first = 0; first < n; first += size) {
      const last = Math.min(n, first + size);
      let lo = -1, hi = -1;
      for (let k = first; k < last; ++k) {
        if (value(k) === null) continue;
        if (lo < 0 || values[k] < values[lo]) lo = k;
        if (hi < 0 || values[k] > values[hi]) hi = k;
      }
      if (lo < 0) { rows.push([times[first], null]); continue; }
      const pair = lo <= hi ? [lo, hi] : [hi, lo];
      rows.push([times[pair[0]], values[pair[0]]]);
      if (pair[1] !== pair[0]) rows.push([times[pair[1]], values[pair[1]]]);
    }
    return rows;
  }

  // signals: [{name, unit, plot, values (base64)}]; times: Float64Array; onSeek(t); eventTimes:
  // the run's events, a thin orange line each in every plot.
  function Plots(signals, times, onSeek, eventTimes) {
    this.times = times;
    this.eventTimes = eventTimes || [];
    this.onSeek = onSeek;
    this.t = times[0];
    this.signals = signals.map((s) => ({ name: s.name, unit: s.unit, plot: s.plot, values: K.f32(s.values) }));
    this.shown = new Map();  // name → {box, graph, cursor}
    this.container = document.getElementById('plots');
    this.buildPicker();
  }

  Plots.prototype.buildPicker = function () {
    const list = document.getElementById('signal-list');
    this.boxes = new Map();
    this.signals.forEach((signal) => {
      const label = document.createElement('label');
      const box = document.createElement('input');
      box.type = 'checkbox';
      box.dataset.signal = signal.name;
      box.addEventListener('change', () => (box.checked ? this.show(signal.name) : this.hide(signal.name)));
      label.appendChild(box);
      label.appendChild(document.createTextNode(' ' + signal.name + (signal.unit ? ' [' + signal.unit + ']' : '')));
      list.appendChild(label);
      this.boxes.set(signal.name, box);
    });
    const filter = document.getElementById('filter');
    filter.addEventListener('input', () => {
      const text = filter.value.toLowerCase();
      this.boxes.forEach((box, name) => {
        box.parentElement.hidden = text !== '' && name.toLowerCase().indexOf(text) < 0;
      });
    });
    if (this.signals.length === 0) filter.placeholder = 'no signals';
  };

  // The signals plotted when the page opens: the names given (URL parameter), else those
  // marked `plot`, else the first three.
  Plots.prototype.showDefaults = function (names) {
    let chosen = names ? names.filter((n) => this.boxes.has(n)) : [];
    if (chosen.length === 0) chosen = this.signals.filter((s) => s.plot).map((s) => s.name);
    if (chosen.length === 0) chosen = this.signals.slice(0, 3).map((s) => s.name);
    chosen.forEach((name) => this.show(name));
  };

  Plots.prototype.show = function (name) {
    if (this.shown.has(name)) return;
    const signal = this.signals.find((s) => s.name === name);
    if (!signal) return;
    this.boxes.get(name).checked = true;
    const box = document.createElement('div');
    box.className = 'plot';
    box.dataset.signal = name;
    const title = document.createElement('div');
    title.className = 'plot-title';
    title.textContent = name + (signal.unit ? ' [' + signal.unit + ']' : '');
    const area = document.createElement('div');
    area.className = 'plot-graph';
    const cursor = document.createElement('div');
    cursor.className = 'plot-cursor';
    box.append(title, area, cursor);
    this.container.appendChild(box);
    const entry = { box: box, area: area, cursor: cursor, graph: null };
    this.shown.set(name, entry);
    entry.graph = new Dygraph(area, rowsOf(this.times, signal.values), {
      labels: ['t', name],
      colors: ['#1f5fa8'],
      strokeWidth: 1.4,
      axisLabelFontSize: 11,
      xLabelHeight: 12,
      legend: 'onmouseover',
      labelsSeparateLines: false,
      animatedZooms: false,
      clickCallback: (event) => {
        const xy = entry.graph.eventToDomCoords(event);
        this.onSeek(entry.graph.toDataXCoord(xy[0]));
      },
      drawCallback: () => this.placeCursor(entry),
      underlayCallback: (ctx, area, g) => {
        ctx.save();
        ctx.strokeStyle = 'rgba(204, 102, 0, 0.6)';
        ctx.lineWidth = 1;
        this.eventTimes.forEach((t) => {
          const x = g.toDomXCoord(t);
          if (x < area.x || x > area.x + area.w) return;
          ctx.beginPath();
          ctx.moveTo(Math.round(x) + 0.5, area.y);
          ctx.lineTo(Math.round(x) + 0.5, area.y + area.h);
          ctx.stroke();
        });
        ctx.restore();
      },
    });
    this.placeCursor(entry);
  };

  Plots.prototype.hide = function (name) {
    const entry = this.shown.get(name);
    if (!entry) return;
    this.boxes.get(name).checked = false;
    entry.graph.destroy();
    entry.box.remove();
    this.shown.delete(name);
  };

  Plots.prototype.placeCursor = function (entry) {
    if (!entry.graph) return;
    const x = entry.graph.toDomXCoord(this.t);
    const area = entry.graph.getArea();
    const inside = Number.isFinite(x) && x >= area.x - 0.5 && x <= area.x + area.w + 0.5;
    entry.cursor.hidden = !inside;
    entry.cursor.style.left = x + 'px';
  };

  Plots.prototype.setTime = function (t) {
    this.t = t;
    this.shown.forEach((entry) => this.placeCursor(entry));
  };

  // For the test hook: each plot's name → the time at its cursor line (null when hidden).
  Plots.prototype.cursorTimes = function () {
    const out = {};
    this.shown.forEach((entry, name) => {
      out[name] = entry.cursor.hidden ? null : entry.graph.toDataXCoord(parseFloat(entry.cursor.style.left));
    });
    return out;
  };

  // For the test hook: the page coordinates of the point (t, its value) on a plot.
  Plots.prototype.pagePoint = function (name, t) {
    const entry = this.shown.get(name);
    if (!entry) return null;
    const rect = entry.area.getBoundingClientRect();
    const area = entry.graph.getArea();
    return [rect.left + entry.graph.toDomXCoord(t), rect.top + area.y + area.h / 2];
  };

  // For the test hook: the points a plot was given, [[t, value], …] (null for no such plot).
  Plots.prototype.rows = function (name) {
    const entry = this.shown.get(name);
    if (!entry) return null;
    const out = [];
    for (let r = 0; r < entry.graph.numRows(); ++r) out.push([entry.graph.getValue(r, 0), entry.graph.getValue(r, 1)]);
    return out;
  };

  K.Plots = Plots;
})(window.kanesimPage = window.kanesimPage || {});
