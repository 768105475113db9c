/* springlab's exact solution, tolerance and verdict for the one-mode oscillator, in JavaScript.
 *
 * Ports, operation for operation, of the Python that decides a run's verdict:
 *   springlab/exact/analytic.py   free_response, step_response (_fundamental, _unit_step_displacement)
 *   springlab/runs/compare.py     predicted_error, tolerances, mode_factor, estimate_range
 *   springlab/runs/run.py         evaluate (errors, blow-up ratio, verdict)
 * tests/render/test_interactive.py compares them with the Python on a grid of parameters. A classic script
 * (the page opens from file://): it defines springlabExact, and module.exports under node.
 */
(function (root) {
  'use strict';

  var SERIES_Z = 1e-3;
  var STEP_SERIES_TERMS = 30;
  var CRITICAL_TOLERANCE = 1e-12;
  var EPS = 2.220446049250313e-16;
  var SAFETY = 2.0;
  var ROUNDOFF_PER_STEP = 100 * EPS;
  var CERTIFIED_CAP = 1e-2;
  var BLOWUP_RATIO = 1e3;
  var ORDERS = { euler: 1, implicit: 1, implicitfast: 1, rk4: 4, discrete: 1 };
  var VERDICTS = {
    PASS: 'PASS',
    FAIL: 'FAIL',
    NOT_VALIDATED: 'not validated: outside the range of the error estimate',
    DIVERGED: 'diverged',
  };

  function errorConstant(integrator) {
    return ORDERS[integrator] === 4 ? 1.0 / 120.0 : 0.5;
  }

  // Python's round(): halves to even (check_timing, mode_factor)
  function roundHalfEven(x) {
    var r = Math.round(x);
    if (Math.abs(x % 1) === 0.5 && r % 2 !== 0) r -= 1;
    return r;
  }

  function constants(m, k, d) {
    var sigma = d / (2.0 * m);
    var wn2 = k / m;
    var wn = Math.sqrt(wn2);
    var b2 = (wn - sigma) * (wn + sigma);
    return { sigma: sigma, wn2: wn2, b2: b2, gamma: Math.sqrt(Math.abs(b2)) };
  }

  function overdampedRoots(sigma, wn2, gamma) {
    return { fast: -(sigma + gamma), slow: -wn2 / (sigma + gamma) + 0.0 };
  }

  function dampingRatio(m, k, d) {
    if (d === 0.0) return 0.0;
    if (k === 0.0) return Infinity;
    var km = k * m;
    var root = km > 0.0 && km < Infinity ? Math.sqrt(km) : Math.sqrt(k) * Math.sqrt(m);
    return d / (2.0 * root);
  }

  function regime(m, k, d) {
    var zeta = dampingRatio(m, k, d);
    if (d === 0.0) return 'undamped';
    if (Math.abs(zeta - 1.0) <= CRITICAL_TOLERANCE) return 'critical';
    return zeta < 1.0 ? 'underdamped' : 'overdamped';
  }

  // analytic._fundamental at one time t [s]
  function fundamental(t, c) {
    var sigma = c.sigma, wn2 = c.wn2, b2 = c.b2, gamma = c.gamma;
    var z = gamma * t;
    var C = NaN, S = NaN, E = Math.exp(-sigma * t), expBranch = false;
    if (z < SERIES_Z) {
      var u = Math.abs(z * z) * (b2 < 0 || Object.is(b2, -0) ? -1 : 1);
      C = 1.0 - (u / 2.0) * (1.0 - (u / 12.0) * (1.0 - (u / 30.0) * (1.0 - u / 56.0)));
      S = t * (1.0 - (u / 6.0) * (1.0 - (u / 20.0) * (1.0 - (u / 42.0) * (1.0 - u / 72.0))));
    }
    if (b2 > 0.0) {
      if (!(z < SERIES_Z)) {
        C = Math.cos(gamma * t);
        S = Math.sin(gamma * t) / gamma;
      }
    } else {
      if (!(z < SERIES_Z) && z <= 1.0) {
        C = Math.cosh(z);
        S = Math.sinh(z) / gamma;
      }
      expBranch = z > 1.0;
    }
    var P, Q, dP, dQ;
    if (!expBranch) {
      P = E * (C + sigma * S);
      Q = E * S;
      dP = -wn2 * (E * S);
      dQ = E * (C - sigma * S);
      if (E === 0.0) P = Q = dP = dQ = 0.0;
    } else {
      var r = overdampedRoots(sigma, wn2, gamma);
      var es = Math.exp(r.slow * t), ef = Math.exp(r.fast * t), twoG = 2.0 * gamma;
      P = ((sigma + gamma) * es + r.slow * ef) / twoG;
      Q = (es - ef) / twoG;
      dP = -wn2 * ((es - ef) / twoG);
      dQ = (r.slow * es - r.fast * ef) / twoG;
    }
    return { P: P, Q: Q, dP: dP, dQ: dQ, E: E, C: C, S: S, expBranch: expBranch };
  }

  var stepSeries = {};
  function stepCoefficients(s_, w_) {
    var key = s_ + ',' + w_;
    if (stepSeries[key]) return stepSeries[key];
    var c = new Array(STEP_SERIES_TERMS).fill(0);
    c[0] = 1.0;
    for (var j = 1; j < STEP_SERIES_TERMS; j++) {
      var prev2 = j >= 2 ? c[j - 2] : 0.0;
      c[j] = -(s_ * (j + 1) * c[j - 1] + w_ * prev2) / ((j + 2) * (j + 1));
    }
    stepSeries = {};
    stepSeries[key] = c;
    return c;
  }

  // analytic._unit_step_displacement at one time t [s]
  function unitStep(t, m, k, c, f) {
    var sigma = c.sigma, wn2 = c.wn2, b2 = c.b2, gamma = c.gamma;
    var wn = Math.sqrt(wn2);
    var lam = Math.max(sigma, wn);
    if (lam * t <= 1.0) {
      if (lam === 0.0) return (t * t) / (2.0 * m);
      var coef = stepCoefficients((2.0 * sigma) / lam, wn2 / (lam * lam));
      var tau = lam * t;
      var acc = coef[coef.length - 1];
      for (var j = coef.length - 2; j >= 0; j--) acc = acc * tau + coef[j];
      return ((t * t) / (2.0 * m)) * acc;
    }
    if (f.P <= 0.5) return (1.0 - f.P) / k;
    if (b2 < 0.0 && gamma * t >= 0.5) {
      var r = overdampedRoots(sigma, wn2, gamma);
      var phiSlow = r.slow === 0.0 ? t : Math.expm1(r.slow * t) / r.slow;
      var phiFast = Math.expm1(r.fast * t) / r.fast;
      return (phiSlow - phiFast) / (2.0 * m * gamma);
    }
    var z = gamma * t, cm;
    if (z < SERIES_Z) {
      var u = Math.abs(z * z) * (b2 < 0 ? -1 : 1);
      cm = (-u / 2.0) * (1.0 - (u / 12.0) * (1.0 - (u / 30.0) * (1.0 - u / 56.0)));
    } else if (b2 > 0.0) {
      cm = -2.0 * Math.pow(Math.sin(z / 2.0), 2);
    } else {
      cm = 2.0 * Math.pow(Math.sinh(z / 2.0), 2);
    }
    return (-Math.expm1(-sigma * t) - f.E * (sigma * f.S) - f.E * cm) / k;
  }

  /* x(t) [m], v(t) [m/s] of m x'' + d x' + k x = force (constant from t = 0), x(0) = x0, v(0) = v0,
     at each time of `times`: analytic.step_response (free_response when force is 0). */
  function response(times, m, k, d, x0, v0, force) {
    var c = constants(m, k, d);
    var n = times.length, x = new Float64Array(n), v = new Float64Array(n);
    for (var i = 0; i < n; i++) {
      var t = times[i], f = fundamental(t, c), xi = 0.0, vi = 0.0;
      if (x0) { xi += x0 * f.P; vi += x0 * f.dP; }
      if (v0) { xi += v0 * f.Q; vi += v0 * f.dQ; }
      if (force) {
        xi += force * unitStep(t, m, k, c, f);
        vi += (force / m) * f.Q;
      }
      x[i] = xi;
      v[i] = vi;
    }
    return { x: x, v: v };
  }

  /* the exact x, v of p = {m, k, d, x0, v0, force, rest} at `times`: the response to F, or about a rest
     position the free response from x0 - rest, shifted (the car's Release.reference) */
  function reference(times, p) {
    if (p.rest === null || p.rest === undefined) return response(times, p.m, p.k, p.d, p.x0, p.v0, p.force);
    var free = response(times, p.m, p.k, p.d, p.x0 - p.rest, p.v0, 0);
    for (var i = 0; i < free.x.length; i++) free.x[i] = free.x[i] + p.rest;
    return free;
  }

  // -- the tolerance: compare.predicted_error and compare.tolerances for z = (x, v[, F]) --------------

  /* A of z = (x, v) or, with a constant input, z = (x, v, g): g = F with coupling 1/m (a force), or
     g = 1 with coupling k rest / m (a preloaded spring holding a load: springlab.exact.linear.generator_system) */
  function systemMatrix(m, k, d, generator) {
    var a = [[0, 1], [-(k / m), -(d / m)]];
    if (!generator) return a;
    return [[0, 1, 0], [-(k / m), -(d / m), generator.coupling], [0, 0, 0]];
  }

  function generatorOf(p) {
    if (p.rest !== null && p.rest !== undefined) return { value: 1, coupling: (p.k * p.rest) / p.m };
    if (p.force) return { value: p.force, coupling: 1 / p.m };
    return null;
  }

  function matmul(a, b) {
    var n = a.length, out = [];
    for (var i = 0; i < n; i++) {
      out.push([]);
      for (var j = 0; j < n; j++) {
        var s = 0;
        for (var l = 0; l < n; l++) s += a[i][l] * b[l][j];
        out[i].push(s);
      }
    }
    return out;
  }

  // numpy.linalg.matrix_power's order of products (binary powers), so round-off matches where it can
  function matrixPower(a, p) {
    var result = null, z = null, n = p;
    while (n > 0) {
      z = z === null ? a : matmul(z, z);
      var bit = n % 2;
      n = Math.floor(n / 2);
      if (bit) result = result === null ? z : matmul(result, z);
    }
    return result;
  }

  // nonzero eigenvalues {re, im} [1/s] of the system (compare.system_rates): the oscillator's two roots
  function rates(m, k, d) {
    var a = k / m, b = d / m, disc = (b / 2) * (b / 2) - a, out;
    if (disc < 0) {
      var im = Math.sqrt(-disc);
      out = [{ re: -b / 2, im: im }, { re: -b / 2, im: -im }];
    } else {
      var q = -(b / 2 + Math.sqrt(disc));
      out = [{ re: q, im: 0 }, { re: q === 0 ? 0 : a / q, im: 0 }];
    }
    var scale = Math.max(Math.hypot(out[0].re, out[0].im), Math.hypot(out[1].re, out[1].im), 1e-300);
    return out.filter(function (r) { return Math.hypot(r.re, r.im) > 1e-12 * scale; });
  }

  function tolerances(time, ref, m, k, d, generator, integrator, dt) {
    var order = ORDERS[integrator];
    var a = systemMatrix(m, k, d, generator);
    var ap = matrixPower(a, order + 1);
    var scale = errorConstant(integrator) * Math.pow(dt, order);
    var r = rates(m, k, d);
    var spectral = 0;
    r.forEach(function (x) { spectral = Math.max(spectral, Math.hypot(x.re, x.im)); });
    var rho = Math.max(spectral, 1.0 / Math.max(time[time.length - 1], 1e-300));
    var worst = 0;
    for (var i = 0; i < time.length; i++) {
      var z = generator ? [ref.x[i], ref.v[i], generator.value] : [ref.x[i], ref.v[i]];
      var ex = 0, ev = 0;
      for (var l = 0; l < z.length; l++) { ex += z[l] * ap[0][l]; ev += z[l] * ap[1][l]; }
      var elapsed = time[i] - time[0];
      worst = Math.max(worst, Math.hypot(scale * elapsed * ex, (scale * elapsed * ev) / rho));
    }
    var floor = ROUNDOFF_PER_STEP * (time.length - 1);
    var out = {};
    [['pos', ref.x, worst], ['vel', ref.v, worst * rho]].forEach(function (c) {
      var size = maxAbs(c[1]);
      var rel = size > 0 ? c[2] / size : c[2];
      out[c[0]] = Math.min(SAFETY * rel + floor, CERTIFIED_CAP);
    });
    return out;
  }

  function maxAbs(values) {
    var out = 0;
    for (var i = 0; i < values.length; i++) out = Math.max(out, Math.abs(values[i]));
    return out;
  }

  // -- the range of the estimate: compare.mode_factor and compare.estimate_range ----------------------

  function maxOverSteps(values, steps, peak) {
    var candidates = [1, steps, Math.min(Math.max(Math.floor(peak), 1), steps), Math.min(Math.max(Math.ceil(peak), 1), steps)];
    return Math.max.apply(null, candidates.map(values));
  }

  function modeFactor(rate, integrator, dt, duration) {
    var order = ORDERS[integrator];
    var steps = Math.max(1, roundHalfEven(duration / dt));
    var size = dt * Math.hypot(rate.re, rate.im);
    var decay = -rate.re * dt;
    var tail = size / (order + 2);
    if (tail >= 1.0) return Infinity;
    var kept = errorConstant(integrator) * Math.pow(size, order + 1);
    var local = (kept * Math.exp(decay)) / (1.0 - tail);
    var growth = Math.log1p(local);
    function whole(n) {
      var x = growth * n;
      if (x <= 0.0) return 0.0;
      var logExpm1 = x < 30.0 ? Math.log(Math.expm1(x)) : x + Math.log1p(-Math.exp(-x));
      return Math.exp(Math.min(-decay * n + logExpm1, 700.0));
    }
    var change = growth - decay, peak;
    if (change >= 0.0 || decay <= 0.0) peak = steps;
    else peak = Math.log(decay / -change) / growth;
    var numerator = maxOverSteps(whole, steps, peak);
    var denominator = maxOverSteps(function (n) { return n * kept * Math.exp(-decay * n); }, steps, decay > 0 ? 1.0 / decay : steps);
    if (denominator <= 0.0 || !isFinite(numerator)) return Infinity;
    return numerator / denominator;
  }

  function roundDown(value) {
    var unit = Math.pow(10, Math.floor(Math.log10(value)) - 1);
    var out = Number((Math.floor((value / unit) * (1 + 1e-12)) * unit).toExponential(1));
    return out <= value ? out : Number((out - unit).toExponential(1));
  }

  function estimateRange(rateList, integrator, dt, duration) {
    if (!rateList.length) return { inside: true, factor: 1.0, largestDt: Infinity };
    function worst(h) {
      var best = -Infinity;
      rateList.forEach(function (r) { best = Math.max(best, modeFactor(r, integrator, h, duration)); });
      return best;
    }
    var factor = worst(dt), inside = factor <= SAFETY;
    var low = inside ? dt : dt / 10.0, high = inside ? 10.0 * dt : dt;
    while (worst(high) <= SAFETY && high < dt * 1e12) { low = high; high = 10.0 * high; }
    while (worst(low) > SAFETY && low > dt * 1e-12) { high = low; low = low / 10.0; }
    for (var i = 0; i < 24; i++) {
      var mid = Math.sqrt(low * high);
      if (worst(mid) <= SAFETY) low = mid; else high = mid;
    }
    return { inside: inside, factor: factor, largestDt: roundDown(low) };
  }

  /* The verdict of a finished run as springlab's run.evaluate states it.
     run: {time, x, v (Float64Arrays, MuJoCo's clock), blewUp (MuJoCo reset or non-finite state)};
     p: {m, k, d, x0, v0, force, rest}; returns {ref, errors {pos, vel}, maxError, tolerances, range, verdict}. */
  function judge(run, p, integrator, dt) {
    var ref = reference(run.time, p);
    var errors = {}, worst = 0;
    [['pos', run.x, ref.x], ['vel', run.v, ref.v]].forEach(function (c) {
      var abs = 0;
      for (var i = 0; i < c[1].length; i++) abs = Math.max(abs, Math.abs(c[1][i] - c[2][i]));
      if (isNaN(abs)) abs = NaN;
      var size = maxAbs(c[2]);
      errors[c[0]] = { maxAbs: abs, maxRel: size > 0 ? abs / size : abs };
      worst = isNaN(errors[c[0]].maxRel) || isNaN(worst) ? NaN : Math.max(worst, errors[c[0]].maxRel);
    });
    var out = { ref: ref, errors: errors, maxError: worst };
    if (run.blewUp || !isFinite(worst) || worst > BLOWUP_RATIO) {
      out.verdict = VERDICTS.DIVERGED;
      return out;
    }
    out.tolerances = tolerances(run.time, ref, p.m, p.k, p.d, generatorOf(p), integrator, dt);
    var span = run.time[run.time.length - 1] - run.time[0];
    out.range = estimateRange(rates(p.m, p.k, p.d), integrator, dt, Math.max(span, dt));
    var passed = errors.pos.maxRel <= out.tolerances.pos && errors.vel.maxRel <= out.tolerances.vel;
    out.verdict = !out.range.inside ? VERDICTS.NOT_VALIDATED : passed ? VERDICTS.PASS : VERDICTS.FAIL;
    return out;
  }

  var api = {
    ORDERS: ORDERS,
    VERDICTS: VERDICTS,
    roundHalfEven: roundHalfEven,
    dampingRatio: dampingRatio,
    regime: regime,
    response: response,
    reference: reference,
    generatorOf: generatorOf,
    rates: rates,
    tolerances: tolerances,
    modeFactor: modeFactor,
    estimateRange: estimateRange,
    judge: judge,
  };
  root.springlabExact = api;
  if (typeof module !== 'undefined' && module.exports) module.exports = api;
})(typeof globalThis !== 'undefined' ? globalThis : this);
