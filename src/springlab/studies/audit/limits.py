"""Stability limits of any model, per integrator: predicted from its modes, measured on its one-step map,
confirmed on the nonlinear model; and the constraint settings a timestep breaks.

The closed-form prediction from the modes (springlab.exact.predicted_limits) seeds the measurement of MuJoCo's
one-step map (springlab.exact.map_limits: the smallest dt at which it grows beyond the exact flow), which
`springlab.exact.point_facts.PointFacts` gathers with the other facts at the point. This module judges those
facts: runs of the nonlinear model just below and above each measured limit confirm it (`confirm`); where
the map is not the dynamics, or runs do not confirm it, runs from the audit's start bracket the limit
(`run_limits`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import mujoco
import numpy as np

from springlab.errors import DivergedError
from springlab.exact.map_limits import MapLimit
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import OperatingPoint
from springlab.exact.predicted_limits import Prediction
from springlab.sim.batch import Job, run_batched
from springlab.sim.simulate import Setup, Trajectory

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


def _deviation(model: mujoco.MjModel, run_a, run_b) -> float:
    """||x_a - x_b||_inf at the end of two runs, in the tangent space."""
    dq = np.zeros(model.nv)
    mujoco.mj_differentiatePos(model, dq, 1.0, run_b.qpos[-1], run_a.qpos[-1])
    return float(max(np.max(np.abs(dq), initial=0.0), np.max(np.abs(run_a.qvel[-1] - run_b.qvel[-1]), initial=0.0)))


def confirm(
    at: ModelAtPoint,
    limits: Iterable[Limit],
    maps: Mapping[str, MapLimit],
    *,
    nthread: int = 0,
    run: Callable[[Sequence[Job]], list] | None = None,
) -> list[Limit]:
    """Run the nonlinear model just below and just above each measured limit: the limits with `confirmed`,
    `detail` and `growth_per_step_above` filled in (in the order given).

    `maps`: each integrator's measured map, read at CONFIRM_ABOVE x its limit (`PointFacts.maps`). Per limit
    four runs, batched: the operating point as it is and perturbed by CONFIRM_SIZE along the most unstable
    eigenvector of Phi(CONFIRM_ABOVE x limit), at CONFIRM_BELOW and CONFIRM_ABOVE x the limit. Confirmed:
    above, the deviation grows beyond GROWTH_SEEN x the exact flow's growth (or the run blows up); below, it
    does not. `run` runs the jobs (default: one batch.run_batched call on
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
        read = maps[limit.integrator]
        above, growth, vector, size = read.above_s, read.growth_above, read.direction_above, read.size_above
        assert above is not None and growth is not None and size is not None, "a measured map is read above it"
        found[index]["growth_per_step_above"] = growth
        physical = math.exp(min(linear.max_growth_rate * above, 700.0))
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
    predicted: Mapping[str, Prediction],
    maps: Mapping[str, MapLimit] | None,
    *,
    nthread: int = 0,
    run: Callable[[Sequence[Job]], list] | None = None,
    probe: RunProbe | None = None,
) -> dict[str, Limit]:
    """Predicted, measured and confirmed limits per integrator of `predicted`; each margin over the model's own
    timestep.

    `predicted`: each integrator's closed-form limit (springlab.exact.predicted_limits.predictions). `maps`:
    their measured one-step-map limits (`PointFacts.maps`, read at CONFIRM_ABOVE x each limit), None where
    something is active at the operating point or along the motion: contacts, limits, equality constraints and
    dry friction make the map a different function at every step, so it is not the dynamics. A measured limit
    is confirmed by runs (`confirm`); with a `probe`, every limit without a map, and a map limit that runs do
    not confirm, comes from brute-force runs (`run_limits`). Without a probe an unconfirmed map limit stays as
    measured, labelled unconfirmed.
    """
    run = run or (lambda jobs: run_batched(jobs, nthread=nthread))
    smooth = maps is not None
    own_dt = float(at.model.opt.timestep)
    limits = []
    for name, prediction in predicted.items():
        kind = "exact" if prediction.exact and smooth else "estimate"
        measured = maps[name].limit_s if maps is not None else None
        limits.append(
            Limit(
                name, prediction.limit_s, measured, limit_dt_s=measured, prediction=kind if prediction.limit_s else None
            )
        )
    if maps is not None:
        limits = confirm(at, limits, maps, run=run)
    fallback = [lim for lim in limits if not smooth or (lim.limit_dt_measured_s is not None and not lim.confirmed)]
    if probe is not None and fallback:
        # an unconfirmed map limit is bracketed too (runs of RUN_MIN_STEPS cost the same at any timestep)
        above = {lim.integrator: 2 * lim.limit_dt_measured_s for lim in fallback if lim.limit_dt_measured_s}
        brackets = run_limits(at.model, probe, [lim.integrator for lim in fallback], own_dt, run, above)
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
