// kanesim viewer: the page (viz/page/viewer.js): the time line (slider, playback,
// keys), the link between the animation time, the 3-D view and the plots, and the test hook.
// The 3-D view (scene.js) is optional: without WebGL (or three.js) the plots and the time line
// work alone and one line in the view's panel says why there is no 3-D view.
//
// URL parameters: t=<seconds> opens paused at that time; speed=<factor> (default 1);
// play=0 opens paused; signals=<name>,<name> chooses the plots.
//
// Test hook window.kanesimViewer (docs/visualization.md, "The browser test"): ready, errors,
// noView3d ('' or the line shown when there is no 3-D view), time(), clock(), seek(t), play(), pause(), playing(),
// bodyPositions(), bodyPoses(), screenPosition(name), screenPoint([x, y, z]), pixel(x, y), hoverText(),
// cursorTimes(), plotPoint(name, t), plotted(), plotRows(name), events() (the scene's), eventMarks()
// (the time line's ticks: t, title, page x and y). Positions and rotations are read back from the
// rendered objects' world matrices with the display rotation undone, i.e. in the simulation's world frame W;
// without a 3-D view they are null.
(function (K) {
  'use strict';

  const hook = { ready: false, failed: false, errors: [], noView3d: '' };
  window.kanesimViewer = hook;
  window.addEventListener('error', (e) => hook.errors.push('error: ' + e.message));
  window.addEventListener('unhandledrejection', (e) => hook.errors.push('unhandled: ' + e.reason));
  document.addEventListener('securitypolicyviolation',
    (e) => hook.errors.push('blocked by the page policy: ' + e.blockedURI + ' (' + e.violatedDirective + ')'));

  function fail(message) {
    const box = document.getElementById('message');
    box.textContent = message;
    box.hidden = false;
    hook.errors.push(message);
    hook.failed = true;
  }

  function parameters() {
    const p = new URLSearchParams(window.location.search);
    const number = (key) => (p.has(key) && Number.isFinite(parseFloat(p.get(key))) ? parseFloat(p.get(key)) : null);
    return {
      t: number('t'),
      speed: number('speed'),
      play: p.get('play') !== '0',
      signals: p.has('signals') ? p.get('signals').split(',').filter((s) => s !== '') : null,
    };
  }

  // The time line, the plots and the 3-D view (view3d: a View3D, or null when there is none).
  function Viewer(data, times, view3d) {
    this.view3d = view3d;
    this.times = times;
    this.t0 = this.times[0];
    this.t1 = this.times[this.times.length - 1];
    this.t = this.t0;
    this.playing = false;
    this.speed = 1;
    this.last = null;
    this.view = document.getElementById('view');
    this.events = (data.events || []).filter((e) => Number.isFinite(e.t));
    this.plots = new K.Plots(data.signals, this.times, (t) => { this.pause(); this.seek(t); },
      this.events.map((e) => e.t));
    this.setUpControls(data);
  }

  Viewer.prototype.setUpControls = function (data) {
    const byId = (id) => document.getElementById(id);
    document.title = data.title;
    byId('title').textContent = data.title;
    this.slider = byId('slider');
    this.slider.min = this.t0;
    this.slider.max = this.t1;
    this.slider.disabled = this.t1 <= this.t0;
    this.slider.addEventListener('input', () => { this.pause(); this.seek(parseFloat(this.slider.value)); });
    this.playButton = byId('play');
    this.playButton.addEventListener('click', () => (this.playing ? this.pause() : this.play()));
    byId('step-back').addEventListener('click', () => this.step(-1));
    byId('step-fwd').addEventListener('click', () => this.step(1));
    this.speedSelect = byId('speed');
    this.speedSelect.addEventListener('change', () => { this.speed = parseFloat(this.speedSelect.value); });
    this.loop = byId('loop');
    const axes = byId('axes');
    axes.disabled = !this.view3d;  // nothing to show them in
    axes.addEventListener('change', () => { if (this.view3d) this.view3d.showAxes(axes.checked); });
    this.clock = byId('clock');
    this.markEvents(byId('event-marks'));
    document.addEventListener('keydown', (e) => {
      if (e.target instanceof HTMLInputElement && e.target.type !== 'range' && e.target.type !== 'checkbox') return;
      if (e.key === ' ') { e.preventDefault(); this.playing ? this.pause() : this.play(); }
      else if (e.key === 'ArrowRight') { e.preventDefault(); this.step(1); }
      else if (e.key === 'ArrowLeft') { e.preventDefault(); this.step(-1); }
    });
    new ResizeObserver(() => this.resize()).observe(this.view);
    this.resize();
  };

  // A tick on the time line per event (its time, element and kind as the tooltip); a click
  // seeks there. Several events at one instant share the tick.
  Viewer.prototype.markEvents = function (strip) {
    const span = this.t1 - this.t0;
    const byTime = new Map();
    this.events.forEach((e) => {
      const line = 't = ' + e.t + ' s: ' + e.element + ': ' + e.kind;
      byTime.set(e.t, byTime.has(e.t) ? byTime.get(e.t) + '\n' + line : line);
    });
    byTime.forEach((title, t) => {
      const mark = document.createElement('span');
      mark.className = 'event-mark';
      mark.dataset.t = String(t);
      mark.title = title;
      mark.style.left = (span > 0 ? (100 * (t - this.t0)) / span : 0) + '%';
      mark.addEventListener('click', () => { this.pause(); this.seek(t); });
      strip.appendChild(mark);
    });
  };

  Viewer.prototype.resize = function () {
    const w = Math.max(1, this.view.clientWidth), h = Math.max(1, this.view.clientHeight);
    if (this.view3d) this.view3d.resize(w, h);
    this.plots.setTime(this.t);
  };

  Viewer.prototype.seek = function (t) {
    this.t = Math.min(Math.max(t, this.t0), this.t1);
    if (this.view3d) this.view3d.place(this.t);
    this.slider.value = this.t;
    this.clock.textContent = 't = ' + this.t.toFixed(3) + ' s / ' + this.t1.toFixed(3) + ' s';
    this.plots.setTime(this.t);
    return this.t;
  };

  // Moves to the next (+1) or previous (−1) written instant.
  Viewer.prototype.step = function (direction) {
    this.pause();
    const where = K.locate(this.times, this.t);
    const k = direction > 0 ? where.k + 1 : (where.s > 0 ? where.k : where.k - 1);
    this.seek(this.times[Math.min(Math.max(k, 0), this.times.length - 1)]);
  };

  Viewer.prototype.play = function () {
    if (this.t >= this.t1) this.seek(this.t0);
    this.playing = true;
    this.last = null;
    this.playButton.innerHTML = '&#10074;&#10074;';
  };

  Viewer.prototype.pause = function () {
    this.playing = false;
    this.playButton.innerHTML = '&#9654;';
  };

  Viewer.prototype.advance = function (now) {
    if (!this.playing) return;
    const last = this.last;
    this.last = now;  // before seek: whatever seek does, no frame's advance is counted twice
    if (last !== null) {
      let t = this.t + ((now - last) / 1000) * this.speed;
      if (t > this.t1) {
        if (this.loop.checked && this.t1 > this.t0) t = this.t0 + ((t - this.t0) % (this.t1 - this.t0));
        else { t = this.t1; this.pause(); }
      }
      this.seek(t);
    }
  };

  Viewer.prototype.render = function () {
    if (this.view3d) this.view3d.render();
  };

  Viewer.prototype.frame = function (now) {
    this.advance(now);
    if (this.view3d) this.view3d.frame();
    window.requestAnimationFrame((time) => this.frame(time));
  };

  Viewer.prototype.installHook = function () {
    const view = this.view3d;
    hook.time = () => this.t;
    hook.clock = () => this.last;  // the frame timestamp (ms) of the last advance; null when paused
    hook.seek = (t) => { this.pause(); const at = this.seek(t); this.render(); return at; };
    hook.play = () => this.play();
    hook.pause = () => this.pause();
    hook.playing = () => this.playing;
    hook.bodyPoses = () => (view ? view.poses() : null);
    hook.bodyPositions = () => {
      if (!view) return null;
      const poses = view.poses();
      const out = {};
      Object.keys(poses).forEach((name) => { out[name] = poses[name].p; });
      return out;
    };
    hook.screenPosition = (name) => (view ? view.screenPosition(name) : null);
    hook.screenPoint = (p_W) => (view ? view.screenPoint(p_W) : null);
    hook.pixel = (x, y) => (view ? view.pixel(x, y) : null);
    hook.hoverText = () => (view ? view.hoverText() : '');
    hook.cursorTimes = () => this.plots.cursorTimes();
    hook.plotPoint = (name, t) => this.plots.pagePoint(name, t);
    hook.plotted = () => Array.from(this.plots.shown.keys());
    hook.plotRows = (name) => this.plots.rows(name);
    hook.events = () => this.events.map((e) => ({ t: e.t, element: e.element, kind: e.kind }));
    hook.eventMarks = () => Array.from(document.querySelectorAll('#event-marks .event-mark')).map((m) => {
      const r = m.getBoundingClientRect();
      return { t: parseFloat(m.dataset.t), title: m.title, x: r.left + r.width / 2, y: r.top + r.height / 2 };
    });
  };

  // The one line in the view's panel saying why there is no 3-D view (not an error: the rest
  // of the page works); the browser's whole message, if longer, is its tooltip.
  function noView3d(reason, detail) {
    const note = document.getElementById('note');
    note.textContent = 'No 3-D view: ' + reason + '; the plots and the time line work.';
    note.title = detail || '';
    note.hidden = false;
    hook.noView3d = note.textContent;
  }

  function start(data) {
    if (typeof Dygraph === 'undefined') return fail('dygraphs did not load (libjs-dygraphs)');
    if (data.format !== 'kanesim-viewer' || data.version !== 1) return fail('not a kanesim viewer scene (version 1)');
    const times = K.f64(data.times);
    const made = K.createView3D(data, times, document.getElementById('view'));
    if (!made.view) noView3d(made.reason, made.detail);
    const viewer = new Viewer(data, times, made.view || null);
    const p = parameters();
    viewer.installHook();
    viewer.plots.showDefaults(p.signals);
    if (p.speed !== null && p.speed > 0) {
      viewer.speed = p.speed;
      viewer.speedSelect.value = String(p.speed);
    }
    viewer.seek(p.t !== null ? p.t : viewer.t0);
    if (p.t === null && p.play) viewer.play();
    viewer.render();
    hook.ready = true;
    window.requestAnimationFrame((time) => viewer.frame(time));
  }

  K.loadScene().then(start).catch((e) => fail('cannot show the scene: ' + (e && e.message ? e.message : e)));
})(window.kanesimPage = window.kanesimPage || {});
