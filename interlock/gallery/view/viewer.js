/* interlock's viewer: an assembly, its frame, the motion the verifier found and the contact forces, in three.js.
 *
 * A scene (interlock.gallery.view.scene, JSON) is mounted into an element with InterlockViewer.mount(element, scene).
 * Everything a page needs is inline: this script, three.js (vendored, MIT) and the scenes; nothing is fetched.
 * For tests and scripts, window.interlock.views holds every mounted view (stats(), setMotion(t), blockMatrix(k)).
 */
(function () {
  'use strict';

  var registry = window.interlock = window.interlock || { views: [], ready: false, errors: [] };

  function decode(text, Type) {
    var bytes = atob(text);
    var buffer = new ArrayBuffer(bytes.length);
    var view = new Uint8Array(buffer);
    for (var k = 0; k < bytes.length; k++) view[k] = bytes.charCodeAt(k);
    return new Type(buffer);
  }

  function element(tag, className, text) {
    var node = document.createElement(tag);
    if (className) node.className = className;
    if (text !== undefined) node.textContent = text;
    return node;
  }

  function ranges(values) {  // [0, 1, 2, 5] -> "0-2,5": what --fixed reads
    var sorted = Array.from(new Set(values)).sort(function (a, b) { return a - b; });
    var parts = [];
    for (var k = 0; k < sorted.length;) {
      var end = k;
      while (end + 1 < sorted.length && sorted[end + 1] === sorted[end] + 1) end++;
      parts.push(end === k ? String(sorted[k]) : sorted[k] + '-' + sorted[end]);
      k = end + 1;
    }
    return parts.join(',');
  }

  function webglAvailable() {
    try {
      var canvas = document.createElement('canvas');
      return !!(window.WebGL2RenderingContext && canvas.getContext('webgl2'));
    } catch (e) {
      return false;
    }
  }

  var SELECTED = new THREE.Color('#ffd400');
  // above this many blocks the edges are not smoothed (multisampling): without a GPU it doubles the first frame
  var SMOOTH_BLOCKS = 2000;
  // moving blocks draw their edges (one line set each) up to this many; beyond, only their colour shows them
  var MOVING_EDGES = 300;

  function forceColour(share, target) {  // blue (small) -> orange -> red (largest)
    var stops = [[0.2, 0.35, 0.85], [0.95, 0.6, 0.1], [0.85, 0.1, 0.1]];
    var x = Math.min(Math.max(share, 0), 1) * 2, i = Math.min(Math.floor(x), 1), f = x - i;
    return target.setRGB(stops[i][0] + f * (stops[i + 1][0] - stops[i][0]),
                         stops[i][1] + f * (stops[i + 1][1] - stops[i][1]),
                         stops[i][2] + f * (stops[i + 1][2] - stops[i][2]));
  }

  function View(container, data) {
    this.container = container;
    this.data = data;
    this.frames = 0;  // frames rendered
    this.frame = new Set(data.blocks.frame);
    this.moving = new Set(data.motion ? data.motion.moving : []);
    this.selected = -1;
    this.pickingFrame = false;
    this.playing = false;
    this.motionAt = 0;
    this.disposed = false;
    this.build();
  }

  View.prototype.build = function () {
    var data = this.data, self = this;
    var root = element('div', 'iv-root');
    this.container.appendChild(root);
    this.root = root;
    var stage = element('div', 'iv-stage');
    root.appendChild(stage);
    this.stage = stage;
    if (!webglAvailable()) {
      stage.appendChild(element('p', 'iv-nogl', 'This view needs WebGL 2, which this browser does not offer.'));
      this.failed = true;
      return;
    }
    var renderer = this.renderer = new THREE.WebGLRenderer({ antialias: data.blocks.count <= SMOOTH_BLOCKS,
                                                              preserveDrawingBuffer: true });
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    renderer.setClearColor(0xf4f5f7, 1);
    stage.appendChild(renderer.domElement);
    var scene = this.scene = new THREE.Scene();
    var camera = this.camera = new THREE.PerspectiveCamera(35, 1, data.size * 1e-3, data.size * 50);
    camera.up.set(0, 0, 1);
    scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a8a, 2.2));
    var sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(0.4, -0.6, 1.0);
    camera.add(sun);
    scene.add(camera);
    var controls = this.controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.enableDamping = false;
    controls.screenSpacePanning = true;
    controls.addEventListener('change', function () { self.render(); });
    controls.addEventListener('start', function () { self.moved = true; });
    this.moved = false;

    this.buildBlocks();
    this.buildForces();
    this.buildMotion();
    this.buildPanels();
    this.bindPicking();
    this.resize();
    if (data.motion) this.setMotion(data.motion.start_at || 0);
    if (window.ResizeObserver) {
      this.observer = new ResizeObserver(function () { self.resize(); });
      this.observer.observe(stage);
    }
  };

  View.prototype.buildBlocks = function () {
    var data = this.data, blocks = data.blocks, n = blocks.count;
    var matrices = decode(blocks.matrix, Float32Array);
    this.matrices = matrices;
    this.meshes = [];
    this.where = new Array(n);  // block -> [mesh index, instance]
    var byType = {};
    for (var k = 0; k < n; k++) (byType[blocks.type[k]] = byType[blocks.type[k]] || []).push(k);
    var material = this.material = new THREE.MeshStandardMaterial({
      flatShading: true, roughness: 0.75, metalness: 0.0, side: THREE.DoubleSide,
      polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1 });
    var edgeMaterial = this.edgeMaterial = new THREE.LineBasicMaterial({ color: 0x2b2b2b, transparent: true,
                                                                          opacity: 0.45 });
    var matrix = new THREE.Matrix4(), point = new THREE.Vector3();
    var staticEdges = [], self = this;
    var ownEdges = this.moving.size <= MOVING_EDGES;
    this.movingEdges = {};
    Object.keys(byType).forEach(function (type) {
      var members = byType[type], spec = data.geometries[type];
      var geometry = new THREE.BufferGeometry();
      geometry.setAttribute('position', new THREE.BufferAttribute(decode(spec.position, Float32Array), 3));
      geometry.setIndex(new THREE.BufferAttribute(decode(spec.index, Uint32Array), 1));
      geometry.computeVertexNormals();
      var mesh = new THREE.InstancedMesh(geometry, material, members.length);
      mesh.userData.blocks = members;
      members.forEach(function (block, i) {
        matrix.fromArray(matrices, 16 * block);
        mesh.setMatrixAt(i, matrix);
        self.where[block] = [self.meshes.length, i];
      });
      mesh.instanceMatrix.needsUpdate = true;
      mesh.frustumCulled = false;
      self.scene.add(mesh);
      self.meshes.push(mesh);
      var edges = new THREE.EdgesGeometry(geometry, 25).getAttribute('position').array;
      members.forEach(function (block) {
        matrix.fromArray(matrices, 16 * block);
        if (self.moving.has(block)) {
          if (!ownEdges) return;  // thousands of moving blocks: one line set each would cost a draw call each
          var own = new THREE.BufferGeometry();
          own.setAttribute('position', new THREE.BufferAttribute(edges, 3));
          var lines = new THREE.LineSegments(own, edgeMaterial);
          lines.matrixAutoUpdate = false;
          lines.matrix.copy(matrix);
          self.movingEdges[block] = lines;
          self.scene.add(lines);
          return;
        }
        var out = new Float32Array(edges.length);
        for (var v = 0; v < edges.length; v += 3) {
          point.set(edges[v], edges[v + 1], edges[v + 2]).applyMatrix4(matrix);
          out[v] = point.x; out[v + 1] = point.y; out[v + 2] = point.z;
        }
        staticEdges.push(out);
      });
    });
    var total = staticEdges.reduce(function (s, a) { return s + a.length; }, 0);
    var merged = new Float32Array(total), at = 0;
    staticEdges.forEach(function (a) { merged.set(a, at); at += a.length; });
    var edgeGeometry = new THREE.BufferGeometry();
    edgeGeometry.setAttribute('position', new THREE.BufferAttribute(merged, 3));
    this.edges = new THREE.LineSegments(edgeGeometry, edgeMaterial);
    this.edges.frustumCulled = false;
    this.scene.add(this.edges);
    this.colourBlocks();
  };

  View.prototype.blockColour = function (block, target) {
    var data = this.data;
    if (block === this.selected) return target.copy(SELECTED);
    if (this.frame.has(block)) return target.set(data.frame_colour);
    if (this.moving.has(block)) return target.set(data.moving_colour);
    return target.set(data.classes.colours[data.blocks['class'][block] % data.classes.colours.length]);
  };

  View.prototype.colourBlocks = function () {
    var colour = new THREE.Color(), self = this;
    this.meshes.forEach(function (mesh) {
      mesh.userData.blocks.forEach(function (block, i) { mesh.setColorAt(i, self.blockColour(block, colour)); });
      mesh.instanceColor.needsUpdate = true;
    });
  };

  View.prototype.buildForces = function () {
    var forces = this.data.forces;
    if (!forces) return;
    var points = decode(forces.points, Float32Array), vectors = decode(forces.vectors, Float32Array);
    var length = 0.9 * this.data.block_size, radius = 0.035 * this.data.block_size;
    var shaft = new THREE.CylinderGeometry(radius, radius, 1, 8);
    shaft.translate(0, 0.5, 0);
    var head = new THREE.ConeGeometry(radius * 2.6, 1, 12);
    head.translate(0, 0.5, 0);
    var material = new THREE.MeshStandardMaterial({ roughness: 0.6, metalness: 0.0, depthTest: false,
                                                   transparent: true, opacity: 0.9 });
    var shafts = new THREE.InstancedMesh(shaft, material, forces.count);
    var heads = new THREE.InstancedMesh(head, material, forces.count);
    var m = new THREE.Matrix4(), q = new THREE.Quaternion(), y = new THREE.Vector3(0, 1, 0);
    var d = new THREE.Vector3(), p = new THREE.Vector3(), s = new THREE.Vector3(), colour = new THREE.Color();
    for (var k = 0; k < forces.count; k++) {
      d.set(vectors[3 * k], vectors[3 * k + 1], vectors[3 * k + 2]);
      var share = d.length() / forces.largest;
      var long = Math.max(share, 0.08) * length;
      d.normalize();
      q.setFromUnitVectors(y, d);
      p.set(points[3 * k], points[3 * k + 1], points[3 * k + 2]);
      var headLength = Math.min(radius * 6, long * 0.5);
      m.compose(p, q, s.set(1, long - headLength, 1));
      shafts.setMatrixAt(k, m);
      m.compose(p.clone().addScaledVector(d, long - headLength), q, s.set(1, headLength, 1));
      heads.setMatrixAt(k, m);
      forceColour(share, colour);
      shafts.setColorAt(k, colour);
      heads.setColorAt(k, colour);
    }
    [shafts, heads].forEach(function (mesh) {
      mesh.frustumCulled = false;
      mesh.renderOrder = 2;  // drawn over the blocks: a force acts inside the joint, where the blocks hide it
    });
    this.forces = new THREE.Group();
    this.forces.add(shafts, heads);
    this.scene.add(this.forces);
  };

  View.prototype.buildMotion = function () {
    var motion = this.data.motion;
    if (!motion) return;
    if (motion.twists) {  // a twist (omega, t) per moving block about its centre: followed exactly, below
      this.twists = decode(motion.twists, Float32Array);
      this.centres = decode(motion.centres, Float32Array);
      this.placed = motion.moving.map(function (block) { return new THREE.Matrix4(); });
      var self = this;
      motion.moving.forEach(function (block, b) { self.placed[b].fromArray(self.matrices, 16 * block); });
      return;
    }
    var matrices = decode(motion.matrices, Float32Array), m = new THREE.Matrix4();
    this.poses = [];  // sampled placements (a finite motion's path): per step, per moving block
    for (var step = 0; step < motion.steps; step++) {
      var row = [];
      for (var b = 0; b < motion.moving.length; b++) {
        var pose = { p: new THREE.Vector3(), q: new THREE.Quaternion(), s: new THREE.Vector3() };
        m.fromArray(matrices, 16 * (step * motion.moving.length + b));
        m.decompose(pose.p, pose.q, pose.s);
        row.push(pose);
      }
      this.poses.push(row);
    }
  };

  // exp(s xi) of a twist xi = (omega, t) about the centre c (Rodrigues; interlock.verify.motion.twist_exponential)
  function screw(omega, t, c, s, target) {
    var px = s * omega[0], py = s * omega[1], pz = s * omega[2], theta = Math.sqrt(px * px + py * py + pz * pz);
    var a, b, d;
    if (theta < 1e-4) {
      a = 1 - theta * theta / 6; b = 0.5 - theta * theta / 24; d = 1 / 6 - theta * theta / 120;
    } else {
      a = Math.sin(theta) / theta; b = (1 - Math.cos(theta)) / (theta * theta);
      d = (theta - Math.sin(theta)) / (theta * theta * theta);
    }
    var K = [[0, -pz, py], [pz, 0, -px], [-py, px, 0]], R = [], V = [];
    for (var i = 0; i < 3; i++) {
      R.push([]); V.push([]);
      for (var j = 0; j < 3; j++) {
        var k2 = K[i][0] * K[0][j] + K[i][1] * K[1][j] + K[i][2] * K[2][j], eye = i === j ? 1 : 0;
        R[i].push(eye + a * K[i][j] + b * k2);
        V[i].push(eye + b * K[i][j] + d * k2);
      }
    }
    var move = [];
    for (i = 0; i < 3; i++) {
      move.push(c[i] - (R[i][0] * c[0] + R[i][1] * c[1] + R[i][2] * c[2])
                + s * (V[i][0] * t[0] + V[i][1] * t[1] + V[i][2] * t[2]));
    }
    return target.set(R[0][0], R[0][1], R[0][2], move[0], R[1][0], R[1][1], R[1][2], move[1],
                      R[2][0], R[2][1], R[2][2], move[2], 0, 0, 0, 1);
  }

  View.prototype.setMotion = function (t) {  // t in [0, 1]: the share of the motion shown
    var motion = this.data.motion;
    if (!motion || this.failed) return;
    this.motionAt = Math.min(Math.max(t, 0), 1);
    var m = new THREE.Matrix4(), self = this, touched = new Set();
    if (this.twists) {
      var s = this.motionAt * motion.end, tw = this.twists, ce = this.centres;
      motion.moving.forEach(function (block, b) {
        screw([tw[6 * b], tw[6 * b + 1], tw[6 * b + 2]], [tw[6 * b + 3], tw[6 * b + 4], tw[6 * b + 5]],
              [ce[3 * b], ce[3 * b + 1], ce[3 * b + 2]], s, m).multiply(self.placed[b]);
        self.place(block, m, touched);
      });
    } else {
      var x = this.motionAt * (motion.steps - 1), i = Math.min(Math.floor(x), motion.steps - 2), f = x - i;
      if (motion.steps < 2) { i = 0; f = 0; }
      var p = new THREE.Vector3(), q = new THREE.Quaternion();
      motion.moving.forEach(function (block, b) {
        var a = self.poses[i][b], c = self.poses[Math.min(i + 1, motion.steps - 1)][b];
        p.lerpVectors(a.p, c.p, f);
        q.slerpQuaternions(a.q, c.q, f);
        m.compose(p, q, a.s);
        self.place(block, m, touched);
      });
    }
    touched.forEach(function (mesh) { mesh.instanceMatrix.needsUpdate = true; mesh.computeBoundingSphere(); });
    if (this.slider && Number(this.slider.value) !== Math.round(this.motionAt * 1000)) {
      this.slider.value = String(Math.round(this.motionAt * 1000));
    }
    this.render();
  };

  View.prototype.place = function (block, matrix, touched) {  // a moving block's placement, and its edges
    var at = this.where[block], mesh = this.meshes[at[0]];
    mesh.setMatrixAt(at[1], matrix);
    touched.add(mesh);
    if (this.movingEdges[block]) this.movingEdges[block].matrix.copy(matrix);
  };

  View.prototype.blockMatrix = function (block) {  // the block's current placement (column-major, 16 numbers)
    var at = this.where[block], m = new THREE.Matrix4();
    this.meshes[at[0]].getMatrixAt(at[1], m);
    return m.toArray();
  };

  View.prototype.blockCentre = function (block) {  // the centre of the block's box, where it is now (scene units)
    var at = this.where[block], mesh = this.meshes[at[0]], m = new THREE.Matrix4(), c = new THREE.Vector3();
    if (!mesh.geometry.boundingBox) mesh.geometry.computeBoundingBox();
    mesh.geometry.boundingBox.getCenter(c);
    mesh.getMatrixAt(at[1], m);
    return c.applyMatrix4(m).toArray();
  };

  View.prototype.screenOf = function (x, y, z) {  // a world point's pixel on the canvas, from its top left
    var p = new THREE.Vector3(x, y, z).project(this.camera), box = this.renderer.domElement.getBoundingClientRect();
    return [(p.x + 1) / 2 * box.width, (1 - p.y) / 2 * box.height];
  };

  View.prototype.play = function (on) {
    var self = this;
    this.playing = on === undefined ? !this.playing : !!on;
    if (this.playButton) this.playButton.textContent = this.playing ? 'Pause' : 'Play';
    if (!this.playing) return;
    var last = null, direction = this.motionAt >= 1 ? -1 : 1, period = 2500;
    function tick(now) {
      if (!self.playing || self.disposed) return;
      if (last !== null) {
        var t = self.motionAt + direction * (now - last) / period;
        if (t >= 1 || t <= 0) direction = -direction;
        self.setMotion(t);
      }
      last = now;
      requestAnimationFrame(tick);
    }
    requestAnimationFrame(tick);
  };

  View.prototype.buildPanels = function () {
    var data = this.data, self = this;
    // the legend
    var legend = element('div', 'iv-legend');
    var title = element('div', 'iv-legend-title', 'Legend');
    legend.appendChild(title);
    function swatch(colour, words) {
      var row = element('div', 'iv-row');
      var box = element('span', 'iv-swatch');
      box.style.background = colour;
      row.appendChild(box);
      row.appendChild(element('span', '', words));
      legend.appendChild(row);
    }
    var present = new Set(), self = this;
    data.blocks['class'].forEach(function (c, block) {
      if (!self.frame.has(block) && !self.moving.has(block)) present.add(c);
    });
    data.classes.names.forEach(function (name, k) {
      if (present.has(k)) swatch(data.classes.colours[k % data.classes.colours.length], name);
    });
    if (data.blocks.frame.length) swatch(data.frame_colour, 'frame (fixed blocks)');
    if (data.motion) swatch(data.moving_colour, 'moving blocks');
    swatch('#ffd400', 'picked block');
    if (data.forces) {
      var ramp = element('div', 'iv-row');
      var bar = element('span', 'iv-ramp');
      ramp.appendChild(bar);
      ramp.appendChild(element('span', '', 'contact force, small to largest'));
      legend.appendChild(ramp);
    }
    this.root.appendChild(legend);

    // the tools
    var tools = element('div', 'iv-tools');
    function button(words, tip, action) {
      var b = element('button', 'iv-button', words);
      b.type = 'button';
      b.title = tip;
      b.addEventListener('click', action);
      tools.appendChild(b);
      return b;
    }
    button('Reset view', 'back to the first view (orbit: drag; zoom: wheel; pan: right-drag)', function () {
      self.home();
    });
    this.frameButton = button('Hide frame', 'show or hide the fixed blocks', function () {
      self.showFrame(!self.frameShown);
    });
    this.frameShown = true;
    this.pickButton = button('Pick frame', 'click blocks to add them to the frame or take them out; the matching '
                             + '--fixed list is shown to copy',
                             function () { self.setPickingFrame(!self.pickingFrame); });
    if (data.motion) {
      this.playButton = button('Play', 'play or pause the motion', function () { self.play(); });
      var slider = this.slider = element('input', 'iv-slider');
      slider.type = 'range';
      slider.min = '0';
      slider.max = '1000';
      slider.value = '0';
      slider.title = 'the motion: ' + data.motion.caption;
      slider.setAttribute('aria-label', 'motion');
      slider.addEventListener('input', function () {
        self.play(false);
        self.setMotion(Number(slider.value) / 1000);
      });
      tools.appendChild(slider);
      tools.appendChild(element('span', 'iv-caption', data.motion.kind === 'finite' ? 'finite motion'
        : data.motion.kind === 'collapse' ? 'collapse' : 'first-order motion'));
    }
    this.root.appendChild(tools);

    // what was picked, and the frame being picked
    var info = this.info = element('div', 'iv-info');
    info.appendChild(element('div', 'iv-hint', 'Click a block to see its index, label, volume and contacts.'));
    this.root.appendChild(info);
    var fixed = this.fixedPanel = element('div', 'iv-fixed');
    fixed.hidden = true;
    fixed.appendChild(element('div', 'iv-hint', 'Click blocks to add them to the frame or take them out.'));
    var line = element('div', 'iv-row');
    var field = this.fixedField = element('input', 'iv-fixed-field');
    field.readOnly = true;
    field.setAttribute('aria-label', '--fixed');
    line.appendChild(field);
    var copy = element('button', 'iv-button', 'Copy');
    copy.type = 'button';
    copy.addEventListener('click', function () { self.copyFixed(); });
    line.appendChild(copy);
    fixed.appendChild(line);
    this.root.appendChild(fixed);
    this.updateFixed();
  };

  View.prototype.showFrame = function (on) {
    var self = this;
    this.frameShown = on;
    this.frameButton.textContent = on ? 'Hide frame' : 'Show frame';
    var hidden = new THREE.Matrix4().makeScale(0, 0, 0), m = new THREE.Matrix4();
    this.data.blocks.frame.forEach(function (block) {
      var at = self.where[block];
      if (on) m.fromArray(self.matrices, 16 * block);
      self.meshes[at[0]].setMatrixAt(at[1], on ? m : hidden);
      self.meshes[at[0]].instanceMatrix.needsUpdate = true;
    });
    this.render();
  };

  View.prototype.fixedText = function () {
    return '--fixed ' + (this.frame.size ? ranges(Array.from(this.frame)) : '""');
  };

  View.prototype.updateFixed = function () {
    this.fixedField.value = this.fixedText();
  };

  View.prototype.copyFixed = function () {
    var text = this.fixedText(), field = this.fixedField;
    field.select();
    if (navigator.clipboard && window.isSecureContext) {
      navigator.clipboard.writeText(text).catch(function () { document.execCommand('copy'); });
    } else {
      document.execCommand('copy');
    }
  };

  View.prototype.setPickingFrame = function (on) {
    this.pickingFrame = on;
    this.pickButton.classList.toggle('iv-on', on);
    this.pickButton.textContent = on ? 'Done picking' : 'Pick frame';
    this.fixedPanel.hidden = !on;
  };

  View.prototype.bindPicking = function () {
    var self = this, canvas = this.renderer.domElement, down = null;
    var raycaster = new THREE.Raycaster(), pointer = new THREE.Vector2();
    canvas.addEventListener('pointerdown', function (e) { down = [e.clientX, e.clientY]; });
    canvas.addEventListener('pointerup', function (e) {
      if (!down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 4) return;  // a drag orbits
      var box = canvas.getBoundingClientRect();
      pointer.set((e.clientX - box.left) / box.width * 2 - 1, -(e.clientY - box.top) / box.height * 2 + 1);
      raycaster.setFromCamera(pointer, self.camera);
      var hits = raycaster.intersectObjects(self.meshes, false);
      self.pick(hits.length ? hits[0].object.userData.blocks[hits[0].instanceId] : -1);
    });
  };

  View.prototype.pick = function (block) {
    var data = this.data, blocks = data.blocks;
    if (block >= 0 && this.pickingFrame) {
      if (this.frame.has(block)) this.frame.delete(block); else this.frame.add(block);
      this.updateFixed();
    }
    this.selected = block;
    this.colourBlocks();
    var info = this.info;
    info.textContent = '';
    if (block < 0) {
      info.appendChild(element('div', 'iv-hint', 'Click a block to see its index, label, volume and contacts.'));
    } else {
      var neighbours = blocks.neighbours.slice(blocks.neighbour_start[block], blocks.neighbour_start[block + 1]);
      var role = this.frame.has(block) ? 'in the frame' : this.moving.has(block) ? 'moving' : 'free';
      var rows = [['block', String(block) + ' (' + role + ')'], ['label', blocks.label[block]],
                  ['class', data.classes.names[blocks['class'][block]]], ['volume', String(blocks.volume[block])],
                  ['contacts', neighbours.length + (neighbours.length ? ': ' + neighbours.slice(0, 24).join(', ')
                    + (neighbours.length > 24 ? ', ...' : '') : '') + ' (' + blocks.neighbour_source + ')']];
      var table = element('table', 'iv-table');
      rows.forEach(function (r) {
        var tr = element('tr');
        tr.appendChild(element('th', '', r[0]));
        tr.appendChild(element('td', '', r[1]));
        table.appendChild(tr);
      });
      info.appendChild(table);
    }
    this.render();
  };

  View.prototype.home = function () {  // the first view: from the front right, above, the whole assembly in sight
    var camera = this.camera, radius = this.data.size / 2;
    var vertical = camera.fov * Math.PI / 180, horizontal = 2 * Math.atan(Math.tan(vertical / 2) * camera.aspect);
    var distance = 1.08 * radius / Math.sin(Math.min(vertical, horizontal) / 2);
    var direction = new THREE.Vector3(0.5, -0.8, 0.75).normalize();
    camera.position.copy(direction.multiplyScalar(distance));
    this.controls.target.set(0, 0, 0);
    this.controls.update();
    this.moved = false;
    this.render();
  };

  View.prototype.resize = function () {
    if (this.failed || this.disposed) return;
    var width = Math.max(this.stage.clientWidth, 1), height = Math.max(this.stage.clientHeight, 1);
    this.renderer.setSize(width, height);
    this.camera.aspect = width / height;
    this.camera.updateProjectionMatrix();
    if (!this.moved) this.home(); else this.render();
  };

  View.prototype.render = function () {
    if (this.failed || this.disposed) return;
    this.renderer.render(this.scene, this.camera);
    this.frames++;
    if (registry.firstFrame === undefined) registry.firstFrame = performance.now();  // ms since the page began
  };

  View.prototype.stats = function () {
    var drawn = 0, frameDrawn = 0, self = this;
    this.meshes.forEach(function (mesh) { drawn += mesh.count; });
    this.frame.forEach(function (block) { if (self.where[block]) frameDrawn++; });
    return { blocks: drawn, frame: frameDrawn, moving: Array.from(this.moving), frames: this.frames,
             forces: this.data.forces ? this.data.forces.count : 0,
             motion: this.data.motion ? this.data.motion.kind : null, fixed: this.fixedText(),
             meshes: this.meshes.length };
  };

  View.prototype.dispose = function () {
    this.playing = false;
    this.disposed = true;
    if (this.observer) this.observer.disconnect();
    if (this.renderer) {
      this.scene.traverse(function (o) { if (o.geometry) o.geometry.dispose(); });
      this.renderer.dispose();
      this.renderer.forceContextLoss();
    }
    this.container.removeChild(this.root);
    var at = registry.views.indexOf(this);
    if (at >= 0) registry.views.splice(at, 1);
  };

  function mount(container, data) {
    var view = new View(container, data);
    registry.views.push(view);
    return view;
  }

  function sceneOf(container) {
    var source = document.getElementById(container.getAttribute('data-scene'));
    return JSON.parse(source.textContent);
  }

  function shown() {  // two animation frames after the first render: the picture has reached the screen
    requestAnimationFrame(function () {
      requestAnimationFrame(function () { if (registry.shown === undefined) registry.shown = performance.now(); });
    });
  }

  function mountAll() {  // every .iv-viewer at once (a single view)
    document.querySelectorAll('.iv-viewer').forEach(function (container) { mount(container, sceneOf(container)); });
    registry.ready = true;
    shown();
  }

  function mountLazily(live) {  // the gallery: a view when its entry scrolls near, at most `live` at a time
    var mounted = new Map(), visible = new Set();
    registry.mounted = 0;
    var observer = new IntersectionObserver(function (entries) {
      entries.forEach(function (entry) {
        if (entry.isIntersecting) visible.add(entry.target); else visible.delete(entry.target);
      });
      visible.forEach(function (container) {
        if (mounted.has(container)) return;
        mounted.set(container, mount(container, sceneOf(container)));
        registry.mounted++;
        shown();
        container.classList.add('iv-live');
      });
      Array.from(mounted.keys()).forEach(function (container) {  // the oldest out of sight go first
        if (mounted.size <= live || visible.has(container)) return;
        mounted.get(container).dispose();
        mounted.delete(container);
        container.classList.remove('iv-live');
      });
    }, { rootMargin: '300px 0px' });
    document.querySelectorAll('.iv-viewer').forEach(function (c) { observer.observe(c); });
    registry.ready = true;
  }

  window.addEventListener('error', function (e) { registry.errors.push(String(e.message)); });
  window.InterlockViewer = { mount: mount, mountAll: mountAll, mountLazily: mountLazily, ranges: ranges };
})();
