"""Stability limits of any model, per integrator: predicted from its modes, measured on its one-step map,
confirmed on the nonlinear model; and the constraint settings a timestep breaks.

Numerical instability, as measured here: at timestep dt the one-step map Phi(dt) (springlab.exact.linearize)
amplifies some mode more than the exact flow does, spectral radius
rho(Phi) > (1 + MAP_MARGIN) max(1, exp(sigma dt)), with sigma the largest growth rate of the
continuous linearization (0 unless the model is physically unstable: an upright pole *should* fall,
and that is no integrator's fault). MAP_MARGIN covers the finite differences: a Jordan block's
double eigenvalue 1 (a free body, an unsprung direction) moves by sqrt(error) ~ 1e-5.

The measured limit is the smallest such dt: a doubling scan from SCAN_START / |lambda|_max, then a
geometric bisection to a ratio of 1 + LIMIT_PRECISION.

The closed-form prediction from the modes (springlab.studies.audit.predict) seeds the measurement: it is
tried first as a bracket of the measured limit.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import mujoco
import numpy as np

from springlab.errors import DivergedError
from springlab.exact.constraints import ConstraintState, active_constraints, summarize_constraints
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import OperatingPoint
from springlab.sim.batch import Job, run_batched
from springlab.sim.simulate import BAD_WARNINGS, Setup, Trajectory, integrator_id, quiet_mujoco

from .predict import IMPLICIT_DAMPING_INTEGRATORS, explicit_stiffness, implicit_damping, predict

#: growth of the one-step map beyond the exact flow's that counts as numerical instability [-]
MAP_MARGIN = 1e-4
#: the scan starts at SCAN_START / |lambda|_max and doubles ...
SCAN_START = 0.01
#: ... up to SCAN_STOP / |lambda|_max (or SCAN_STOP_S without a mode) [s]
SCAN_STOP = 1e4
SCAN_STOP_S = 10.0
#: bisection down to this ratio between stable and unstable timesteps
LIMIT_PRECISION = 1e-4
#: a predicted limit p is first bracketed by [p / GUESS_BRACKET, p * GUESS_BRACKET]
GUESS_BRACKET = 1.01
#: confirmation runs at these fractions of the measured limit
CONFIRM_BELOW, CONFIRM_ABOVE = 0.98, 1.02
#: a confirmation run "grows" when its deviation from the unperturbed run grows GROWTH_SEEN x beyond the
#: exact flow's growth, and stays bounded when it does not; the run is long enough for the map to
#: predict GROWTH_TARGET x, within [CONFIRM_MIN_STEPS, CONFIRM_MAX_STEPS] steps
GROWTH_SEEN = 100.0
GROWTH_TARGET = 1e6
CONFIRM_MIN_STEPS, CONFIRM_MAX_STEPS = 200, 20_000
#: the confirmation perturbation, along the map's most unstable eigenvector [tangent-space units]
CONFIRM_SIZE = 1e-6


@dataclasses.dataclass(frozen=True)
class Limit:
    """One integrator's stability limit; `to_dict()` is its entry in audit.json's "stability".

    Attributes
    ----------
    integrator
        name.
    limit_dt_predicted_s
        closed-form limit from the modes [s] (None: no closed form, or no limit).
    limit_dt_measured_s
        from the measured one-step map [s] (None: stable over the whole scan, or the map was not used).
    confirmed
        whether runs confirm `limit_dt_s`: the nonlinear model stays bounded just below it and grows just
        above (None: no limit, nothing to confirm). An unconfirmed figure is never the reason a setting
        is called unstable.
    margin
        `limit_dt_s` / the model's own timestep [-] (None: no limit).
    detail
        how the limit was found and confirmed, for people.
    growth_per_step_above
        rho(Phi) / max(1, exp(sigma dt)) just above the map's limit [-] (None: not probed).
    limit_dt_s
        the audit's figure [s]: the map's when runs confirm it, else the brute-force one (`method`), else
        the map's unconfirmed one (None: no limit found).
    method
        what gave `limit_dt_s`: "linear map" (MuJoCo's one-step map, bisected), "nonlinear runs" (bisection
        of blow-up of runs from the audit's start, against a fine reference's speed) or "none".
    prediction
        "exact" (the closed form is the linearization's limit) or "estimate" (modes coupled, or the
        linear map is not meaningful at the operating point); None without a prediction.
    runs_bounded_dt_s, runs_blew_up_dt_s
        the brute force's bracket [s]: the largest timestep whose run stayed bounded and the smallest
        whose run blew up (None: not run, or none did).
    """

    integrator: str
    limit_dt_predicted_s: float | None
    limit_dt_measured_s: float | None
    confirmed: bool | None = None
    margin: float | None = None
    detail: str = ""
    growth_per_step_above: float | None = None
    limit_dt_s: float | None = None
    method: str = "linear map"
    prediction: str | None = None
    runs_bounded_dt_s: float | None = None
    runs_blew_up_dt_s: float | None = None

    @property
    def confirmed_limit_s(self) -> float | None:
        """`limit_dt_s` when runs confirm it, else None [s]: the only figure that may call a setting unstable."""
        return self.limit_dt_s if self.confirmed else None

    def to_dict(self) -> dict[str, Any]:
        """{"limit_dt_predicted_s", "limit_dt_measured_s", "confirmed", "margin", "detail", "limit_dt_s",
        "method", "prediction", "runs_bounded_dt_s", "runs_blew_up_dt_s"}."""
        return {
            "limit_dt_predicted_s": self.limit_dt_predicted_s,
            "limit_dt_measured_s": self.limit_dt_measured_s,
            "confirmed": self.confirmed,
            "margin": self.margin,
            "detail": self.detail,
            "limit_dt_s": self.limit_dt_s,
            "method": self.method,
            "prediction": self.prediction,
            "runs_bounded_dt_s": self.runs_bounded_dt_s,
            "runs_blew_up_dt_s": self.runs_blew_up_dt_s,
        }


@dataclasses.dataclass(frozen=True)
class ConstraintFlag:
    """A constraint whose solref time constant is shorter than 2 dt (`constraint_flags`).

    Attributes
    ----------
    element
        what it is, e.g. "geom 'floor'".
    timeconst_s
        its time constant [s].
    dt_limit_s
        timeconst / 2, the largest timestep that keeps it as written [s].
    """

    element: str
    timeconst_s: float
    dt_limit_s: float

    def to_dict(self) -> dict[str, Any]:
        """{"element", "timeconst_s", "dt_limit_s"}: its row in audit.json's "constraints_broken"."""
        return dataclasses.asdict(self)


