/* springlab interactive: one scenario with real MuJoCo (WebAssembly) in the page.
 *
 * A classic script (the page opens from file://, where Chromium refuses module scripts). It reads the
 * page's JSON config (springlab.render.interactive.page_config), loads MuJoCo (loadMujoco, from the
 * mujoco-js script beside the page), and on every slider move: writes the parameters into the scene's
 * MJCF text (config.edits, the same values Scene.edit sets in Python), recompiles, steps it as
 * springlab.sim.simulate does (state set at t = 0, control held, mj_step), judges the run with
 * springlabExact (springlab's closed form, tolerance and verdict), and redraws.
 * #result carries the run's settings and numbers as data- attributes for scripts and tests.
 */
(function () {
  'use strict';
  var config = JSON.parse(document.getElementById('springlab-config').textContent);
  var exact = window.springlabExact;
  var names = config.names;
  var formulas = {};

  // an InteractiveSpec formula (+ - * / over parameter names and g): JavaScript's precedence and left-to-right
  // order are Python's, so it rounds as springlab.scenes.capabilities.formula does
  function formula(text, params) {
    if (!/^[A-Za-z0-9_.+\-*\/() eE]*$/.test(text)) throw new Error('not a formula: ' + text);
    if (!formulas[text]) {
      var names = Object.keys(config.parameters).concat(['g']);
      formulas[text] = { names: names, fn: new Function(names.join(','), '"use strict"; return (' + text + ');') };
    }
    var f = formulas[text];
    return f.fn.apply(null, f.names.map(function (n) { return n === 'g' ? config.g : params[n]; }));
  }
  var state = {
    params: Object.assign({}, config.parameters),
    integrator: config.integrator,
    dt: config.dt,
    duration: config.duration,
  };
  var mj = null, model = null, modelXml = null, view = null, run = null, judged = null;
  var statusLine = document.getElementById('status');
  var resultLine = document.getElementById('result');

  function fmt(x, digits) {
    if (!isFinite(x)) return String(x);
    return Number(x).toPrecision(digits || 4);
  }

  // -- the model: the MJCF text with the parameters written in (config.edits) ------------------------

  function editedMjcf(params) {
    var doc = new DOMParser().parseFromString(config.mjcf, 'application/xml');
    config.edits.forEach(function (edit) {
      var found = null;
      doc.querySelectorAll(edit.tag).forEach(function (el) {
        if (el.getAttribute('name') === edit.name) found = el;
      });
      if (!found) throw new Error('no <' + edit.tag + ' name="' + edit.name + '"> in the MJCF');
      if (edit.child) {
        var child = null;
        for (var i = 0; i < found.children.length; i++) if (found.children[i].tagName === edit.child) child = found.children[i];
        if (!child) throw new Error('no <' + edit.child + '> in <' + edit.tag + ' name="' + edit.name + '">');
        found = child;
      }
      // String(x) is the shortest text that parses back to the same double: MuJoCo reads x exactly
      found.setAttribute(edit.attribute, String(formula(edit.value, params)));
    });
    return new XMLSerializer().serializeToString(doc);
  }

  function compile(xml) {
    if (xml === modelXml && model) return model;
    if (view) { view.delete(); view = null; }
    if (model) { model.delete(); model = null; }
    mj.FS.writeFile('/working/scene.xml', xml);
    model = mj.MjModel.loadFromXML('/working/scene.xml');
    modelXml = xml;
    view = new mj.MjData(model);
    return model;
  }

  function integratorIds() {
    var out = {};
    Object.keys(exact.ORDERS).forEach(function (name) {
      var entry = mj.mjtIntegrator['mjINT_' + name.toUpperCase()];
      if (entry !== undefined) out[name] = entry.value !== undefined ? entry.value : entry;
    });
    return out;
  }

  var BAD_WARNINGS = ['mjWARN_BADQPOS', 'mjWARN_BADQVEL', 'mjWARN_BADQACC'];

  function warningCount(data) {
    var total = 0;
    BAD_WARNINGS.forEach(function (name) {
      var entry = mj.mjtWarning && mj.mjtWarning[name];
      if (entry === undefined) return;
      var w = data.warning.get(entry.value !== undefined ? entry.value : entry);
      total += w.number;
      if (w.delete) w.delete();
    });
    return total;
  }

  // one run as springlab.sim.simulate makes it: state at t = 0, control held, `steps` calls of mj_step
  function simulate() {
    var p = state.params;
    var m = compile(editedMjcf(p));
    m.opt.integrator = integratorIds()[state.integrator];
    m.opt.timestep = state.dt;
    var d = new mj.MjData(m);
    var steps = exact.roundHalfEven(state.duration / state.dt);
    var time = new Float64Array(steps + 1), x = new Float64Array(steps + 1), v = new Float64Array(steps + 1);
    var qpos = d.qpos, qvel = d.qvel;
    var q = physical();
    qpos[config.qposadr] = q.x0;
    qvel[config.dofadr] = q.v0;
    if (config.actuator >= 0) d.ctrl[config.actuator] = q.force;
    time[0] = d.time; x[0] = qpos[config.qposadr]; v[0] = qvel[config.dofadr];
    var blewUp = false, started = performance.now(), n = steps;
    for (var i = 1; i <= steps; i++) {
      mj.mj_step(m, d);
      qpos = d.qpos; qvel = d.qvel; // views into WebAssembly memory: read them again after each call
      time[i] = d.time; x[i] = qpos[config.qposadr]; v[i] = qvel[config.dofadr];
      // MuJoCo resets a blown-up state silently (time jumps back); springlab calls that diverged
      if (!(time[i] > time[i - 1]) || !isFinite(x[i]) || !isFinite(v[i])) { blewUp = true; n = i; break; }
    }
    if (warningCount(d) > 0) blewUp = true;
    d.delete();
    var wall = performance.now() - started;
    return { time: time.subarray(0, n + 1), x: x.subarray(0, n + 1), v: v.subarray(0, n + 1), blewUp: blewUp, steps: n, wallMs: wall };
  }

  function physical() {
    var p = state.params;
    var f = config.formulas;
    return {
      m: p[names.mass], k: p[names.stiffness], d: p[names.damping],
      x0: formula(f.x0, p), v0: formula(f.v0, p),
      force: f.force ? formula(f.force, p) : 0,
      rest: f.rest ? formula(f.rest, p) : null,
    };
  }

  function update() {
    var started = performance.now();
    try {
      run = simulate();
      judged = exact.judge(run, physical(), state.integrator, state.dt);
    } catch (error) {
      statusLine.textContent = 'error: ' + error.message;
      throw error;
    }
    publish(performance.now() - started);
    draw();
  }

  // -- #result: the settings and numbers for scripts and tests -----------------------------------------

  var runs = 0;
  function publish(ms) {
    var verdict = judged.verdict;
    runs += 1;
    var final = run.x[run.x.length - 1];
    var attrs = {
      'data-scene': config.scene,
      'data-scenario': config.scenario,
      'data-integrator': state.integrator,
      'data-dt': String(state.dt),
      'data-duration': String(state.duration),
      'data-steps': String(run.steps),
      'data-final-position': String(final),
      'data-final-velocity': String(run.v[run.v.length - 1]),
      'data-max-error': String(judged.maxError),
      'data-tolerance': judged.tolerances ? String(Math.max(judged.tolerances.pos, judged.tolerances.vel)) : '',
      'data-verdict': verdict,
      'data-parameters': JSON.stringify(state.params),
      'data-compute-ms': ms.toFixed(2),
      'data-run': String(runs),
    };
    Object.keys(attrs).forEach(function (key) { resultLine.setAttribute(key, attrs[key]); });
    resultLine.className = verdict === 'PASS' ? 'PASS' : verdict === 'FAIL' ? 'FAIL' : verdict === 'diverged' ? 'diverged' : 'notvalidated';
    var p = physical();
    var zeta = exact.dampingRatio(p.m, p.k, p.d);
    var text;
    if (verdict === 'diverged') {
      text = 'diverged: ' + state.integrator + ' at dt = ' + fmt(state.dt, 3) + ' s blew up (error ' + fmt(judged.maxError, 3) +
        ' times the signal' + (run.blewUp ? ', MuJoCo reset the state' : '') + '); springlab run reports no result for it (exit 3)';
    } else {
      var tol = Math.max(judged.tolerances.pos, judged.tolerances.vel);
      text = verdict + ': max relative error ' + fmt(judged.maxError, 3) + ' against the exact solution, tolerance ' + fmt(tol, 3) +
        ' (' + state.integrator + ', order ' + exact.ORDERS[state.integrator] + ', dt = ' + fmt(state.dt, 3) + ' s)';
      if (!judged.range.inside) {
        text += '; dt is outside the range of the error estimate' + (isFinite(judged.range.largestDt) ? ' (dt <= ' + fmt(judged.range.largestDt, 2) + ' s is inside)' : '');
      }
    }
    resultLine.textContent = text;
    var rows = [
      ['regime', exact.regime(p.m, p.k, p.d) + ', ζ = ' + fmt(zeta, 4)],
      ['m, k, d', fmt(p.m) + ' kg, ' + fmt(p.k) + ' N/m, ' + fmt(p.d) + ' N s/m'],
      ['x(0), v(0)' + (p.force ? ', F' : ''), fmt(p.x0) + ' m, ' + fmt(p.v0) + ' m/s' + (p.force ? ', ' + fmt(p.force) + ' N' : '') + (p.rest !== null ? ' (at rest: ' + fmt(p.rest) + ' m)' : '')],
      ['steps', run.steps + ' of dt = ' + fmt(state.dt, 4) + ' s (' + state.duration + ' s), ' + fmt(run.wallMs, 3) + ' ms in MuJoCo, ' + fmt(ms, 3) + ' ms with the verdict'],
      ['final x', String(run.x[run.x.length - 1]) + ' m (exact ' + String(judged.ref.x[judged.ref.x.length - 1]) + ' m)'],
      ['max error', 'position ' + fmt(judged.errors.pos.maxRel, 3) + ', velocity ' + fmt(judged.errors.vel.maxRel, 3) + ' (relative)'],
    ];
    if (judged.tolerances) rows.push(['tolerance', 'position ' + fmt(judged.tolerances.pos, 3) + ', velocity ' + fmt(judged.tolerances.vel, 3) + ' (2 × C h^p t |A^(p+1) z| + 100 eps per step)']);
    var table = document.getElementById('numbers');
    table.innerHTML = '';
    rows.forEach(function (r) {
      var tr = table.insertRow(), a = tr.insertCell(), b = tr.insertCell();
      a.textContent = r[0]; b.textContent = r[1];
    });
  }

  // -- the controls -------------------------------------------------------------------------------------

  var controls = {};
  var rebuildQueued = false;
  function queue() {
    if (rebuildQueued) return;
    rebuildQueued = true;
    requestAnimationFrame(function () { rebuildQueued = false; update(); });
  }

  function slider(id, label, min, max, step, value, log, onInput, show) {
    var wrap = document.createElement('label');
    var out = document.createElement('output');
    var input = document.createElement('input');
    input.type = 'range'; input.id = id; input.min = String(min); input.max = String(max); input.step = String(step);
    input.value = String(log ? Math.log10(value) : value);
    wrap.textContent = label + ' ';
    wrap.appendChild(out);
    wrap.appendChild(input);
    out.textContent = show(value);
    input.addEventListener('input', function () {
      var raw = Number(input.value);
      var v = log ? Math.pow(10, raw) : raw;
      onInput(v);
      out.textContent = show(v);
      queue();
    });
    controls[id] = { input: input, output: out, show: show };
    return wrap;
  }

  function setDamping() {
    var p = state.params;
    p[names.damping] = 2 * state.zeta * Math.sqrt(p[names.stiffness] * p[names.mass]);
  }

  function buildControls() {
    var box = document.getElementById('controls');
    var p = state.params;
    state.zeta = exact.dampingRatio(p[names.mass], p[names.stiffness], p[names.damping]);
    var m0 = p[names.mass], k0 = p[names.stiffness];
    // a decade either side, or the range the scene declares (where it stays inside its model)
    function bounds(name, value) {
      var r = config.ranges[name] || [value / 10, value * 10];
      return [Math.log10(r[0]), Math.log10(r[1])];
    }
    var mb = bounds(names.mass, m0), kb = bounds(names.stiffness, k0);
    box.appendChild(slider('zeta', 'damping ratio ζ =', 0, Math.max(2, Math.ceil(state.zeta)), 0.01, state.zeta, false,
      function (v) { state.zeta = v; setDamping(); }, function (v) { return fmt(v, 3); }));
    box.appendChild(slider('mass', 'mass m [kg] =', mb[0], mb[1], 0.01, m0, true,
      function (v) { p[names.mass] = v; setDamping(); }, function (v) { return fmt(v, 3); }));
    box.appendChild(slider('stiffness', 'stiffness k [N/m] =', kb[0], kb[1], 0.01, k0, true,
      function (v) { p[names.stiffness] = v; setDamping(); }, function (v) { return fmt(v, 3); }));
    box.appendChild(slider('dt', 'timestep dt [s] =', Math.log10(config.dtRange[0]), Math.log10(config.dtRange[1]), 0.01, state.dt, true,
      function (v) { state.dt = v; }, function (v) { return fmt(v, 3); }));
    var wrap = document.createElement('label');
    wrap.textContent = 'integrator ';
    var select = document.createElement('select');
    select.id = 'integrator';
    Object.keys(integratorIds()).forEach(function (name) {
      var option = document.createElement('option');
      option.value = name; option.textContent = name + ' (order ' + exact.ORDERS[name] + ')';
      if (name === state.integrator) option.selected = true;
      select.appendChild(option);
    });
    select.addEventListener('input', function () { state.integrator = select.value; queue(); });
    wrap.appendChild(select);
    box.appendChild(wrap);
    var reset = document.createElement('button');
    reset.type = 'button'; reset.id = 'reset'; reset.textContent = 'initial settings (springlab run ' + config.scene + ' ' + config.scenario + ')';
    reset.addEventListener('click', function () {
      state.params = Object.assign({}, config.parameters);
      state.integrator = config.integrator; state.dt = config.dt;
      box.innerHTML = ''; buildControls(); update();
    });
    box.appendChild(reset);
  }

  // -- drawing: x(t), phase plane, error, and the 3D view from the model's geoms ------------------------

  var SUPERSCRIPT = { '-': '\u207b', 0: '\u2070', 1: '\u00b9', 2: '\u00b2', 3: '\u00b3', 4: '\u2074', 5: '\u2075', 6: '\u2076', 7: '\u2077', 8: '\u2078', 9: '\u2079' };

  // a log10 axis's end labelled as the power it is: 10⁻¹⁷, never the bare exponent -17
  function power(k) {
    return '10' + String(Math.round(k)).split('').map(function (c) { return SUPERSCRIPT[c]; }).join('');
  }

  // the frame and its end labels (yLabel formats the y ends, fmt by default); the labels are kept in the
  // canvas's data-x-labels and data-y-labels, and the lines drawn through the map stay inside the frame
  function axes(ctx, w, h, xr, yr, pad, yLabel) {
    ctx.clearRect(0, 0, w, h);
    ctx.strokeStyle = '#bbb'; ctx.lineWidth = 1;
    ctx.strokeRect(pad, 8, w - pad - 8, h - pad - 8);
    ctx.fillStyle = '#555'; ctx.font = '11px sans-serif';
    var label = yLabel || function (y) { return fmt(y, 3); };
    var ys = [label(yr[0]), label(yr[1])], xs = [fmt(xr[0], 3), fmt(xr[1], 3)];
    ctx.fillText(ys[1], 2, 16); ctx.fillText(ys[0], 2, h - pad);
    ctx.fillText(xs[0], pad, h - pad + 14); ctx.fillText(xs[1], w - 50, h - pad + 14);
    ctx.canvas.dataset.xLabels = JSON.stringify(xs);
    ctx.canvas.dataset.yLabels = JSON.stringify(ys);
    var map = function (x, y) {
      return [pad + ((x - xr[0]) / (xr[1] - xr[0] || 1)) * (w - pad - 8), 8 + (1 - (y - yr[0]) / (yr[1] - yr[0] || 1)) * (h - pad - 8)];
    };
    map.frame = [pad, 8, w - pad - 8, h - pad - 8];
    return map;
  }

  function line(ctx, map, xs, ys, color, dash) {
    ctx.save();
    ctx.beginPath(); ctx.rect(map.frame[0], map.frame[1], map.frame[2], map.frame[3]); ctx.clip();  // a diverged run stays in its frame
    ctx.strokeStyle = color; ctx.setLineDash(dash || []); ctx.lineWidth = 1.5;
    ctx.beginPath();
    var stride = Math.max(1, Math.floor(xs.length / 2000));
    for (var i = 0; i < xs.length; i += stride) {
      var p = map(xs[i], ys[i]);
      if (!isFinite(p[1])) continue;
      if (i === 0) ctx.moveTo(p[0], p[1]); else ctx.lineTo(p[0], p[1]);
    }
    ctx.stroke(); ctx.setLineDash([]);
    ctx.restore();
  }

  function range(values, extra) {
    var lo = Infinity, hi = -Infinity;
    [values, extra].forEach(function (vs) {
      if (!vs) return;
      for (var i = 0; i < vs.length; i++) if (isFinite(vs[i])) { lo = Math.min(lo, vs[i]); hi = Math.max(hi, vs[i]); }
    });
    if (!isFinite(lo)) return [-1, 1];
    var pad = (hi - lo) * 0.05 || Math.abs(hi) * 0.05 || 1;
    return [lo - pad, hi + pad];
  }

  var cursor = null;

  function drawPlots() {
    var ref = judged.ref;
    var c = document.getElementById('xt'), ctx = c.getContext('2d');
    var diverged = judged.verdict === 'diverged';
    var map = axes(ctx, c.width, c.height, [0, state.duration], range(ref.x, diverged ? null : run.x), 44);
    line(ctx, map, run.time, ref.x, '#888', [5, 4]);
    line(ctx, map, run.time, run.x, '#c0392b');
    if (cursor !== null) {
      var q = map(run.time[cursor], run.x[cursor]);
      ctx.fillStyle = '#c0392b'; ctx.beginPath(); ctx.arc(q[0], q[1], 4, 0, 7); ctx.fill();
    }
    c = document.getElementById('phase'); ctx = c.getContext('2d');
    map = axes(ctx, c.width, c.height, range(ref.x, diverged ? null : run.x), range(ref.v, diverged ? null : run.v), 44);
    line(ctx, map, ref.x, ref.v, '#888', [5, 4]);
    line(ctx, map, run.x, run.v, '#2c6fbb');
    c = document.getElementById('error'); ctx = c.getContext('2d');
    var err = new Float64Array(run.x.length);
    for (var i = 0; i < err.length; i++) err[i] = Math.log10(Math.abs(run.x[i] - ref.x[i]) + 1e-300);
    var lo = -17, hi = 1;
    for (i = 0; i < err.length; i++) if (isFinite(err[i])) hi = Math.max(hi, err[i]);
    map = axes(ctx, c.width, c.height, [0, state.duration], [lo, Math.min(Math.ceil(hi), 20)], 44, power);
    line(ctx, map, run.time, err, '#8e44ad');
    if (judged.tolerances) {
      var size = 0;
      for (i = 0; i < ref.x.length; i++) size = Math.max(size, Math.abs(ref.x[i]));
      var level = Math.log10(judged.tolerances.pos * size);
      var a = map(0, level), b = map(state.duration, level);
      ctx.strokeStyle = '#27ae60'; ctx.setLineDash([3, 3]); ctx.beginPath(); ctx.moveTo(a[0], a[1]); ctx.lineTo(b[0], b[1]); ctx.stroke(); ctx.setLineDash([]);
    }
  }

  var GEOM = { PLANE: 0, SPHERE: 2, CAPSULE: 3, ELLIPSOID: 4, CYLINDER: 5, BOX: 6 };

  function cameraOf(d) {
    var id = config.camera >= 0 ? config.camera : 0;
    var pos = d.cam_xpos, mat = d.cam_xmat;
    return {
      pos: [pos[3 * id], pos[3 * id + 1], pos[3 * id + 2]],
      mat: Array.prototype.slice.call(mat, 9 * id, 9 * id + 9),
      fovy: model.cam_fovy[id],
    };
  }

  function projector(cam, w, h) {
    var f = (h / 2) / Math.tan((cam.fovy * Math.PI) / 360);
    var R = cam.mat;
    return function (p) {
      var dx = p[0] - cam.pos[0], dy = p[1] - cam.pos[1], dz = p[2] - cam.pos[2];
      var cx = R[0] * dx + R[3] * dy + R[6] * dz, cy = R[1] * dx + R[4] * dy + R[7] * dz, cz = R[2] * dx + R[5] * dy + R[8] * dz;
      var depth = -cz;
      return [w / 2 + (f * cx) / depth, h / 2 - (f * cy) / depth, depth];
    };
  }

  function colorOf(g) {
    var mat = model.geom_matid[g], rgba = mat >= 0 ? model.mat_rgba : model.geom_rgba, at = 4 * (mat >= 0 ? mat : g);
    return [rgba[at], rgba[at + 1], rgba[at + 2], rgba[at + 3]];
  }

  function shade(rgba, light) {
    var s = 0.45 + 0.55 * light;
    return 'rgba(' + Math.round(255 * Math.min(1, rgba[0] * s)) + ',' + Math.round(255 * Math.min(1, rgba[1] * s)) + ',' + Math.round(255 * Math.min(1, rgba[2] * s)) + ',' + rgba[3] + ')';
  }

  // a geom as polygons of its surface: boxes exactly, cylinders and capsules as 16-sided prisms
  function geomFaces(g, d, faces, cam) {
    var type = model.geom_type[g];
    var size = [model.geom_size[3 * g], model.geom_size[3 * g + 1], model.geom_size[3 * g + 2]];
    var c = [d.geom_xpos[3 * g], d.geom_xpos[3 * g + 1], d.geom_xpos[3 * g + 2]];
    var R = Array.prototype.slice.call(d.geom_xmat, 9 * g, 9 * g + 9);
    var rgba = colorOf(g);
    if (rgba[3] === 0) return;
    function world(l) {
      return [c[0] + R[0] * l[0] + R[1] * l[1] + R[2] * l[2], c[1] + R[3] * l[0] + R[4] * l[1] + R[5] * l[2], c[2] + R[6] * l[0] + R[7] * l[1] + R[8] * l[2]];
    }
    var ring = [];
    if (type === GEOM.BOX) {
      ring = [[1, 1], [-1, 1], [-1, -1], [1, -1]].map(function (q) { return [q[0] * size[0], q[1] * size[1]]; });
    } else if (type === GEOM.CYLINDER || type === GEOM.CAPSULE) {
      for (var i = 0; i < 16; i++) ring.push([size[0] * Math.cos((i * Math.PI) / 8), size[0] * Math.sin((i * Math.PI) / 8)]);
      size = [size[0], size[0], type === GEOM.CAPSULE ? size[1] + size[0] : size[1]];
    } else if (type === GEOM.SPHERE || type === GEOM.ELLIPSOID) {
      faces.push({ sphere: true, centre: c, radius: size[0], rgba: rgba, depth: dist(c, cam.pos) });
      return;
    } else {
      return; // planes, height fields and meshes: not drawn
    }
    var h = type === GEOM.BOX ? size[2] : size[2];
    var top = ring.map(function (q) { return world([q[0], q[1], h]); });
    var bottom = ring.map(function (q) { return world([q[0], q[1], -h]); });
    function add(poly, normal) { faces.push({ poly: poly, normal: normal, rgba: rgba, depth: dist(centroid(poly), cam.pos) }); }
    add(top, [R[2], R[5], R[8]]);
    add(bottom.slice().reverse(), [-R[2], -R[5], -R[8]]);
    for (var j = 0; j < ring.length; j++) {
      var k = (j + 1) % ring.length;
      var mid = [(ring[j][0] + ring[k][0]) / 2, (ring[j][1] + ring[k][1]) / 2];
      var n = world([mid[0], mid[1], 0]);
      add([top[j], top[k], bottom[k], bottom[j]], [n[0] - c[0], n[1] - c[1], n[2] - c[2]]);
    }
  }

  function dist(a, b) { return Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }
  function centroid(poly) {
    var s = [0, 0, 0];
    poly.forEach(function (p) { s[0] += p[0]; s[1] += p[1]; s[2] += p[2]; });
    return [s[0] / poly.length, s[1] / poly.length, s[2] / poly.length];
  }

  var coilTurns = null;

  function site(d, id, offset) {
    return [d.site_xpos[3 * id] + offset[0], d.site_xpos[3 * id + 1] + offset[1], d.site_xpos[3 * id + 2] + offset[2]];
  }

  function basis(axis) {
    var len = Math.hypot(axis[0], axis[1], axis[2]) || 1, a = [axis[0] / len, axis[1] / len, axis[2] / len];
    var helper = Math.abs(a[2]) < 0.9 ? [0, 0, 1] : [1, 0, 0];
    var e1 = [a[1] * helper[2] - a[2] * helper[1], a[2] * helper[0] - a[0] * helper[2], a[0] * helper[1] - a[1] * helper[0]];
    var l1 = Math.hypot(e1[0], e1[1], e1[2]);
    e1 = [e1[0] / l1, e1[1] / l1, e1[2] / l1];
    var e2 = [a[1] * e1[2] - a[2] * e1[1], a[2] * e1[0] - a[0] * e1[2], a[0] * e1[1] - a[1] * e1[0]];
    return [e1, e2];
  }

  function drawSprings(ctx, d, project) {
    if (coilTurns === null) {
      coilTurns = config.springs.map(function (s) {
        var a = site(d, s.a, s.offset), b = site(d, s.b, s.offset);
        return Math.min(14, Math.max(4, Math.round(dist(a, b) / (2 * config.coilRadius * s.size))));
      });
    }
    config.springs.forEach(function (s, i) {
      var a = site(d, s.a, s.offset), b = site(d, s.b, s.offset);
      var axis = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], e = basis(axis), r = config.coilRadius * s.size;
      ctx.strokeStyle = 'rgba(' + s.rgba.slice(0, 3).map(function (x) { return Math.round(255 * x); }).join(',') + ',1)';
      ctx.lineWidth = 1.6; ctx.beginPath();
      var n = 24 * coilTurns[i];
      for (var j = 0; j <= n; j++) {
        var u = j / n, phi = 2 * Math.PI * coilTurns[i] * u;
        var p = [0, 1, 2].map(function (q) { return a[q] + u * axis[q] + r * (Math.cos(phi) * e[0][q] + Math.sin(phi) * e[1][q]); });
        var s2 = project(p);
        if (j === 0) ctx.moveTo(s2[0], s2[1]); else ctx.lineTo(s2[0], s2[1]);
      }
      ctx.stroke();
    });
    if (!(state.params[names.damping] > 0)) return; // no damping: no damper drawn (as in the videos)
    config.dampers.forEach(function (s) {
      var a = site(d, s.a, s.offset), b = site(d, s.b, s.offset);
      var mid = [0, 1, 2].map(function (q) { return (a[q] + b[q]) / 2; });
      var pa = project(a), pm = project(mid), pb = project(b);
      var f = Math.abs(pa[1] - project([a[0], a[1], a[2] + s.size])[1]) * 2 + 2;
      ctx.strokeStyle = 'rgba(' + s.rgba.slice(0, 3).map(function (x) { return Math.round(255 * x); }).join(',') + ',1)';
      ctx.lineCap = 'butt'; ctx.lineWidth = f; ctx.beginPath(); ctx.moveTo(pa[0], pa[1]); ctx.lineTo(pm[0], pm[1]); ctx.stroke();
      ctx.lineWidth = Math.max(1.5, f / 3); ctx.beginPath(); ctx.moveTo(pm[0], pm[1]); ctx.lineTo(pb[0], pb[1]); ctx.stroke();
    });
  }

  function drawScene(index) {
    var c = document.getElementById('scene3d'), ctx = c.getContext('2d');
    var d = view;
    d.qpos[config.qposadr] = run.x[index];
    mj.mj_forward(model, d);
    var cam = cameraOf(d), project = projector(cam, c.width, c.height);
    ctx.fillStyle = '#fafafa'; ctx.fillRect(0, 0, c.width, c.height);
    var faces = [];
    for (var g = 0; g < model.ngeom; g++) geomFaces(g, d, faces, cam);
    faces.sort(function (a, b) { return b.depth - a.depth; });
    var light = [0.3, -0.6, 0.75];
    faces.forEach(function (face) {
      if (face.sphere) {
        var p = project(face.centre), rad = ((c.height / 2) / Math.tan((cam.fovy * Math.PI) / 360)) * face.radius / p[2];
        ctx.fillStyle = shade(face.rgba, 0.8); ctx.beginPath(); ctx.arc(p[0], p[1], rad, 0, 7); ctx.fill();
        return;
      }
      var mid = centroid(face.poly), toCam = [cam.pos[0] - mid[0], cam.pos[1] - mid[1], cam.pos[2] - mid[2]];
      var n = face.normal, ln = Math.hypot(n[0], n[1], n[2]) || 1;
      if (n[0] * toCam[0] + n[1] * toCam[1] + n[2] * toCam[2] <= 0) return; // facing away
      var lit = Math.max(0, (n[0] * light[0] + n[1] * light[1] + n[2] * light[2]) / ln);
      ctx.fillStyle = shade(face.rgba, lit);
      ctx.beginPath();
      face.poly.forEach(function (p, i) { var s = project(p); if (i === 0) ctx.moveTo(s[0], s[1]); else ctx.lineTo(s[0], s[1]); });
      ctx.closePath(); ctx.fill();
    });
    drawSprings(ctx, d, project);
    ctx.fillStyle = '#333'; ctx.font = '12px sans-serif';
    ctx.fillText('t = ' + fmt(run.time[index], 3) + ' s   x = ' + fmt(run.x[index], 4) + ' m', 8, 16);
  }

  var playing = null;
  function draw() {
    cursor = null;
    drawPlots();
    drawScene(run.x.length - 1);
  }

  function play() {
    if (playing) cancelAnimationFrame(playing);
    var start = performance.now();
    function frame(now) {
      var t = (now - start) / 1000;
      if (t > state.duration) { playing = null; cursor = null; drawPlots(); drawScene(run.x.length - 1); return; }
      cursor = Math.min(run.x.length - 1, Math.round(t / state.dt));
      drawScene(cursor);
      drawPlots();
      playing = requestAnimationFrame(frame);
    }
    playing = requestAnimationFrame(frame);
  }

  // -- start ----------------------------------------------------------------------------------------------

  var loadStarted = performance.now();
  window.loadMujoco().then(function (module) {
    mj = module;
    mj.FS.mkdir('/working');
    mj.FS.mount(mj.MEMFS, { root: '.' }, '/working');
    var loaded = performance.now() - loadStarted;
    buildControls();
    update();
    statusLine.textContent = '';
    resultLine.setAttribute('data-load-ms', loaded.toFixed(0));
    document.getElementById('play').addEventListener('click', play);
    window.springlabPage = { state: state, update: update, editedMjcf: editedMjcf };
  }).catch(function (error) {
    statusLine.textContent = 'MuJoCo could not start in this browser: ' + error;
    resultLine.setAttribute('data-verdict', 'error');
  });
})();
