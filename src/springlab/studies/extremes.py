"""The one-mode oscillator at the extremes: stiff, light, undamped-long and hugely overdamped, near each stability limit.

The oscillator is the scene that declares itself the textbook's mass-spring-damper
(`Scene.oscillator`, springlab.scenes.capabilities.oscillator.OscillatorSpec; `oscillator_scene`): the
studies set its parameters by the names it declares and never name it.

`extremes_table` runs every case x integrator at 0.5x, 0.99x and 1.01x its
stability limit, classifies each run accurate / inaccurate / diverged, and
says what to use instead: the cheapest setting predicted (from MuJoCo's
measured one-step map) to hold the accuracy threshold, run in full to verify.
Each row is an `ExtremeRun`.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import math
from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from springlab import scenes
from springlab.errors import DivergedError, SpringlabError
from springlab.exact.limits import stability_limit
from springlab.runs.run import evaluate
from springlab.scenes.base import Case, Scene
from springlab.scenes.capabilities.oscillator import OscillatorSpec
from springlab.sim.batch import Job, run_batched
from springlab.sim.simulate import INTEGRATORS, Trajectory, quiet_mujoco

from .settings import counted_cost
from .tradeoff import round_down

#: stability_limit scans for rk4; the tables ask for the same few values many times
_limit = functools.lru_cache(maxsize=None)(stability_limit)

#: a run is "accurate" within this max relative error [-]
ACCURACY = 1e-2
#: timesteps of the extremes table, as fractions of each integrator's stability limit
LIMIT_FRACTIONS = (0.5, 0.99, 1.01)
#: every extremes run takes at least this many steps (so an instability shows) and at most MAX_EXTREME_STEPS
MIN_EXTREME_STEPS = 2000
MAX_EXTREME_STEPS = 70_000
#: an advised setting is run (its row added) when it takes at most this many steps; --full: always
VERIFY_STEPS = 200_000
#: MuJoCo treats |qpos|, |qvel| or |qacc| beyond this as a blow-up and resets (mjMAXVAL in mjtype.h)
MUJOCO_MAXVAL = 1e10
#: integrators the advice chooses from (euler and implicit equal implicitfast on these scenes)
ADVICE_INTEGRATORS = ("rk4", "implicitfast", "discrete")


@dataclasses.dataclass(frozen=True)
class ExtremeCase:
    """The oscillator at an extreme: mass [kg], stiffness [N/m], damping ratio [-], released from x0 [m] at rest.

    duration_periods: simulated time in natural periods 2 pi / omega, or None to use
    `slow_time_constants` time constants of the slow root (overdamped cases). The
    motion is linear, so x0 only scales it; it is chosen to keep the peak
    acceleration omega^2 x0 well inside MuJoCo's 1e10 limit, except in the case
    that shows that limit.
    """

    name: str
    description: str
    mass: float
    stiffness: float
    zeta: float
    x0: float = 0.1
    duration_periods: float | None = None
    slow_time_constants: float | None = None

    @property
    def omega(self) -> float:
        """Natural frequency [rad/s]."""
        return math.sqrt(self.stiffness / self.mass)

    @property
    def damping(self) -> float:
        """Damping coefficient [N s/m]."""
        return 2.0 * self.zeta * math.sqrt(self.stiffness * self.mass)

    @property
    def duration(self) -> float:
        """Simulated time [s] the case asks for."""
        if self.duration_periods is not None:
            return self.duration_periods * 2 * math.pi / self.omega
        slow = self.omega * (self.zeta - math.sqrt(self.zeta**2 - 1)) if self.zeta > 1 else self.omega * self.zeta
        assert self.slow_time_constants is not None, "a case sets duration_periods or slow_time_constants"
        return self.slow_time_constants / slow

    @property
    def peak_acceleration(self) -> float:
        """omega^2 x0 [m/s^2], the acceleration at release."""
        return self.omega**2 * abs(self.x0)


EXTREME_CASES = (
    ExtremeCase(
        "stiff",
        "k = 1e12 N/m, m = 1 kg, zeta = 0.05, x0 = 1e-5 m, 20 periods",
        1.0,
        1e12,
        0.05,
        x0=1e-5,
        duration_periods=20,
    ),
    ExtremeCase(
        "stiff-large-x0",
        "k = 1e12 N/m, m = 1 kg, zeta = 0.05, x0 = 0.1 m: |qacc| = 1e11 m/s^2",
        1.0,
        1e12,
        0.05,
        x0=0.1,
        duration_periods=20,
    ),
    ExtremeCase(
        "light",
        "m = 1e-9 kg, k = 100 N/m, zeta = 0.05, x0 = 1e-4 m, 20 periods",
        1e-9,
        100.0,
        0.05,
        x0=1e-4,
        duration_periods=20,
    ),
    ExtremeCase(
        "undamped-long",
        "m = 1 kg, k = 100 N/m, zeta = 0, x0 = 0.1 m, 1e4 periods",
        1.0,
        100.0,
        0.0,
        duration_periods=1e4,
    ),
    ExtremeCase(
        "overdamped",
        "m = 1 kg, k = 100 N/m, zeta = 1e4, x0 = 0.1 m, 3 slow time constants",
        1.0,
        100.0,
        1e4,
        slow_time_constants=3,
    ),
)
FULL_EXTREME_CASES = EXTREME_CASES + (
    ExtremeCase(
        "stiff-1e6",
        "k = 1e6 N/m, m = 1 kg, zeta = 0.05, x0 = 1e-3 m, 20 periods",
        1.0,
        1e6,
        0.05,
        x0=1e-3,
        duration_periods=20,
    ),
    ExtremeCase(
        "light-1e-5",
        "m = 1e-5 kg, k = 100 N/m, zeta = 0.05, x0 = 0.01 m, 20 periods",
        1e-5,
        100.0,
        0.05,
        x0=0.01,
        duration_periods=20,
    ),
    ExtremeCase(
        "overdamped-100",
        "m = 1 kg, k = 100 N/m, zeta = 100, x0 = 0.1 m, 3 slow time constants",
        1.0,
        100.0,
        100.0,
        slow_time_constants=3,
    ),
)


def oscillator_scene() -> tuple[Scene, OscillatorSpec]:
    """The scene that declares itself the textbook's one-mode mass-spring-damper, and its declaration.

    Returns
    -------
    tuple[Scene, OscillatorSpec]
        the first scene of the catalogue whose `Scene.oscillator` is set, and that declaration.

    Raises
    ------
    SpringlabError
        no scene declares one.
    """
    for scene in scenes.SCENES.values():
        if scene.oscillator is not None:
            return scene, scene.oscillator
    raise SpringlabError("no scene declares itself a one-mode oscillator (Scene.oscillator)")


@dataclasses.dataclass(frozen=True)
class Oscillator:
    """The oscillator scene built at one set of values: what a run of its free scenario needs.

    Attributes
    ----------
    case
        the declaring scene's free scenario at the values, compiled (one degree of freedom).
    spec
        the scene's declaration (its parameter and joint names).
    """

    case: Case
    spec: OscillatorSpec

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled model (one degree of freedom)."""
        return self.case.model

    @property
    def params(self) -> dict[str, float]:
        """The resolved parameters (SI), by the scene's names."""
        return self.case.params