class _MapProbe:
    """rho(Phi(dt)) relative to the exact flow's growth, per dt [s], for one integrator.

    For a physically stable model the exact flow grows nowhere, so the excess is rho(Phi) itself.
    With a physically unstable mode each eigenvalue mu of Phi is compared with exp(lambda dt) of the
    continuous mode its eigenvector lies along (largest coefficient in A's eigenvector basis), so an
    upright pole's fall does not hide a fast mode's numerical growth.
    """

    def __init__(self, at: ModelAtPoint, integrator: str):
        self.at, self.integrator = at, integrator
        linear = at.linear
        self.sigma = linear.max_growth_rate
        self.scratch = at.workspace  # one copy of the model for every map at this point
        self.basis = None
        if linear.physically_unstable:
            values, vectors = linear.eigenvectors
            self.rates = np.maximum(values.real, 0.0)
            self.basis = np.linalg.pinv(vectors)

    def map(self, dt: float) -> np.ndarray:
        return self.at.one_step_map(self.integrator, dt, self.scratch)

    def excess(self, dt: float, phi: np.ndarray | None = None) -> tuple[float, np.ndarray | None, float]:
        """(max |mu| / exact growth of its mode [-], that mu's eigenvector, that |mu| [-]); the first > 1 +
        MAP_MARGIN is numerical growth."""
        phi = self.map(dt) if phi is None else phi
        if not np.isfinite(phi).all():
            return math.inf, None, math.inf
        if not phi.size:
            return 0.0, None, 0.0
        values, vectors = np.linalg.eig(phi)
        if self.basis is None:
            ratios = np.abs(values)
        else:
            modes = np.argmax(np.abs(self.basis @ vectors), axis=0)
            ratios = np.abs(values) * np.exp(-self.rates[modes] * dt)  # no overflow for fast physical growth
        worst = int(np.argmax(ratios))
        return float(ratios[worst]), vectors[:, worst], float(np.abs(values[worst]))

    def unstable(self, dt: float) -> bool:
        return self.excess(dt)[0] > 1 + MAP_MARGIN


