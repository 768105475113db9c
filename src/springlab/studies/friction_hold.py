"""`springlab friction-settings MODEL.xml`: how fast a body that dry friction holds creeps in MuJoCo, and the
cheapest settings that stop it, on any MJCF model.

MuJoCo's dry friction is soft: a body that Coulomb friction holds (a box in a gripper, a part on a tilted
tray) slides slowly, at a steady velocity with no acceleration. That is friction creep, MuJoCo's model error,
and no integrator or timestep removes it. On a model file this study

* finds what dry friction holds (`find_hold`): the bodies named (`bodies`), or every free-jointed body in a
  frictional contact at the operating point (a keyframe, by default the first), else every body whose own
  joints have frictionloss; the bodies it touches there hold it. Per held body its size (the largest extent of
  its colliding geoms' bounding boxes: the length scale of `tol`) and its Coulomb margin (friction could carry
  this many times the force it carries early in the hold, in a run of the model's own settings);
* runs the hold at the model's own settings over the whole hold: each body's slip (its centre of mass's
  distance from where the hold starts), creep velocity (its mean speed over the second half of the time it is
  held) and when it leaves the grip (touches none of the bodies that held it);
* sweeps the settings that act on that friction (`hold_settings`: impratio, the cone, NoSlip iterations, the
  held contacts' solref time constant and solimp impedance) with every integrator and timestep (the model's own
  and its halves) over the first SWEEP_WINDOW_S of the hold: a run's slip over the whole hold is its slip there
  plus its creep velocity over the rest;
* ranks them with springlab.studies.settings (counted work per hold, the Pareto front) and recommends the
  cheapest whose slip over the hold stays within `tol` body sizes, verified by a run of the whole hold.

Its reference is physical, not a converged run: a body that dry friction holds should not move. The result is
the friction scene's study (springlab.studies.friction_results.FrictionSettings) with one case, "hold", whose
error is a run's slip over the hold in body sizes, and the hold's facts (`FrictionSettings.hold`).
"""

from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from collections.abc import Mapping, Sequence
from typing import Any

import mujoco

from springlab.errors import BadInputError, DivergedError
from springlab.scenes.capabilities.friction import (
    CONTACT_FRICTION,
    JOINT_FRICTION,
    DryFrictionSpec,
    FrictionCase,
    FrictionMeasure,
)
from springlab.scenes.declarations import keyword_parameters
from springlab.sim import model_files
from springlab.sim.simulate import INTEGRATORS, check_timing, integrator_id

from . import friction_settings as scene_study
from .audit.ship import compiled, ship
from .executor import Executor, chunked, resolve
from .friction_results import CaseStudy, FrictionSettings, HeldBody, HoldReport, SettingRun
from .friction_settings import grid, model_errors
from .held import DEFAULT_HOLD_S, HoldPlan, Track, configure, coulomb_margin, find_hold, run_hold, slip_over_hold
from .settings import (
    Recommendation,
    Run,
    Setting,
    Verification,
    cheapest_verified,
    counted_cost,
    pareto_front,
    work_per_evaluation,
)

#: the slip allowed over the hold, in body sizes [-], when no tol is given (1 mm for a 40 mm box)
DEFAULT_TOL = 0.025
#: each sweep run lasts the first this-many seconds of the hold (or the hold); its slip over the rest of the hold
#: is its creep velocity times the rest, and the pick's verification runs the whole hold [s]
SWEEP_WINDOW_S = 5.0
#: integrators swept besides the model's own (implicit is implicitfast plus Coriolis terms: its own only)
HOLD_INTEGRATORS = ("euler", "implicitfast", "rk4")
#: the timesteps swept, as fractions of the model's own
DT_FRACTIONS = (1.0, 0.5)
#: candidate settings verified by a run of the whole hold, cheapest first, before the study gives up
MAX_VERIFIED = 20
#: runs per chunk of the executor
CHUNK_RUNS = 24
#: the settings that also change how stiff the contact is (how far the grip's surfaces press into each other),
#: not only its friction: the study also names the cheapest setting that leaves them as they are
STIFFNESS = ("solref_timeconst", "solimp_d")
#: the case's name in the study's rows and JSON
CASE = "hold"