def build_oscillator(
    *,
    mass: float | None = None,
    stiffness: float | None = None,
    damping: float | None = None,
    x0: float | None = None,
    v0: float | None = None,
) -> Oscillator:
    """The oscillator scene's free scenario at m [kg], k [N/m], d [N s/m], x0 [m], v0 [m/s] (None: its default).

    Raises
    ------
    SpringlabError
        the declaring scene's free scenario has more than one degree of freedom.
    """
    scene, spec = oscillator_scene()
    case = scene.case(spec.free, spec.parameters(mass=mass, stiffness=stiffness, damping=damping, x0=x0, v0=v0))
    if case.model.nv != 1:
        raise SpringlabError(
            f"{scene.name}'s scenario {spec.free!r} declares a one-mode oscillator but has {case.model.nv}"
            " degrees of freedom"
        )
    return Oscillator(case, spec)


def _case_model(case: ExtremeCase) -> Oscillator:
    return build_oscillator(mass=case.mass, stiffness=case.stiffness, damping=case.damping, x0=case.x0, v0=0.0)


def _sample_steps(steps: int, count: int = 2000) -> np.ndarray:
    """Step indices in [0, steps] to evaluate a long run at: dense early, quasi-random (no aliasing with
    the motion's period), and the last step."""
    golden = (np.arange(1, count + 1) * 0.6180339887498949) % 1.0
    early = np.arange(min(steps, 200) + 1)
    picks = np.concatenate([early, np.floor(golden * steps), np.geomspace(1, max(steps, 1), 400).round(), [steps]])
    return np.unique(picks.astype(np.int64))