def measured_limit(
    at: ModelAtPoint,
    integrator: str,
    scale_s: float,
    stop_s: float,
    guess_s: float | None = None,
) -> float | None:
    """The smallest dt [s] at which `integrator`'s measured one-step map grows (module docstring), or None.

    scale_s: the model's fastest time scale 1/|lambda|_max [s] (or its own timestep without a mode);
    stop_s: the largest dt worth scanning [s] (a run's duration); guess_s: a predicted limit [s], tried
    first as a bracket [guess / GUESS_BRACKET, guess * GUESS_BRACKET] (it only saves map evaluations: a
    wrong guess falls back to the doubling scan from its stable side).
    """
    probe = _MapProbe(at, integrator)
    stop = min(SCAN_STOP * scale_s, stop_s)
    low, high = 0.0, None
    if guess_s is not None and GUESS_BRACKET * guess_s < stop:
        # a good prediction brackets the limit in two maps; a wrong one only costs those two
        below, above = guess_s / GUESS_BRACKET, min(guess_s * GUESS_BRACKET, stop)
        if probe.unstable(below):
            high = below
        elif probe.unstable(above):
            low, high = below, above
        else:
            low = above
    if high is None:
        dt = min(2 * low if low else SCAN_START * scale_s, stop)
        while not probe.unstable(dt):
            if dt >= stop:
                return None
            low, dt = dt, min(2 * dt, stop)
        high = dt
    if low == 0.0:  # unstable at the first probe: go down
        floor = 1e-6 * high
        while high > floor and probe.unstable(high / 2):
            high /= 2
        low = high / 2
    while high / low > 1 + LIMIT_PRECISION:
        mid = math.sqrt(low * high)
        low, high = (low, mid) if probe.unstable(mid) else (mid, high)
    return math.sqrt(low * high)


def _deviation(model: mujoco.MjModel, run_a, run_b) -> float:
    """||x_a - x_b||_inf at the end of two runs, in the tangent space."""
    dq = np.zeros(model.nv)
    mujoco.mj_differentiatePos(model, dq, 1.0, run_b.qpos[-1], run_a.qpos[-1])
    return float(max(np.max(np.abs(dq), initial=0.0), np.max(np.abs(run_a.qvel[-1] - run_b.qvel[-1]), initial=0.0)))