_NAMES = {value: name for name, value in INTEGRATORS.items()}

MEASURES = (
    FrictionMeasure("creep_velocity_m_s", "creep velocity [m/s]", ""),
    FrictionMeasure("slip_m", "slip over the hold (in body sizes)", "body_size_m"),
)


# -- the sweep on the executor ----------------------------------------------------------------


#: one run of a chunk: ((setting, value) pairs, integrator, dt [s])
HoldJob = tuple[tuple[tuple[str, float], ...], str, float]


@dataclasses.dataclass(frozen=True)
class HoldChunk:
    """A chunk of the sweep: the model (shipped to dask workers, or the compiled model locally), the plan, the
    runs' length [s] and the runs, in groups of one setting."""

    model: Any
    plan: HoldPlan
    duration: float
    groups: tuple[tuple[HoldJob, ...], ...]


def _model_of(payload: Any) -> mujoco.MjModel:
    return payload if isinstance(payload, mujoco.MjModel) else compiled(payload)


def hold_chunk(payload: HoldChunk, nthread: int = 0) -> list[dict[str, Any]]:
    """One chunk of runs (module-level, plain data: it runs on dask workers too): per run its steps, CPU
    time, each body's slip over the run and the hold, creep velocity and loss, and its model's work."""
    model = _model_of(payload.model)
    plan = payload.plan
    rows = []
    for group in payload.groups:
        settings = dict(group[0][0])
        work_model = configure(model, settings, plan)
        work = work_per_evaluation(work_model)
        for _, integrator, dt in group:
            row: dict[str, Any] = {"work": work, "cpu_time_s": math.nan, "tracks": None, "detail": ""}
            try:
                _, tracks, cpu = run_hold(work_model, plan, integrator, dt, payload.duration)
            except DivergedError as blown:
                row["detail"] = str(blown)
            else:
                row["cpu_time_s"] = cpu
                row["tracks"] = [dataclasses.astuple(t) for t in tracks]
            rows.append(row)
    return rows


def _row(plan: HoldPlan, config: tuple[dict[str, float], str, float], outcome: Mapping[str, Any], duration: float):
    """The study's row of one run: its error is its slip over the hold in body sizes (the worst body)."""
    settings, integrator, dt = config
    steps = check_timing(dt, plan.hold_s)  # the cost of holding for the whole hold at this setting
    cost = counted_cost(integrator, steps, outcome["work"])
    if outcome["tracks"] is None:
        run = Run(Setting(integrator, dt, tuple(settings.items())), steps, None, cost, diverged=True)
        run = dataclasses.replace(run, detail=outcome["detail"])
        none = {m.quantity: None for m in MEASURES}
        return SettingRun(run, CASE, dict(settings), None, dict(none), {**none, "lost_at_s": None})
    tracks = [Track(*t) for t in outcome["tracks"]]
    slips = slip_over_hold(tracks, plan, duration)
    error = max(s / size if size > 0 else math.inf for s, size in zip(slips, plan.sizes))
    creep = max(t.creep_velocity_m_s for t in tracks)
    lost = [t.lost_at_s for t in tracks if t.lost_at_s is not None]
    run = Run(Setting(integrator, dt, tuple(settings.items())), steps, error, cost, float(outcome["cpu_time_s"]))
    return SettingRun(
        run,
        CASE,
        dict(settings),
        None,
        {"creep_velocity_m_s": creep, "slip_m": error},
        {"creep_velocity_m_s": creep, "slip_m": max(slips), "lost_at_s": min(lost) if lost else None},
    )