def predicted_error(
    case: ExtremeCase,
    integrator: str,
    dt: float,
    context: Oscillator,
) -> float:
    """Max relative error [-] of a run of `case`, from MuJoCo's measured one-step map.

    The oscillator is linear, so a run is z_n = M^n z_0 exactly, with M measured
    by stepping the case's own model (`context`, `build_oscillator`) once from two
    independent states. The error against the exact reference is taken over
    `_sample_steps` of the run, as max |sim - ref| / max |ref| per column (pos,
    vel); cheap for any length.
    """
    model = context.model
    steps = max(1, round(case.duration / dt))
    work = copy.copy(model)
    work.opt.integrator = INTEGRATORS[integrator]
    work.opt.timestep = dt
    data = mujoco.MjData(work)
    columns = []
    scale = (case.x0, case.omega * case.x0)  # unit states scaled to the case's amplitude (MuJoCo's range)
    with quiet_mujoco():
        for j in range(2):
            mujoco.mj_resetData(work, data)
            data.qpos[0], data.qvel[0] = (scale[0], 0.0) if j == 0 else (0.0, scale[1])
            mujoco.mj_step(work, data)
            columns.append(np.array([data.qpos[0], data.qvel[0]]) / scale[j])
    one_step = np.column_stack(columns)
    values, vectors = np.linalg.eig(one_step)
    n = _sample_steps(steps)
    coefficients = np.linalg.solve(vectors, np.array([case.x0, 0.0], complex))
    with np.errstate(over="ignore", invalid="ignore"):
        powers = values[None, :] ** n[:, None]
        states = ((vectors[None, :, :] * (powers * coefficients[None, :])[:, None, :]).sum(-1)).real
    if not np.isfinite(states).all():
        return math.inf
    reference = context.case.reference(n * dt, dt=dt)
    assert reference is not None, "the oscillator's free scenario has an exact reference"
    joint = context.spec.joint
    errors = []
    for k, series in ((0, reference.pos[joint]), (1, reference.vel[joint])):
        peak = float(np.max(np.abs(series)))
        errors.append(float(np.max(np.abs(states[:, k] - series))) / peak if peak > 0 else 0.0)
    return max(errors)


def _advice(case: ExtremeCase, context: Oscillator) -> dict[str, Any]:
    """The cheapest setting predicted (`predicted_error`) to hold ACCURACY/2 over the case's duration.

    Per integrator of ADVICE_INTEGRATORS: the largest dt (bisection in log dt,
    at most 0.9x its stability limit) whose predicted error is within half the
    accuracy threshold; cost = the counted work (settings.counted_cost: steps x
    model evaluations per step), so the same case gets the same advice on every
    run and machine (a measured time per step flipped the overdamped case's
    advice between discrete and implicitfast on a busy machine). For a case
    beyond MuJoCo's value limit no dt helps, and the advice says so.
    """
    if case.peak_acceleration >= MUJOCO_MAXVAL or case.omega * abs(case.x0) >= MUJOCO_MAXVAL:
        return {
            "integrator": None,
            "dt": None,
            "steps": None,
            "predicted_error": None,
            "phrase": (
                f"no dt helps: MuJoCo resets any |qacc| > {MUJOCO_MAXVAL:.0e} m/s^2 (mjMAXVAL), and"
                f" omega^2 x0 = {case.peak_acceleration:.1e}; rescale units or amplitude"
            ),
        }
    best: dict[str, Any] | None = None
    target = ACCURACY / 2
    for name in ADVICE_INTEGRATORS:
        high = min(0.9 * _limit(name, case.zeta) / case.omega, case.duration / 10)
        low = case.duration / 1e12
        if predicted_error(case, name, high, context) <= target:
            dt = high
        else:
            for _ in range(16):  # 12 decades to within 2 %
                mid = math.sqrt(low * high)
                if predicted_error(case, name, mid, context) <= target:
                    low = mid
                else:
                    high = mid
            dt = low
        dt = round_down(dt)
        steps = max(1, round(case.duration / dt))
        cost = counted_cost(name, steps)
        if best is None or cost < best["cost"]:
            best = {
                "integrator": name,
                "dt": dt,
                "steps": steps,
                "cost": cost,
                "predicted_error": predicted_error(case, name, dt, context),
            }
    assert best is not None, "every integrator has a predicted error"
    best["phrase"] = (
        f"use {best['integrator']} with dt <= {best['dt']:.2g} s ({best['steps']:.2g} steps,"
        f" predicted error {best['predicted_error']:.1g})"
    )
    return best


@dataclasses.dataclass(frozen=True)
class ExtremeRun:
    """One run of the extremes table (`extremes_table`); `to_dict()` is its row in stability.json.

    Attributes
    ----------
    kind
        'limit' (at a fraction of a stability limit) or 'advised' (the advice, run over the whole case).
    case, description
        the `ExtremeCase`'s name and description.
    integrator
        the run's integrator.
    fraction
        of `limit_of`'s stability limit [-] (None for an advised run).
    limit_of
        the integrator whose limit the fraction is of (discrete, which has none: euler).
    omega_dt, limit_omega_dt
        the run's omega*dt and that limit's [-] (inf: no limit).
    dt, duration
        timestep and simulated time [s].
    steps
        number of steps.
    outcome
        'accurate' | 'inaccurate' | 'diverged'.
    max_rel_error
        max relative error against the exact solution [-] (None if diverged).
    detail
        how it diverged ('' otherwise).
    advice
        one phrase: which integrator and dt to use instead.
    """

    kind: str
    case: str
    description: str
    integrator: str
    fraction: float | None
    limit_of: str
    omega_dt: float
    limit_omega_dt: float
    dt: float
    duration: float
    steps: int
    outcome: str
    max_rel_error: float | None
    detail: str
    advice: str

    def to_dict(self) -> dict[str, Any]:
        """The row of stability.json's "extremes": every attribute, in this order."""
        return dataclasses.asdict(self)