def confirm(
    at: ModelAtPoint,
    limits: Iterable[Limit],
    *,
    nthread: int = 0,
    run: Callable[[Sequence[Job]], list] | None = None,
) -> list[Limit]:
    """Run the nonlinear model just below and just above each measured limit: the limits with `confirmed`,
    `detail` and `growth_per_step_above` filled in (in the order given).

    Per limit four runs, batched: the operating point as it is and perturbed by CONFIRM_SIZE along the
    most unstable eigenvector of Phi(CONFIRM_ABOVE x limit), at CONFIRM_BELOW and CONFIRM_ABOVE x the
    limit. Confirmed: above, the deviation grows beyond GROWTH_SEEN x the exact flow's growth (or the
    run blows up); below, it does not. `run` runs the jobs (default: one batch.run_batched call on
    `nthread` threads; the audit passes springlab.studies.audit.ship.Runner, which may send them to dask workers).
    """
    model, point, linear = at.model, at.point, at.linear
    given = list(limits)
    found: list[dict[str, Any]] = [{} for _ in given]  # per limit: the fields the confirmation fills in
    jobs, plan = [], []
    for index, limit in enumerate(given):
        measured = limit.limit_dt_measured_s
        if measured is None:
            found[index]["detail"] = "no limit found: nothing to confirm"
            if linear.fastest is None:
                # no stiffness, no damping at the point: the map is a shear of the free flow at any dt
                found[index]["detail"] = (
                    "no limit: every mode is rigid (no stiffness or damping at the operating point),"
                    " so no timestep makes the map grow; nothing to confirm"
                )
            continue
        probe = _MapProbe(at, limit.integrator)
        above = CONFIRM_ABOVE * measured
        growth, vector, size = probe.excess(above)
        found[index]["growth_per_step_above"] = growth
        physical = math.exp(min(probe.sigma * above, 700.0))
        if vector is None or CONFIRM_MAX_STEPS * math.log(max(size / physical, 1e-300)) < math.log(GROWTH_SEEN):
            # the model's own growth per step outruns the numerical one: a run cannot tell them apart
            found[index]["detail"] = (
                f"not confirmable by a run: the physically unstable mode grows {physical:.3g}x per step,"
                f" the numerical one {size:.3g}x"
            )
            continue
        steps = math.ceil(math.log(GROWTH_TARGET) / math.log(size / physical)) if size > physical else CONFIRM_MAX_STEPS
        steps = int(min(max(steps, CONFIRM_MIN_STEPS), CONFIRM_MAX_STEPS))
        direction = np.real(vector)
        if not np.any(direction):
            direction = np.imag(vector)
        direction = CONFIRM_SIZE * direction / np.max(np.abs(direction))
        start = _perturbed(model, point, direction)
        base = Setup(point.qpos, point.qvel, point.act, point.ctrl)
        for fraction in (CONFIRM_BELOW, CONFIRM_ABOVE):
            dt = fraction * measured
            for setup in (base, start):
                jobs.append(Job(model, limit.integrator, dt, steps, setup))
            plan.append((index, fraction, steps, dt))
    outcomes = run(jobs) if run is not None else run_batched(jobs, nthread=nthread)
    verdicts: dict[int, dict[float, bool]] = {}
    for position, (index, fraction, steps, dt) in enumerate(plan):
        plain, pushed = outcomes[2 * position], outcomes[2 * position + 1]
        if isinstance(plain, DivergedError) or isinstance(pushed, DivergedError):
            grew = True
        else:
            allowed = math.exp(linear.max_growth_rate * dt * steps)
            grew = _deviation(model, pushed, plain) > GROWTH_SEEN * allowed * CONFIRM_SIZE
        verdicts.setdefault(index, {})[fraction] = grew
        if fraction == CONFIRM_ABOVE:
            below = verdicts[index][CONFIRM_BELOW]
            found[index]["confirmed"] = (not below) and grew
            found[index]["method"] = "linear map"
            found[index]["detail"] = (
                f"{steps} steps at {CONFIRM_BELOW:g}x: {'grew' if below else 'bounded'};"
                f" at {CONFIRM_ABOVE:g}x: {'grew' if grew else 'bounded'}"
            )
    return [dataclasses.replace(limit, **fields) for limit, fields in zip(given, found)]


def _perturbed(model: mujoco.MjModel, point: OperatingPoint, direction: np.ndarray) -> Setup:
    """The operating point moved by `direction` = (dq, dv, dact) in the tangent space."""
    nv = model.nv
    qpos = point.qpos.copy()
    mujoco.mj_integratePos(model, qpos, direction[:nv], 1.0)
    return Setup(qpos, point.qvel + direction[nv : 2 * nv], point.act + direction[2 * nv :], point.ctrl)


#: brute force: every run takes at least this many steps (a growth of BLOWUP_FACTOR over them is 0.23 % a step)
RUN_MIN_STEPS = 2000
#: ... and blows up when MuJoCo flags it or its speed passes this multiple of the physical bound
BLOWUP_FACTOR = 100.0
#: ... bisected down to this ratio between the bounded and the blown-up timestep
RUN_PRECISION = 0.02
#: ... between the model's own timestep / RUN_FLOOR and the ceiling of `RunProbe`
RUN_FLOOR = 64.0