def friction_hold(
    model: str | os.PathLike[str],
    *,
    bodies: Sequence[str] = (),
    hold_s: float = DEFAULT_HOLD_S,
    keyframe: str | int | None = None,
    tol: float = DEFAULT_TOL,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    values: Mapping[str, Sequence[float]] | None = None,
    executor: Executor | None = None,
) -> FrictionSettings:
    """How fast what dry friction holds in a model file creeps, and the cheapest settings that stop it.

    Parameters
    ----------
    model
        path of an MJCF (or URDF MuJoCo loads).
    bodies
        names of the held bodies (empty: found, see the module docstring).
    hold_s
        how long the body must be held [s] (> 0).
    keyframe
        the operating point: a keyframe name or index (None: the first keyframe, else qpos0 at rest).
    tol
        the slip allowed over the hold, in body sizes [-] (0.025: 1 mm for a 40 mm box).
    integrators
        integrators swept (None: HOLD_INTEGRATORS and the model's own).
    dts
        timesteps swept [s] (None: the model's own x DT_FRACTIONS).
    values
        setting -> the values to sweep instead of `held.hold_settings`' (a smaller study; the model's own value
        is the baseline either way).
    executor
        where the sweep's chunks run (None: here).

    Returns
    -------
    FrictionSettings
        the study, one case "hold", with `hold` (HoldReport): the bodies, their creep at the model's own
        settings, when they fall out, and the recommendation.

    Raises
    ------
    BadInputError
        no such file, a model MuJoCo cannot compile, an unknown keyframe or body, a model or body without dry
        friction, a hold or tol that is not positive, an unknown integrator, a bad timestep.
    """
    started = _time.perf_counter()
    label = os.fspath(model)
    _check_hold(hold_s, tol)
    compiled_model = model_files.load(label)
    own_integrator, own_dt = _NAMES[int(compiled_model.opt.integrator)], float(compiled_model.opt.timestep)
    names = tuple(dict.fromkeys(integrators or (*HOLD_INTEGRATORS, own_integrator)))
    for name in names:
        integrator_id(name)
    steps_of = sorted({float(d) for d in (dts or [own_dt * f for f in DT_FRACTIONS])}, reverse=True)
    for dt in steps_of:
        check_timing(dt, hold_s)
    plan, settings, skipped, point = find_hold(compiled_model, label, bodies=bodies, keyframe=keyframe, hold_s=hold_s)
    if len(steps_of) < 2:
        raise BadInputError(
            f"the study needs at least two timesteps to show the creep does not depend on dt, got {steps_of}"
        )
    for name, chosen in (values or {}).items():
        if name not in {s.name for s in settings} or not chosen:
            valid = ", ".join(s.name for s in settings)
            raise BadInputError(f"values: {name!r} is no swept setting of this hold (valid: {valid}) or has no values")
    friction = CONTACT_FRICTION if any(plan.holder_geoms) else JOINT_FRICTION
    question = f"does dry friction hold {_listed(compiled_model, plan)} for {hold_s:g} s?"
    case = FrictionCase(CASE, friction, question, MEASURES)
    spec = DryFrictionSpec((case,), settings, tuple(steps_of), names)
    window = min(hold_s, SWEEP_WINDOW_S)
    runner = resolve(executor)
    carried = ship(("path", label), compiled_model) if runner.distributed else compiled_model
    baseline = dict(plan.baseline)
    own = _own_run(compiled_model, plan, baseline, own_integrator, own_dt)
    groups = grid(spec, case, names, steps_of, values)
    runs = _swept(runner, carried, plan, window, groups, len(steps_of))
    default = own.row
    study = CaseStudy(
        scenario=CASE,
        friction=friction,
        question=question,
        measures=MEASURES,
        settings=settings,
        runs=runs,
        default=default,
        model_errors=model_errors(runs, tuple(steps_of)) if "rk4" in names else (),
        pareto=tuple(pareto_front(runs)),
    )
    pick, verified = _pick(compiled_model, plan, study, tol, default)
    study = dataclasses.replace(study, pick=pick)
    alternative: Recommendation[SettingRun] | None = None
    alternative_bodies: tuple[HeldBody, ...] = ()
    if pick.found and pick.row is not None and any(pick.row.settings.get(n) != baseline.get(n) for n in STIFFNESS):
        alternative, alternative_bodies = _pick(compiled_model, plan, study, tol, default, keep=STIFFNESS)
    report = HoldReport(
        model=label,
        operating_point=point.label,
        hold_s=float(hold_s),
        window_s=window,
        tol=float(tol),
        bodies=own.bodies,
        skipped=skipped,
        pick_bodies=verified,
        friction_only=alternative,
        friction_only_bodies=alternative_bodies,
    )
    return FrictionSettings(
        scene=label,
        overrides={},
        tol=float(tol),
        integrators=names,
        dts=tuple(steps_of),
        mujoco_default=(own_integrator, own_dt),
        cases=(study,),
        wall_time_s=_time.perf_counter() - started,
        hold=report,
    )


