// kanesim viewer: the page (runtime/viz/page/viewer.js): renderer, camera, playback controls,
// hover names, the link between the animation time and the plots, and the test hook.
//
// URL parameters: t=<seconds> opens paused at that time; speed=<factor> (default 1);
// play=0 opens paused; signals=<name>,<name> chooses the plots.
//
// Test hook window.kanesimViewer (docs/visualization.md, "The browser test"): ready, errors,
// time(), clock(), seek(t), play(), pause(), playing(), bodyPositions(), bodyPoses(), screenPosition(name),
// screenPoint([x, y, z]), pixel(x, y), hoverText(), cursorTimes(), plotPoint(name, t), plotted(). Positions and
// rotations are read back from the rendered objects' world matrices with the display rotation
// undone, i.e. in the simulation's world frame W.
(function (K) {
  'use strict';

  const hook = { ready: false, failed: false, errors: [] };
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

  function Viewer(data, built, renderer) {
    this.built = built;
    this.renderer = renderer;
    this.times = built.motion.times;
    this.t0 = this.times[0];
    this.t1 = this.times[this.times.length - 1];
    this.t = this.t0;
    this.playing = false;
    this.speed = 1;
    this.dirty = true;
    this.mouse = null;      // the mouse over the view, in normalised device coordinates
    this.hovered = null;    // the mesh under the mouse
    this.view = document.getElementById('view');
    this.tooltip = document.getElementById('tooltip');
    this.setUpCamera();
    this.setUpLights();
    this.plots = new K.Plots(data.signals, this.times, (t) => { this.pause(); this.seek(t); });
    this.setUpControls(data);
  }

  Viewer.prototype.setUpCamera = function () {
    const box = this.built.box;
    const center = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
    const fov = 40;
    const distance = radius / Math.sin((fov / 2) * Math.PI / 180);
    this.camera = new THREE.PerspectiveCamera(fov, 1, distance / 200, distance * 50);
    const direction = new THREE.Vector3(0.5, 0.55, 1).normalize();  // in front, to the right and above
    this.camera.position.copy(center).addScaledVector(direction, distance);
    this.camera.up.set(0, 1, 0);
    this.controls = new THREE.OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.copy(center);
    this.controls.update();
    this.controls.addEventListener('change', () => { this.dirty = true; });
    this.axes = new THREE.AxesHelper(0.3 * radius);  // W's x, y, z in red, green, blue
    this.built.world.add(this.axes);
  };

  Viewer.prototype.setUpLights = function () {
    const scene = this.built.scene;
    scene.background = new THREE.Color(0xe9edf2);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x555566, 0.65));
    const light = new THREE.DirectionalLight(0xffffff, 0.7);
    light.position.set(0.5, 1, 0.8);
    this.camera.add(light);  // the light moves with the camera
    scene.add(this.camera);
  };

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
    axes.addEventListener('change', () => { this.axes.visible = axes.checked; this.dirty = true; });
    this.clock = byId('clock');
    document.addEventListener('keydown', (e) => {
      if (e.target instanceof HTMLInputElement && e.target.type !== 'range' && e.target.type !== 'checkbox') return;
      if (e.key === ' ') { e.preventDefault(); this.playing ? this.pause() : this.play(); }
      else if (e.key === 'ArrowRight') { e.preventDefault(); this.step(1); }
      else if (e.key === 'ArrowLeft') { e.preventDefault(); this.step(-1); }
    });
    const canvas = this.renderer.domElement;
    canvas.addEventListener('mousemove', (e) => {
      const rect = canvas.getBoundingClientRect();
      this.mouse = { x: ((e.clientX - rect.left) / rect.width) * 2 - 1, y: -((e.clientY - rect.top) / rect.height) * 2 + 1,
        px: e.clientX - this.view.getBoundingClientRect().left, py: e.clientY - this.view.getBoundingClientRect().top };
    });
    canvas.addEventListener('mouseleave', () => { this.mouse = null; });
    new ResizeObserver(() => this.resize()).observe(this.view);
    this.resize();
  };

  Viewer.prototype.resize = function () {
    const w = Math.max(1, this.view.clientWidth), h = Math.max(1, this.view.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.plots.setTime(this.t);
    this.dirty = true;
  };

  Viewer.prototype.seek = function (t) {
    this.t = Math.min(Math.max(t, this.t0), this.t1);
    K.placeBodies(this.built, this.t);
    this.slider.value = this.t;
    this.clock.textContent = 't = ' + this.t.toFixed(3) + ' s / ' + this.t1.toFixed(3) + ' s';
    this.plots.setTime(this.t);
    this.dirty = true;
    return this.t;
  };

  // Moves to the next (+1) or previous (−1) written instant.
  Viewer.prototype.step = function (direction) {
    this.pause();
    const where = this.built.motion.locate(this.t);
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

  // The body (or named decoration) under the mouse, once per frame.
  Viewer.prototype.hover = function () {
    let hit = null;
    if (this.mouse) {
      const ray = new THREE.Raycaster();
      ray.setFromCamera(new THREE.Vector2(this.mouse.x, this.mouse.y), this.camera);
      const hits = ray.intersectObjects(this.built.pickables, false);
      hit = hits.length > 0 ? hits[0].object : null;
    }
    if (hit !== this.hovered) {
      if (this.hovered) this.hovered.material.emissive.setHex(0x000000);
      if (hit) hit.material.emissive.setHex(0x333333);
      this.hovered = hit;
      this.dirty = true;
    }
    if (hit) {
      const pick = hit.userData.pick;
      this.tooltip.textContent = pick.name + (pick.label ? '\n' + pick.label : '');
      this.tooltip.style.left = this.mouse.px + 14 + 'px';
      this.tooltip.style.top = this.mouse.py + 10 + 'px';
    }
    this.tooltip.hidden = !hit;
  };

  Viewer.prototype.render = function () {
    this.renderer.render(this.built.scene, this.camera);
    this.dirty = false;
  };

  Viewer.prototype.frame = function (now) {
    this.advance(now);
    this.hover();
    if (this.dirty) this.render();
    window.requestAnimationFrame((time) => this.frame(time));
  };

  // The pose of each body in W, read back from what is rendered: R_WB, p_WB from
  // (world's matrixWorld)⁻¹ · (body's matrixWorld).
  Viewer.prototype.poses = function () {
    this.built.scene.updateMatrixWorld(true);
    const toW = new THREE.Matrix4().getInverse(this.built.world.matrixWorld);
    const out = {};
    this.built.bodies.forEach((body) => {
      const e = new THREE.Matrix4().multiplyMatrices(toW, body.group.matrixWorld).elements;  // column-major
      out[body.name] = { p: [e[12], e[13], e[14]], R: [[e[0], e[4], e[8]], [e[1], e[5], e[9]], [e[2], e[6], e[10]]] };
    });
    return out;
  };

  Viewer.prototype.installHook = function () {
    hook.time = () => this.t;
    hook.clock = () => this.last;  // the frame timestamp (ms) of the last advance; null when paused
    hook.seek = (t) => { this.pause(); const at = this.seek(t); this.render(); return at; };
    hook.play = () => this.play();
    hook.pause = () => this.pause();
    hook.playing = () => this.playing;
    hook.bodyPoses = () => this.poses();
    hook.bodyPositions = () => {
      const poses = this.poses();
      const out = {};
      Object.keys(poses).forEach((name) => { out[name] = poses[name].p; });
      return out;
    };
    // The page coordinates (CSS pixels) of a body frame's origin as the camera projects it.
    hook.screenPosition = (name) => {
      const body = this.built.bodies.find((b) => b.name === name);
      if (!body) return null;
      this.built.scene.updateMatrixWorld(true);
      const v = body.group.getWorldPosition(new THREE.Vector3()).project(this.camera);
      const rect = this.renderer.domElement.getBoundingClientRect();
      return [rect.left + ((v.x + 1) / 2) * rect.width, rect.top + ((1 - v.y) / 2) * rect.height];
    };
    // The page coordinates of a point given in W, through the display rotation and the camera.
    hook.screenPoint = (p_W) => {
      this.built.scene.updateMatrixWorld(true);
      const v = new THREE.Vector3().fromArray(p_W).applyMatrix4(this.built.world.matrixWorld).project(this.camera);
      const rect = this.renderer.domElement.getBoundingClientRect();
      return [rect.left + ((v.x + 1) / 2) * rect.width, rect.top + ((1 - v.y) / 2) * rect.height];
    };
    // The colour drawn at page coordinates (x, y): [r, g, b, a] in 0..255, rendered afresh.
    hook.pixel = (x, y) => {
      this.render();
      const canvas = this.renderer.domElement;
      const rect = canvas.getBoundingClientRect();
      const px = Math.floor(((x - rect.left) * canvas.width) / rect.width);
      const py = Math.floor(((y - rect.top) * canvas.height) / rect.height);
      const gl = this.renderer.getContext();
      const out = new Uint8Array(4);
      gl.readPixels(px, canvas.height - 1 - py, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, out);
      return Array.from(out);
    };
    hook.hoverText = () => (this.tooltip.hidden ? '' : this.tooltip.textContent);
    hook.cursorTimes = () => this.plots.cursorTimes();
    hook.plotPoint = (name, t) => this.plots.pagePoint(name, t);
    hook.plotted = () => Array.from(this.plots.shown.keys());
  };

  function start(data) {
    if (typeof THREE === 'undefined' || !THREE.OrbitControls) return fail('three.js did not load (libjs-three)');
    if (typeof Dygraph === 'undefined') return fail('dygraphs did not load (libjs-dygraphs)');
    if (data.format !== 'kanesim-viewer' || data.version !== 1) return fail('not a kanesim viewer scene (version 1)');
    let renderer;
    try {
      renderer = new THREE.WebGLRenderer({ antialias: true });
    } catch (e) {
      return fail('WebGL is not available in this browser: ' + e.message);
    }
    renderer.gammaOutput = true;  // colours are linear; the screen is sRGB
    renderer.gammaFactor = 2.2;
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    document.getElementById('view').appendChild(renderer.domElement);
    const viewer = new Viewer(data, K.buildScene(data), renderer);
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