@dataclasses.dataclass(frozen=True)
class RunProbe:
    """How the brute-force runs start and when one counts as blown up.

    Attributes
    ----------
    start
        the audit's start (the perturbed operating point), every run's initial state.
    horizon_s
        the audit's duration [s]; a run lasts max(RUN_MIN_STEPS steps, this).
    peak_speed
        the fine reference's largest |qvel| from `start` over the duration [m/s or rad/s].
    gravity
        |g| [m/s^2]: a run of length T may reach peak_speed + |g| T by falling.
    ceiling_s
        the largest timestep tried [s].
    """

    start: Setup
    horizon_s: float
    peak_speed: float
    gravity: float
    ceiling_s: float

    def steps(self, dt: float) -> int:
        """Steps of a brute-force run at `dt` [s]."""
        return max(RUN_MIN_STEPS, math.ceil(self.horizon_s / dt * (1 - 1e-12)))

    def blew_up(self, outcome: Trajectory | DivergedError, dt: float) -> bool:
        """MuJoCo flagged the run, or its speed passed BLOWUP_FACTOR x (peak_speed + |g| x its length)."""
        if isinstance(outcome, DivergedError):
            return True
        bound = BLOWUP_FACTOR * (self.peak_speed + self.gravity * self.steps(dt) * dt)
        return not float(np.max(np.abs(outcome.qvel), initial=0.0)) <= bound


@dataclasses.dataclass(frozen=True)
class Watch:
    """A fine run from the audit's start: its peak speed and every constraint active along it.

    Attributes
    ----------
    peak_speed
        max |qvel| over the run [m/s or rad/s].
    along
        the union of the constraints active at its steps (`ConstraintState`).
    dt
        its timestep [s] (RK4).
    diverged
        whether it blew up (its figures then cover the steps before).
    """

    peak_speed: float
    along: ConstraintState
    dt: float
    diverged: bool


#: the fine watch run's timestep: the model's own / WATCH_REFINE (again, if that blows up)
WATCH_REFINE = 4


def watch(model: mujoco.MjModel, start: Setup, duration: float) -> Watch:
    """RK4 at the model's own timestep / WATCH_REFINE from `start` for `duration` [s], stepped here to
    read the constraints active at every step (contacts that begin, limits that engage)."""
    work = copy.copy(model)
    work.opt.integrator = integrator_id("rk4")
    dt = float(model.opt.timestep) / WATCH_REFINE
    for _ in range(2):
        work.opt.timestep = dt
        data = mujoco.MjData(work)
        elements: set[str] = set()
        dry: set[str] = set()
        peak_v = peak_a = 0.0
        diverged = False
        with quiet_mujoco():
            mujoco.mj_resetData(work, data)
            data.qpos[:] = start.qpos if start.qpos is not None else work.qpos0
            if start.qvel is not None:
                data.qvel[:] = start.qvel
            if start.act is not None and work.na:
                data.act[:] = start.act
            if start.control is not None and work.nu:
                data.ctrl[:] = np.atleast_2d(start.control)[0]
            for _ in range(max(1, round(duration / dt))):
                mujoco.mj_step(work, data)  # leaves the constraints and qacc of the state it started from
                if data.nefc:
                    found, friction = active_constraints(work, data)
                    elements |= found
                    dry |= friction
                peak_a = max(peak_a, float(np.max(np.abs(data.qacc), initial=0.0)))
                speed = float(np.max(np.abs(data.qvel), initial=0.0))
                if not math.isfinite(speed) or any(data.warning[w].number for w in BAD_WARNINGS):
                    diverged = True
                    break
                peak_v = max(peak_v, speed)
        if not diverged:
            break
        dt /= WATCH_REFINE
    return Watch(peak_v, summarize_constraints(elements, dry, peak_v, peak_a), dt, diverged)


