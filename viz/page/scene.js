// kanesim viewer: the scene and the 3-D view (viz/page/scene.js).
//
// Reads the scene JSON (format "kanesim-viewer" 1, viz/scene_json.h), builds the
// three.js objects, places the bodies at a time and draws them (K.createView3D). The 3-D view
// is optional: without WebGL or three.js the page keeps its plots and time line (viewer.js). Frames: W is the simulation's world; the
// group `world` holds everything in W and is turned so that W's up direction points along
// three.js's +Y (the camera's up), so gravity points down on the screen. Each body is a group
// (its frame B) under `world`, positioned by p_WB and q_WB; its mesh is resolved in B.
(function (K) {
  'use strict';

  function bytesOf(base64) {
    const text = atob(base64);
    const bytes = new Uint8Array(text.length);
    for (let i = 0; i < text.length; ++i) bytes[i] = text.charCodeAt(i);
    return bytes.buffer;
  }
  K.f32 = (base64) => new Float32Array(bytesOf(base64));
  K.f64 = (base64) => new Float64Array(bytesOf(base64));

  // The scene: inline in the page (offline), or fetched from the same origin (served).
  K.loadScene = function () {
    const element = document.getElementById('kanesim-scene');
    if (element.dataset.src) {
      return fetch(element.dataset.src).then((response) => {
        if (!response.ok) throw new Error(element.dataset.src + ': HTTP ' + response.status);
        return response.json();
      });
    }
    return Promise.resolve(JSON.parse(element.textContent));
  };

  function geometryOf(mesh) {
    if (mesh.vertices === 0) return null;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(K.f32(mesh.positions), 3));
    geometry.setAttribute('normal', new THREE.BufferAttribute(K.f32(mesh.normals), 3));
    const indices = bytesOf(mesh.indices);
    geometry.setIndex(new THREE.BufferAttribute(
      mesh.index_bytes === 2 ? new Uint16Array(indices) : new Uint32Array(indices), 1));
    geometry.computeBoundingSphere();
    return geometry;
  }

  // Colours are linear RGBA (as glTF's base colour); the renderer converts to sRGB on output.
  function materialOf(rgba) {
    return new THREE.MeshPhongMaterial({
      color: new THREE.Color(rgba[0], rgba[1], rgba[2]), opacity: rgba[3], transparent: rgba[3] < 1,
      side: THREE.DoubleSide, shininess: 40, specular: 0x222222,
    });
  }

  // A mesh with what hovering shows.
  function meshOf(spec, name, label, pickables) {
    const geometry = geometryOf(spec.mesh);
    if (!geometry) return null;
    const mesh = new THREE.Mesh(geometry, materialOf(spec.rgba));
    if (name) {
      mesh.userData.pick = { name: name, label: label || '' };
      pickables.push(mesh);
    }
    return mesh;
  }

  // The instant k with times[k] <= t < times[k + 1] (clamped to the ends) and the fraction
  // s in [0, 1] of the way to the next one. Needs no three.js: the time line uses it too.
  K.locate = function (times, t) {
    const n = times.length;
    if (n === 1 || t <= times[0]) return { k: 0, s: 0 };
    if (t >= times[n - 1]) return { k: n - 1, s: 0 };
    let lo = 0, hi = n - 1;  // times[lo] <= t < times[hi]
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      if (times[mid] <= t) lo = mid; else hi = mid;
    }
    return { k: lo, s: (t - times[lo]) / (times[hi] - times[lo]) };
  };

  // Motion: the poses at the written instants (times: the decoded data.times), and the pose of
  // a body at any time.
  function Motion(data, times) {
    this.times = times;
    this.poses = K.f32(data.poses);  // per instant, per body: p (x, y, z), q (w, x, y, z)
    this.nBodies = data.bodies.length;
    this.qa = new THREE.Quaternion();
    this.qb = new THREE.Quaternion();
  }

  Motion.prototype.locate = function (t) { return K.locate(this.times, t); };

  // Sets object's position and quaternion to body b's pose at t: positions interpolated
  // linearly, rotations by slerp (the shorter way), between the instants around t.
  Motion.prototype.place = function (object, b, where) {
    const a = (where.k * this.nBodies + b) * 7;
    const p = this.poses;
    object.position.set(p[a], p[a + 1], p[a + 2]);
    this.qa.set(p[a + 4], p[a + 5], p[a + 6], p[a + 3]);
    if (where.s === 0) {
      object.quaternion.copy(this.qa);
      return;
    }
    const c = a + 7 * this.nBodies;
    const s = where.s;
    object.position.set(p[a] + s * (p[c] - p[a]), p[a + 1] + s * (p[c + 1] - p[a + 1]),
      p[a + 2] + s * (p[c + 2] - p[a + 2]));
    this.qb.set(p[c + 4], p[c + 5], p[c + 6], p[c + 3]);
    THREE.Quaternion.slerp(this.qa, this.qb, object.quaternion, s);
  };

  // The box, in display coordinates, that the bodies sweep (their drawings' bounding spheres
  // at up to 400 instants and the last), or the world drawings when no body has one.
  function bounds(built) {
    const box = new THREE.Box3();
    const sphere = new THREE.Sphere();
    const grow = (object) => {
      if (!object.isMesh) return;
      sphere.copy(object.geometry.boundingSphere).applyMatrix4(object.matrixWorld);
      box.expandByPoint(sphere.center.clone().addScalar(sphere.radius));
      box.expandByPoint(sphere.center.clone().addScalar(-sphere.radius));
    };
    const n = built.motion.times.length;
    const step = Math.max(1, Math.floor(n / 400));
    const instants = [];
    for (let k = 0; k < n; k += step) instants.push(k);
    if (instants[instants.length - 1] !== n - 1) instants.push(n - 1);
    instants.forEach((k) => {
      built.bodies.forEach((body, b) => {
        built.motion.place(body.group, b, { k: k, s: 0 });
        body.group.updateMatrixWorld(true);
        body.group.traverse(grow);
      });
    });
    if (box.isEmpty()) built.world.traverse(grow);
    if (box.isEmpty()) box.setFromCenterAndSize(new THREE.Vector3(), new THREE.Vector3(2, 2, 2));
    return box;
  }

  // Builds the three.js scene: {scene, world, bodies: [{name, label, group}], pickables, motion, box}.
  function buildScene(data, times) {
    const scene = new THREE.Scene();
    const world = new THREE.Group();
    world.name = 'kanesim_world';
    const up = new THREE.Vector3().fromArray(data.up).normalize();
    world.quaternion.setFromUnitVectors(up, new THREE.Vector3(0, 1, 0));
    scene.add(world);
    const pickables = [];
    const bodies = data.bodies.map((spec) => {
      const group = new THREE.Group();
      group.name = spec.name;
      const mesh = meshOf(spec, spec.name, spec.label, pickables);
      if (mesh) group.add(mesh);
      world.add(group);
      return { name: spec.name, label: spec.label, group: group };
    });
    data.decorations.forEach((spec) => {
      const mesh = meshOf(spec, spec.name, '', pickables);
      if (mesh) (spec.body < 0 ? world : bodies[spec.body].group).add(mesh);
    });
    const built = { scene: scene, world: world, bodies: bodies, pickables: pickables, motion: new Motion(data, times) };
    scene.updateMatrixWorld(true);
    built.box = bounds(built);
    return built;
  }

  // ---- the 3-D view ---------------------------------------------------------------------------

  // Why no WebGL renderer could be made, in a few words: Chromium's reason from the canvas's
  // webglcontextcreationerror event (its first clause: the rest is driver ids), else three.js's.
  function whyNoWebGL(status, error) {
    if (typeof WebGLRenderingContext === 'undefined') return 'this browser has no WebGL (not supported)';
    let detail = status || (error && error.message) || 'unknown reason';
    if (detail.length > 60 && detail.indexOf(',') > 0) detail = detail.slice(0, detail.indexOf(','));
    return 'this browser has no WebGL (' + detail.replace(/[.\s]+$/, '') + ')';
  }

  // The 3-D view in the element `element`, or why there is none:
  // {view: View3D} or {reason: 'three.js did not load …', detail: the browser's whole message}.
  K.createView3D = function (data, times, element) {
    if (typeof THREE === 'undefined' || !THREE.OrbitControls) {
      return { reason: 'three.js did not load (libjs-three)', detail: '' };
    }
    const canvas = document.createElement('canvas');
    let status = '';
    canvas.addEventListener('webglcontextcreationerror', (e) => { status = e.statusMessage || ''; });
    let renderer;
    try {
      renderer = new THREE.WebGLRenderer({ canvas: canvas, antialias: true });
    } catch (e) {
      return { reason: whyNoWebGL(status, e), detail: status || e.message };
    }
    element.appendChild(canvas);
    return { view: new View3D(buildScene(data, times), renderer, element) };
  };

  // The renderer, the camera (orbit controls), the lights, the world axes and the body under
  // the mouse. `dirty`: something changed since the last render.
  function View3D(built, renderer, element) {
    this.built = built;
    this.renderer = renderer;
    this.element = element;
    this.tooltip = document.getElementById('tooltip');
    this.dirty = true;
    this.mouse = null;      // the mouse over the view, in normalised device coordinates
    this.hovered = null;    // the mesh under the mouse
    renderer.gammaOutput = true;  // colours are linear; the screen is sRGB
    renderer.gammaFactor = 2.2;
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.setUpCamera();
    this.setUpLights();
    this.setUpMouse();
  }

  View3D.prototype.setUpCamera = function () {
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

  View3D.prototype.setUpLights = function () {
    const scene = this.built.scene;
    scene.background = new THREE.Color(0xe9edf2);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x555566, 0.65));
    const light = new THREE.DirectionalLight(0xffffff, 0.7);
    light.position.set(0.5, 1, 0.8);
    this.camera.add(light);  // the light moves with the camera
    scene.add(this.camera);
  };

  View3D.prototype.setUpMouse = function () {
    const canvas = this.renderer.domElement;
    canvas.addEventListener('mousemove', (e) => {
      const rect = canvas.getBoundingClientRect();
      const outer = this.element.getBoundingClientRect();
      this.mouse = { x: ((e.clientX - rect.left) / rect.width) * 2 - 1, y: -((e.clientY - rect.top) / rect.height) * 2 + 1,
        px: e.clientX - outer.left, py: e.clientY - outer.top };
    });
    canvas.addEventListener('mouseleave', () => { this.mouse = null; });
  };

  View3D.prototype.resize = function (w, h) {
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.dirty = true;
  };

  View3D.prototype.place = function (t) {
    const where = this.built.motion.locate(t);
    this.built.bodies.forEach((body, b) => this.built.motion.place(body.group, b, where));
    this.dirty = true;
  };

  View3D.prototype.showAxes = function (visible) {
    this.axes.visible = visible;
    this.dirty = true;
  };

  // The body (or named decoration) under the mouse, once per frame.
  View3D.prototype.hover = function () {
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

  View3D.prototype.render = function () {
    this.renderer.render(this.built.scene, this.camera);
    this.dirty = false;
  };

  View3D.prototype.frame = function () {
    this.hover();
    if (this.dirty) this.render();
  };

  // The pose of each body in W, read back from what is rendered: R_WB, p_WB from
  // (world's matrixWorld)⁻¹ · (body's matrixWorld).
  View3D.prototype.poses = function () {
    this.built.scene.updateMatrixWorld(true);
    const toW = new THREE.Matrix4().getInverse(this.built.world.matrixWorld);
    const out = {};
    this.built.bodies.forEach((body) => {
      const e = new THREE.Matrix4().multiplyMatrices(toW, body.group.matrixWorld).elements;  // column-major
      out[body.name] = { p: [e[12], e[13], e[14]], R: [[e[0], e[4], e[8]], [e[1], e[5], e[9]], [e[2], e[6], e[10]]] };
    });
    return out;
  };

  // The page coordinates (CSS pixels) of a point in display coordinates, through the camera.
  View3D.prototype.onScreen = function (v) {
    v.project(this.camera);
    const rect = this.renderer.domElement.getBoundingClientRect();
    return [rect.left + ((v.x + 1) / 2) * rect.width, rect.top + ((1 - v.y) / 2) * rect.height];
  };

  // A body frame's origin on the page, or null for no such body.
  View3D.prototype.screenPosition = function (name) {
    const body = this.built.bodies.find((b) => b.name === name);
    if (!body) return null;
    this.built.scene.updateMatrixWorld(true);
    return this.onScreen(body.group.getWorldPosition(new THREE.Vector3()));
  };

  // A point given in W on the page, through the display rotation and the camera.
  View3D.prototype.screenPoint = function (p_W) {
    this.built.scene.updateMatrixWorld(true);
    return this.onScreen(new THREE.Vector3().fromArray(p_W).applyMatrix4(this.built.world.matrixWorld));
  };

  // The colour drawn at page coordinates (x, y): [r, g, b, a] in 0..255, rendered afresh.
  View3D.prototype.pixel = function (x, y) {
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

  View3D.prototype.hoverText = function () {
    return this.tooltip.hidden ? '' : this.tooltip.textContent;
  };
})(window.kanesimPage = window.kanesimPage || {});