def extremes_table(
    cases: Sequence[ExtremeCase] = EXTREME_CASES, *, verify_steps: int = VERIFY_STEPS, nthread: int = 0
) -> tuple[ExtremeRun, ...]:
    """Run every case x integrator at LIMIT_FRACTIONS of its stability limit; classify each run.

    discrete has no limit: its rows use the euler limit's fractions, to show it
    stays stable where the others do not. Durations: the case's, stretched to
    MIN_EXTREME_STEPS steps and cut at MAX_EXTREME_STEPS (each row says its own).
    Each case also gets a row for its advised setting (`_advice`), run in full
    over the case's duration when it takes at most `verify_steps` steps.

    Returns
    -------
    tuple[ExtremeRun, ...]
        One per run: the limit runs case by case, integrator by integrator, then the advised runs.
    """
    jobs: list[Job] = []
    meta: list[tuple[str, ExtremeCase, str, float | None, float, str]] = []
    contexts: dict[str, Oscillator] = {}
    for case in cases:
        context = _case_model(case)
        contexts[case.name] = context
        for name in INTEGRATORS:
            limit_name = "euler" if name == "discrete" else name
            limit = _limit(limit_name, case.zeta)
            for fraction in LIMIT_FRACTIONS:
                dt = fraction * limit / case.omega
                steps = min(max(round(case.duration / dt), MIN_EXTREME_STEPS), MAX_EXTREME_STEPS)
                jobs.append(context.case.job(name, dt, steps))
                meta.append(("limit", case, name, fraction, limit, limit_name))
    advice = {case.name: _advice(case, contexts[case.name]) for case in cases}
    for case in cases:
        pick = advice[case.name]
        if pick["integrator"] is None or pick["steps"] > verify_steps:
            continue
        jobs.append(contexts[case.name].case.job(pick["integrator"], pick["dt"], pick["steps"]))
        meta.append(
            ("advised", case, pick["integrator"], None, _limit(pick["integrator"], case.zeta), pick["integrator"])
        )
    outcomes = run_batched(jobs, nthread=nthread)
    rows = []
    for job, outcome, (kind, case, name, of_limit, limit, limit_name) in zip(jobs, outcomes, meta):
        outcome_name, max_error, detail = _classify(contexts[case.name], outcome)
        pick = advice[case.name]
        if kind == "advised":
            phrase = f"the advice, run over the whole {case.duration:.3g} s"
        else:
            phrase = _advice_phrase(outcome_name, name, job.dt, limit, pick)
        rows.append(
            ExtremeRun(
                kind=kind,
                case=case.name,
                description=case.description,
                integrator=name,
                fraction=of_limit,
                limit_of=limit_name,
                omega_dt=job.dt * case.omega,
                limit_omega_dt=limit,
                dt=job.dt,
                duration=job.dt * job.steps,
                steps=job.steps,
                outcome=outcome_name,
                max_rel_error=max_error,
                detail=detail,
                advice=phrase,
            )
        )
    return tuple(rows)


def _classify(context: Oscillator, outcome: Trajectory | DivergedError) -> tuple[str, float | None, str]:
    """('accurate' | 'inaccurate' | 'diverged', max relative error or None, divergence detail)."""
    if isinstance(outcome, DivergedError):
        return "diverged", None, str(outcome)
    try:
        result = evaluate(context.case, outcome)
    except DivergedError as error:
        return "diverged", None, str(error)
    worst = max(e.max_rel for e in result.errors.values())
    return ("accurate" if worst <= ACCURACY else "inaccurate"), worst, ""


def _advice_phrase(outcome: str, integrator: str, dt: float, limit: float, pick: dict) -> str:
    if pick["integrator"] is None:
        return pick["phrase"]
    if outcome == "diverged":
        return f"unstable past omega*dt = {limit:.3g}: {pick['phrase']}"
    if outcome == "inaccurate":
        return f"stable but too coarse: {pick['phrase']}"
    if pick["integrator"] == integrator and pick["dt"] <= dt * 1.0001:
        return "fine as is"
    return f"fine; cheapest for {ACCURACY:.0%}: {pick['phrase']}"