def run_limits(
    model: mujoco.MjModel,
    probe: RunProbe,
    integrators: Sequence[str],
    own_dt: float,
    run: Callable[[Sequence[Job]], list],
    ceilings: dict[str, float] | None = None,
) -> dict[str, tuple[float | None, float | None]]:
    """Brute force: per integrator (largest bounded dt, smallest blown-up dt) [s] (None: none).

    From the model's own timestep, doubling up to the probe's ceiling while runs stay bounded, halving
    down to own / RUN_FLOOR while they blow up, then bisecting (geometrically) to a ratio of 1 +
    RUN_PRECISION; every integrator's next run goes into one batch per round (`run`)."""
    state: dict[str, list[float | None]] = {name: [None, None] for name in integrators}
    pending = {name: own_dt for name in integrators}
    floor = own_dt / RUN_FLOOR
    while pending:
        outcomes = run([Job(model, name, dt, probe.steps(dt), probe.start) for name, dt in pending.items()])
        following: dict[str, float] = {}
        for (name, dt), outcome in zip(pending.items(), outcomes):
            low, high = state[name]
            if probe.blew_up(outcome, dt):
                high = dt if high is None else min(high, dt)
            else:
                low = dt if low is None else max(low, dt)
            state[name] = [low, high]
            if high is None:
                assert low is not None  # this run was bounded
                ceiling = max(probe.ceiling_s, (ceilings or {}).get(name, 0.0))
                if low < ceiling:
                    following[name] = min(2 * low, ceiling)
            elif low is None:
                if high > floor * (1 + 1e-9):
                    following[name] = max(high / 2, floor)
            elif high / low > 1 + RUN_PRECISION:
                following[name] = math.sqrt(low * high)
        pending = following
    return {name: (low, high) for name, (low, high) in state.items()}


def stability_limits(
    at: ModelAtPoint,
    integrators: Iterable[str],
    stop_s: float,
    *,
    nthread: int = 0,
    run: Callable[[Sequence[Job]], list] | None = None,
    smooth: bool = True,
    probe: RunProbe | None = None,
) -> dict[str, Limit]:
    """Predicted, measured and confirmed limits per integrator name; each margin over the model's own timestep.

    `smooth`: nothing constrains the model at its operating point or along its motion, so MuJoCo's
    one-step map there is the dynamics: its limit is measured (scanned up to `stop_s` [s]) and confirmed
    by runs (`confirm`). Otherwise the map is not measured (contacts, limits, equality constraints and
    dry friction make it a different function at every step) and, with a `probe`, every limit comes from
    brute-force runs (`run_limits`); a map limit that runs do not confirm falls back to them as well.
    Without a probe an unconfirmed map limit stays as measured, labelled unconfirmed.
    """
    run = run or (lambda jobs: run_batched(jobs, nthread=nthread))
    model, linear = at.model, at.linear
    fastest = linear.fastest
    scale = 1.0 / fastest.rate_rad_s if fastest is not None else model.opt.timestep
    own_dt = float(model.opt.timestep)
    names = list(integrators)
    spring = None
    if "discrete" in names:
        spring = linear.K - explicit_stiffness(at)
    limits = []
    for name in names:
        damping = None
        if name in IMPLICIT_DAMPING_INTEGRATORS or name == "discrete":
            damping = implicit_damping(at, "implicitfast" if name == "discrete" else name)
        prediction = predict(linear, name, damping, spring if name == "discrete" else None)
        kind = "exact" if prediction.exact and smooth else "estimate"
        measured = measured_limit(at, name, scale, stop_s, prediction.limit_s) if smooth else None
        limits.append(
            Limit(
                name, prediction.limit_s, measured, limit_dt_s=measured, prediction=kind if prediction.limit_s else None
            )
        )
    if smooth:
        limits = confirm(at, limits, run=run)
    fallback = [lim for lim in limits if not smooth or (lim.limit_dt_measured_s is not None and not lim.confirmed)]
    if probe is not None and fallback:
        # an unconfirmed map limit is bracketed too (runs of RUN_MIN_STEPS cost the same at any timestep)
        above = {lim.integrator: 2 * lim.limit_dt_measured_s for lim in fallback if lim.limit_dt_measured_s}
        brackets = run_limits(model, probe, [lim.integrator for lim in fallback], own_dt, run, above)
        limits = [
            _from_runs(lim, *brackets[lim.integrator], probe, own_dt, smooth) if lim.integrator in brackets else lim
            for lim in limits
        ]
    elif not smooth:
        limits = [
            dataclasses.replace(lim, method="none", detail="constraints active: no limit measured") for lim in limits
        ]
    return {
        lim.integrator: dataclasses.replace(lim, margin=None if lim.limit_dt_s is None else lim.limit_dt_s / own_dt)
        for lim in limits
    }


