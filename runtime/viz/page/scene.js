// kanesim viewer: the scene (runtime/viz/page/scene.js).
//
// Reads the scene JSON (format "kanesim-viewer" 1, runtime/viz/scene_json.h), builds the
// three.js objects and places the bodies at a time. Frames: W is the simulation's world; the
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

  // Motion: the poses at the written instants, and the pose of a body at any time.
  function Motion(data) {
    this.times = K.f64(data.times);
    this.poses = K.f32(data.poses);  // per instant, per body: p (x, y, z), q (w, x, y, z)
    this.nBodies = data.bodies.length;
    this.qa = new THREE.Quaternion();
    this.qb = new THREE.Quaternion();
  }

  // The instant k with times[k] <= t < times[k + 1] (clamped to the ends) and the fraction
  // s in [0, 1] of the way to the next one.
  Motion.prototype.locate = function (t) {
    const times = this.times;
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
  K.buildScene = function (data) {
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
    const built = { scene: scene, world: world, bodies: bodies, pickables: pickables, motion: new Motion(data) };
    scene.updateMatrixWorld(true);
    built.box = bounds(built);
    return built;
  };

  // Places every body at time t.
  K.placeBodies = function (built, t) {
    const where = built.motion.locate(t);
    built.bodies.forEach((body, b) => built.motion.place(body.group, b, where));
  };
})(window.kanesimPage = window.kanesimPage || {});