def _check_hold(hold_s: float, tol: float) -> None:
    """BadInputError unless the hold [s] and the slip allowed [body sizes] are finite numbers > 0."""
    if not (isinstance(hold_s, (int, float)) and math.isfinite(hold_s) and hold_s > 0):
        raise BadInputError(f"--hold must be a number of seconds > 0, got {hold_s!r}")
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
        raise BadInputError(f"--tol is the slip allowed over the hold in body sizes, a number > 0; got {tol!r}")


def _swept(
    runner: Executor,
    carried: Any,
    plan: HoldPlan,
    window: float,
    groups: list[list[tuple[dict[str, float], str, float]]],
    n_steps: int,
) -> tuple[SettingRun, ...]:
    """The sweep's runs, one per configuration of `groups` in order: chunks of whole groups (about CHUNK_RUNS
    runs each, `n_steps` timesteps per group) run by `runner` on the model as `carried`, over `window` [s]."""
    configs = [config for group in groups for config in group]
    pieces = chunked(len(groups), max(1, CHUNK_RUNS // n_steps))
    payloads = [HoldChunk(carried, plan, window, tuple(_jobs(groups[p.start : p.stop]))) for p in pieces]
    sizes = [sum(len(g) for g in groups[p.start : p.stop]) for p in pieces]
    outcomes = [
        row
        for part in runner.map(hold_chunk, payloads, description="friction settings: hold", sizes=sizes)
        for row in part
    ]
    return tuple(_row(plan, config, outcome, window) for config, outcome in zip(configs, outcomes))


def _listed(model: mujoco.MjModel, plan: HoldPlan) -> str:
    return ", ".join(repr(model.body(b).name or str(b)) for b in plan.bodies)


def _jobs(groups: Sequence[Sequence[tuple[dict[str, float], str, float]]]) -> list[tuple[HoldJob, ...]]:
    return [tuple((tuple(s.items()), name, dt) for s, name, dt in group) for group in groups]


@dataclasses.dataclass(frozen=True)
class _Own:
    row: SettingRun | None
    bodies: tuple[HeldBody, ...]


def _held_bodies(model: mujoco.MjModel, plan: HoldPlan, work_model, trajectory, tracks) -> tuple[HeldBody, ...]:
    """The held bodies with what a run of the whole hold did to them."""
    out = []
    for j, body in enumerate(plan.bodies):
        t = tracks[j] if tracks is not None else None
        holders = sorted({model.body(int(model.geom_bodyid[g])).name or str(g) for g in plan.holder_geoms[j]})
        margin = None if t is None else coulomb_margin(work_model, trajectory, plan, j, t.margin_state)
        out.append(
            HeldBody(
                name=model.body(body).name or str(body),
                size_m=plan.sizes[j],
                holders=tuple(holders),
                coulomb_margin=margin,
                creep_velocity_m_s=None if t is None else t.creep_velocity_m_s,
                slip_m=None if t is None else t.slip_m,
                lost_at_s=None if t is None else t.lost_at_s,
            )
        )
    return tuple(out)


def _own_run(model: mujoco.MjModel, plan: HoldPlan, baseline: dict[str, float], integrator: str, dt: float) -> _Own:
    """The model's own settings over the whole hold: the baseline row and what it does to each body."""
    work = work_per_evaluation(model)
    try:
        trajectory, tracks, cpu = run_hold(model, plan, integrator, dt, plan.hold_s)
    except DivergedError as blown:
        outcome: dict[str, Any] = {"work": work, "cpu_time_s": math.nan, "tracks": None, "detail": str(blown)}
        return _Own(
            _row(plan, (baseline, integrator, dt), outcome, plan.hold_s), _held_bodies(model, plan, model, None, None)
        )
    tracked = [dataclasses.astuple(t) for t in tracks]
    outcome = {"work": work, "cpu_time_s": cpu, "tracks": tracked, "detail": ""}
    return _Own(
        _row(plan, (baseline, integrator, dt), outcome, plan.hold_s),
        _held_bodies(model, plan, model, trajectory, tracks),
    )


def _pick(
    model: mujoco.MjModel,
    plan: HoldPlan,
    study: CaseStudy,
    tol: float,
    default: SettingRun | None,
    keep: Sequence[str] = (),
) -> tuple[Recommendation[SettingRun], tuple[HeldBody, ...]]:
    """The cheapest setting whose slip over the hold stays within tol body sizes, verified by a run of the whole
    hold (springlab.studies.settings.cheapest_verified: counted work, then slip; no timer decides), and the held
    bodies through that run (empty: no pick). Settings named in `keep` stay at the model's own values."""
    passed: list[tuple[HeldBody, ...]] = []

    def verify(candidate: SettingRun) -> Verification:
        work_model = configure(model, candidate.settings, plan)
        try:
            trajectory, tracks, cpu = run_hold(work_model, plan, candidate.integrator, candidate.dt, plan.hold_s)
        except DivergedError:
            return Verification(False, None)
        slips = slip_over_hold(tracks, plan, plan.hold_s)
        error = max(s / size if size > 0 else math.inf for s, size in zip(slips, plan.sizes))
        ok = error <= tol and all(t.lost_at_s is None for t in tracks)
        if ok:
            passed.append(_held_bodies(model, plan, work_model, trajectory, tracks))
        details = {
            "work_vs_default": candidate.cost / default.cost if default is not None else None,
            "speedup": default.cpu_time_s / cpu if default is not None and cpu > 0 else None,
            "slip_m": max(slips),
            "creep_velocity_m_s": max(t.creep_velocity_m_s for t in tracks),
        }
        return Verification(ok, error, cpu, details)

    def describe(setting: Setting) -> str:
        return f"{study.describe(setting.option_values)} with {setting.integrator} at dt = {setting.dt:g} s"

    def changed(row: SettingRun) -> float:
        """How many of the model's own settings, integrator and timestep the row changes."""
        settings = sum(row.settings.get(s.name) != s.mujoco_default for s in study.settings)
        if default is None:
            return float(settings)
        return float(settings + (row.integrator != default.integrator) + (row.dt != default.dt))

    own = {s.name: s.mujoco_default for s in study.settings}
    candidates = [
        r
        for r in study.runs
        if r.run.valid and r.error <= tol and all(r.settings.get(name, own.get(name)) == own.get(name) for name in keep)
    ]
    pick = cheapest_verified(
        candidates,
        tol,
        verify,
        describe=describe,
        max_tries=MAX_VERIFIED,
        error_words="slip over the hold in body sizes",
        prefer=changed,  # of equal counted work, the fewest changes to the model's own settings
        tie_words="ranked after it as they change more settings, slip more or are listed later in the sweep",
    )
    if pick.found:
        return pick, passed[-1]
    return dataclasses.replace(pick, text=_floor(study, tol, len(candidates))), ()


def _floor(study: CaseStudy, tol: float, within: int) -> str:
    """Why no swept setting holds the body within tol, in words."""
    finite = [r for r in study.runs if r.run.valid]
    if not finite:
        return f"No swept setting holds it within {tol:g} body sizes: every run diverged."
    best = min(finite, key=lambda r: r.error)
    closest = (
        f"the closest is {study.describe(best.settings)} with {best.integrator} at dt = {best.dt:g} s, predicted"
        f" slip {best.error:.2g} body sizes"
    )
    if within:
        return (
            f"{within} swept settings predict a slip within {tol:g} body sizes, but none holds it over a run of the"
            f" whole hold ({min(within, MAX_VERIFIED)} tried): its creep grows later in the hold; {closest}."
        )
    return (
        f"No swept setting holds it within {tol:g} body sizes over the hold: {closest}. Larger impratio, more NoSlip"
        " iterations or a stiffer grip (more squeeze, more friction) are the next things to try."
    )


def friction_settings(
    model: str | os.PathLike[str],
    scenarios: Sequence[str] | None = None,
    *,
    tol: float | None = None,
    bodies: Sequence[str] = (),
    hold_s: float | None = None,
    keyframe: str | int | None = None,
    integrators: Sequence[str] | None = None,
    dts: Sequence[float] | None = None,
    executor: Executor | None = None,
    **parameters: float,
) -> FrictionSettings:
    """MuJoCo's friction settings: a scene's exact dry-friction cases, or the creep of what dry friction holds in a
    model file (`springlab friction-settings SCENE | MODEL.xml`).

    Parameters
    ----------
    model
        a scene that declares dry-friction cases (e.g. "friction"), or the path of a model file (MJCF, URDF).
    scenarios
        a scene's cases (None: all); not for a model file.
    tol
        a scene: the relative error each case's pick must meet (None: no picks); a model file: the slip allowed
        over the hold, in body sizes [-] (None: DEFAULT_TOL, 1 mm for a 40 mm box).
    bodies
        a model file: the held bodies' names (empty: found).
    hold_s
        a model file: how long they must be held [s] (None: 10 s).
    keyframe
        a model file: where the hold starts (None: the first keyframe).
    integrators, dts
        the integrators and timesteps [s] swept (None: the scene's, or the model's own and its half).
    executor
        where the runs go (None: here).
    **parameters
        a scene's parameters in SI units (not the swept settings); not for a model file.

    Returns
    -------
    FrictionSettings
        the study: per case its runs, model errors, Pareto front and pick; a model file's also its `hold`.

    Raises
    ------
    BadInputError
        as `springlab.studies.friction_settings.friction_settings` (a scene) or `friction_hold` (a model file);
        a scene's options given with a model file, or a model file's with a scene.

    Examples
    --------
    >>> import springlab
    >>> study = springlab.friction_settings("tests/data/gripper.xml", hold_s=60)  # doctest: +SKIP
    >>> study.hold.bodies[0].creep_velocity_m_s  # doctest: +SKIP
    0.00835
    """
    overrides = keyword_parameters("friction_settings", parameters)
    if not model_files.is_model_file(model):
        given = [
            name
            for name, value in (("bodies", bodies), ("hold_s", hold_s), ("keyframe", keyframe))
            if value not in (None, (), [])
        ]
        if given:
            raise BadInputError(f"{given[0]} applies to a model file (MODEL.xml), not to the scene {model!r}")
        return scene_study.friction_settings(
            str(model), scenarios, tol=tol, integrators=integrators, dts=dts, executor=executor, **overrides
        )
    if scenarios or overrides:
        raise BadInputError(f"scenarios and parameters apply to a scene, not to a model file ({os.fspath(model)})")
    return friction_hold(
        model,
        bodies=bodies,
        hold_s=DEFAULT_HOLD_S if hold_s is None else hold_s,
        keyframe=keyframe,
        tol=DEFAULT_TOL if tol is None else tol,
        integrators=integrators,
        dts=dts,
        executor=executor,
    )