def _from_runs(
    limit: Limit, low: float | None, high: float | None, probe: RunProbe, own_dt: float, smooth: bool
) -> Limit:
    """`limit` with the brute force's bracket as its figure (`run_limits`)."""
    why = (
        f"the one-step map's limit {limit.limit_dt_measured_s:.4g} s was not confirmed ({limit.detail})"
        if smooth
        else "constraints, contacts or dry friction active: the linear map is not the dynamics"
    )
    runs = f"runs of max({RUN_MIN_STEPS} steps, {probe.horizon_s:g} s) from the audit's start"
    if high is None:
        detail = f"{why}; {runs}: none blew up up to {low:.4g} s"
        return dataclasses.replace(
            limit, limit_dt_s=None, confirmed=None, method="nonlinear runs", detail=detail, runs_bounded_dt_s=low
        )
    if low is None:
        detail = f"{why}; {runs}: every one blew up, down to {high:.4g} s"
        return dataclasses.replace(
            limit, limit_dt_s=None, confirmed=None, method="nonlinear runs", detail=detail, runs_blew_up_dt_s=high
        )
    detail = f"{why}; {runs}: bounded at {low:.4g} s, blew up at {high:.4g} s"
    return dataclasses.replace(
        limit,
        limit_dt_s=low,
        confirmed=True,
        method="nonlinear runs",
        detail=detail,
        runs_bounded_dt_s=low,
        runs_blew_up_dt_s=high,
    )


def constraint_flags(model: mujoco.MjModel, dt: float) -> list[ConstraintFlag]:
    """Constraint settings whose solref time constant is shorter than 2 dt [s] (MuJoCo then stiffens nothing:
    with refsafe on it clamps the time constant to 2 dt, so the constraint is softer than written; off, the
    integrator can go unstable). One `ConstraintFlag` per element (dt_limit_s = timeconst / 2, the largest
    timestep that keeps it as written)."""
    rows = []

    def check(kind: str, count: int, solref: np.ndarray, name_of, active=lambda i: True) -> None:
        for i in range(count):
            timeconst = float(solref[i][0])
            if timeconst > 0 and timeconst < 2 * dt and active(i):
                rows.append(ConstraintFlag(f"{kind} {name_of(i)!r}", timeconst, timeconst / 2))

    def name(obj):
        return lambda i: obj(i).name or str(i)

    # only constraints that can become active: a geom that can touch another, a joint or tendon with a range
    check("geom", model.ngeom, model.geom_solref, name(model.geom), lambda i: _can_collide(model, i))
    check("joint limit", model.njnt, model.jnt_solref, name(model.joint), lambda i: bool(model.jnt_limited[i]))
    check("equality", model.neq, model.eq_solref, name(model.eq))
    check(
        "tendon limit",
        model.ntendon,
        model.tendon_solref_lim,
        name(model.tendon),
        lambda i: bool(model.tendon_limited[i]),
    )
    check("contact pair", model.npair, model.pair_solref, name(model.pair))
    if model.opt.enableflags & int(mujoco.mjtEnableBit.mjENBL_OVERRIDE):
        check("option o_solref", 1, model.opt.o_solref[None], lambda i: "override")
    return rows


def _can_collide(model: mujoco.MjModel, geom: int) -> bool:
    """Whether `geom` can ever touch another: contacts are enabled, and its contype/conaffinity bits match those
    of a geom of another body (or an explicit contact pair names it). A geom with contype = conaffinity = 0, or
    alone in the model, never makes a contact."""
    if model.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT):
        return False
    if any(geom in (int(model.pair_geom1[p]), int(model.pair_geom2[p])) for p in range(model.npair)):
        return True
    body = int(model.geom_bodyid[geom])
    contype, conaffinity = int(model.geom_contype[geom]), int(model.geom_conaffinity[geom])
    return any(
        int(model.geom_bodyid[other]) != body
        and ((contype & int(model.geom_conaffinity[other])) or (int(model.geom_contype[other]) & conaffinity))
        for other in range(model.ngeom)
    )
