"""Families of runs a figure compares: one scenario from several displacements, or at several damping ratios.

A study, not a plot: every member is simulated here, and springlab.plots.run only draws the
family it is given (`plots.run.phase_family`, `plots.run.zeta_family`).

* `run_phase_family(result)`: the scenario's phase trajectories released from several
  initial displacements (Fig. 5.11); where a separatrix crosses v = 0 on the release's
  side, the displacements straddle it, so bounded and escaping (or one-well and two-well)
  orbits appear side by side.
* `run_zeta_family(scene, scenario)`: the chapter's damping-ratio slider as runs at
  zeta = 0 ... 2, each with its exact reference.

Positions in [m] (hinges [rad]), velocities in [m/s] ([rad/s]).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, scenes, tables
from springlab.errors import BadInputError, DivergedError
from springlab.files import json_ready
from springlab.runs.run import Result, run_scenario
from springlab.scenes.base import Case
from springlab.sim.simulate import Setup

#: damping ratios of the zeta family (the chapter's slider from undamped to overdamped)
ZETAS = (0.0, 0.1, 0.25, 0.5, 1.0, 2.0)
#: initial displacements of a family, as fractions of the scenario's (or of the separatrix's)
FAMILY_FRACTIONS = (0.25, 0.5, 0.75, 1.0)
FAMILY_SEPARATRIX_FRACTIONS = (0.3, 0.6, 0.9, 1.1, 1.3)

#: separatrix branches as (x [m], v [m/s]) arrays
Curves = list[tuple[np.ndarray, np.ndarray]]

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure


def _read_only(values: np.ndarray | None) -> np.ndarray | None:
    """A read-only view of `values` (None stays None)."""
    if values is None:
        return None
    view = np.asarray(values).view()
    view.setflags(write=False)
    return view


@dataclasses.dataclass(frozen=True)
class Member:
    """One release of a phase family.

    Attributes
    ----------
    start
        initial displacement [m] (hinges [rad]).
    x, v
        position [m] and velocity [m/s] series; None when the member diverged.
    stopped
        the scenario's stop condition ended it early (e.g. an escape to infinity).
    fraction
        the start as a fraction of the scenario's displacement, or of the distance to the separatrix.
    """

    start: float
    x: np.ndarray | None
    v: np.ndarray | None
    stopped: bool
    fraction: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", _read_only(self.x))
        object.__setattr__(self, "v", _read_only(self.v))

    @property
    def diverged(self) -> bool:
        """Whether the member blew up (it has no series)."""
        return self.x is None or self.v is None

    def to_dict(self) -> dict[str, Any]:
        """start [m], fraction [-], stopped, diverged (the series are in PhaseFamily.to_pandas())."""
        return {"start": self.start, "fraction": self.fraction, "stopped": self.stopped, "diverged": self.diverged}


@dataclasses.dataclass(frozen=True, repr=False)
class PhaseFamily(display.Shown):
    """The phase trajectories of one scenario from several initial displacements.

    Attributes
    ----------
    result
        the run the family is built around (its model, parameters, integrator and dt).
    joint
        the one reported joint.
    equilibria, separatrices
        of the unforced phase plane (Scene.equilibria, Scene.separatrices).
    center
        the stable equilibrium the displacements are measured from [m].
    straddles
        the starts lie on both sides of a separatrix.
    members
        one per start, in order.
    """

    result: Result
    joint: str
    equilibria: list[dict]
    separatrices: Curves
    center: float
    straddles: bool
    members: tuple[Member, ...]

    def _shown(self) -> display.Summary:
        """The family as a notebook shows it: the releases, which stopped, and the run they come from."""
        return display.Summary(
            "PhaseFamily",
            f"{self.result.scene} / {self.result.scenario}: {self.joint}",
            f"{len(self.members)} releases",
            None,
            f"{sum(m.stopped for m in self.members)} of {len(self.members)} stopped"
            + ("; the releases straddle a separatrix" if self.straddles else ""),
            (display.Fact("centre", self.center), display.Fact("equilibria", len(self.equilibria))),
            display.table(
                ("start", "fraction [-]", "stopped"), [(m.start, m.fraction, m.stopped) for m in self.members]
            ),
        )

    def plot(self) -> Figure:
        """The phase trajectories of the releases (`springlab.plots.run.phase_family`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """The family's facts (plain JSON values): scene, scenario, integrator, dt [s], joint, center [m],
        straddles, equilibria, members (see Member.to_dict); the series are in `to_pandas()`."""
        return json_ready(
            {
                "scene": self.result.scene,
                "scenario": self.result.scenario,
                "integrator": self.result.integrator,
                "dt": self.result.dt,
                "joint": self.joint,
                "center": self.center,
                "straddles": self.straddles,
                "equilibria": self.equilibria,
                "members": [m.to_dict() for m in self.members],
            }
        )

    def to_pandas(self) -> pandas.DataFrame:
        """The members' phase trajectories in long form, one row per member and step: member (its
        index), start [m], x [m], v [m/s] (hinges [rad], [rad/s]); diverged members have no rows (needs pandas)."""
        return tables.to_pandas(
            {
                "member": np.concatenate([np.full(len(m.x), i) for i, m in enumerate(self.members) if m.x is not None]),
                "start": np.concatenate([np.full(len(m.x), m.start) for m in self.members if m.x is not None]),
                "x": np.concatenate([m.x for m in self.members if m.x is not None]),
                "v": np.concatenate([m.v for m in self.members if m.v is not None]),
            }
        )


@dataclasses.dataclass(frozen=True, repr=False)
class ZetaFamily(display.Shown):
    """One scenario at several damping ratios.

    Attributes
    ----------
    scene, scenario
        the names run.
    damping_per_ratio
        damping d [N s/m] per unit damping ratio of the scene's single mode (d = zeta x this).
    runs
        (zeta [-], Result) for every ratio, in order.
    """

    scene: str
    scenario: str
    damping_per_ratio: float
    runs: tuple[tuple[float, Result], ...]

    @property
    def joint(self) -> str:
        """The one reported joint."""
        return next(iter(self.runs[0][1].pos))

    def _shown(self) -> display.Summary:
        """The family as a notebook shows it: whether every run passed, then one row per damping ratio."""
        passed = [r.passed for _, r in self.runs]
        return display.Summary(
            "ZetaFamily",
            f"{self.scene} / {self.scenario}",
            f"{sum(p is True for p in passed)} of {len(passed)} passed",
            all(p is not False for p in passed),
            f"the scenario at {len(self.runs)} damping ratios",
            (display.Fact("damping per unit ratio", self.damping_per_ratio, "N s/m"),),
            display.table(
                ("zeta [-]", "verdict", "max rel error [-]", "tolerance [-]"),
                [
                    (zeta, None if r.verdict is None else str(r.verdict), r.max_rel_error, r.tolerance)
                    for zeta, r in self.runs
                ],
            ),
        )

    def plot(self) -> Figure:
        """x(t) and the phase plane at every damping ratio, exact curves dashed (`springlab.plots.run.zeta_family`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """scene, scenario, damping_per_ratio [N s/m], runs: [{"zeta", "run": summary.json of that run}]."""
        return json_ready(
            {
                "scene": self.scene,
                "scenario": self.scenario,
                "damping_per_ratio": self.damping_per_ratio,
                "runs": [{"zeta": zeta, "run": run.to_dict()} for zeta, run in self.runs],
            }
        )

    def to_pandas(self) -> pandas.DataFrame:
        """The runs in long form, one row per ratio and step: zeta [-], then each run's trajectory.csv
        columns (time [s] = k dt, `<joint>_pos`, `<joint>_vel`, `<joint>_pos_ref`, `<joint>_vel_ref`) (needs pandas)."""
        parts = []
        for zeta, run in self.runs:
            columns = run.columns()
            steps = len(columns["time"])
            parts.append({"zeta": np.full(steps, zeta), **columns, "time": np.arange(steps) * float(run.dt)})
        return tables.to_pandas({name: np.concatenate([part[name] for part in parts]) for name in parts[0]})


def separatrix_crossings(curves: Curves) -> list[float]:
    """Positions where the separatrices meet v = 0 (branch ends at zero velocity) [m]."""
    out = []
    for x, v in curves:
        scale = max(float(np.max(np.abs(v))), 1e-300)
        for i in (0, -1):
            if abs(v[i]) <= 1e-6 * scale:
                out.append(float(x[i]))
    return sorted(set(out))


def _family_displacements(
    result: Result, equilibria: list[dict], separatrices: Curves
) -> tuple[float, list[float], list[float], bool]:
    """(equilibrium [m], initial displacements [m], their fractions [-], straddles a separatrix) for a family."""
    joint = next(iter(result.pos))
    x0 = float(result.pos[joint][0])
    stable = [e["x"] for e in equilibria if e.get("stable")] or [e["x"] for e in equilibria]
    center = min(stable, key=lambda xe: abs(xe - x0))
    offset = x0 - center
    if abs(offset) <= 1e-12 * max(1.0, abs(center)):
        # released at the equilibrium (a launch or a forced run): use the largest excursion
        excursion = result.pos[joint] - center
        offset = float(excursion[np.argmax(np.abs(excursion))])
    direction = 1.0 if offset >= 0 else -1.0
    beyond = [c - center for c in separatrix_crossings(separatrices) if (c - center) * direction > 1e-12]
    if beyond:
        boundary = min(beyond, key=abs)
        fractions = list(FAMILY_SEPARATRIX_FRACTIONS)
        return center, [center + f * boundary for f in fractions], fractions, True
    fractions = list(FAMILY_FRACTIONS)
    return center, [center + f * offset for f in fractions], fractions, False


def _family_members(result: Result, starts: Sequence[float], fractions: Sequence[float]) -> tuple[Member, ...]:
    """The scenario from each initial displacement.

    Each member is the scenario's own model and inputs, released from another
    displacement: through the `x0` parameter where the scene has one (so its
    setup and stop condition, e.g. an escape, see the new start), else by
    moving the joint in the scenario's initial state. Only the trajectory is
    needed, so members run through `simulate` without references or checks;
    a member that diverges has no series.
    """
    scene, scenario = result.case.scene, result.case.scenario
    joint = next(iter(result.pos))
    integrator, dt = result.integrator, result.dt
    steps = result.trajectory.steps
    if result.trajectory.stopped:  # the scenario's own length: bounded members run it all
        steps = max(steps, int(round(scenario.duration / dt)))
    duration = steps * dt
    members: list[Member] = []
    for start, fraction in zip(starts, fractions):
        params = dict(result.parameters)
        if "x0" in scene.parameters:
            params["x0"] = start
        try:
            case = Case.compiled(scene, scenario, params)
            setup = case.setup(steps, dt)
            if "x0" not in scene.parameters:
                model = case.model
                qpos = np.array(setup.qpos if setup.qpos is not None else model.qpos0, float)
                qvel = np.array(setup.qvel if setup.qvel is not None else np.zeros(model.nv), float)
                qpos[model.joint(joint).qposadr[0]] = start
                qvel[model.joint(joint).dofadr[0]] = 0.0
                setup = Setup(qpos=qpos, qvel=qvel, act=setup.act, control=setup.control)
            trajectory = case.simulate(integrator, dt, duration, setup=setup)
        except DivergedError:
            members.append(Member(start, None, None, False, fraction))
            continue
        x, v = case.joint_columns(trajectory)[joint]
        members.append(Member(start, x, v, trajectory.stopped, fraction))
    return tuple(members)


def run_phase_family(result: Result) -> PhaseFamily:
    """The phase trajectories of `result`'s scenario from several initial displacements (Fig. 5.11).

    The displacements are fractions of the scenario's own initial displacement
    from its nearest stable equilibrium; where a separatrix crosses v = 0 on
    that side, they are fractions (0.3 ... 1.3) of the distance to it, so the
    family shows both sides. Each member runs at the result's integrator and dt.

    Parameters
    ----------
    result
        a run of the scenario (springlab.run).

    Raises
    ------
    BadInputError
        The scene has no phase plane for this scenario (several joints or a
        time-dependent field) or no equilibrium to start from.
    """
    field = result.case.phase_field() if len(result.pos) == 1 else None
    equilibria = result.case.equilibria() if field is not None else []
    if field is None or not equilibria:
        raise BadInputError(
            f"plot kind 'family' needs one joint, an autonomous phase field and an equilibrium; "
            f"{result.scene}/{result.scenario} has none (use --kind time or phase)"
        )
    separatrices = result.case.separatrices()
    center, starts, fractions, straddles = _family_displacements(result, equilibria, separatrices)
    return PhaseFamily(
        result=result,
        joint=next(iter(result.pos)),
        equilibria=equilibria,
        separatrices=separatrices,
        center=center,
        straddles=straddles,
        members=_family_members(result, starts, fractions),
    )


def _damping_per_ratio(scene_name: str, scenario_name: str | None, parameters: dict[str, Any]) -> float:
    """Damping [N s/m] per unit damping ratio of the scene's single mode (zeta is linear in d)."""
    # the number of modes first: a two-mode scenario (car pitch_heave) may not even take 'damping'
    case = scenes.case(scene_name, scenario_name, parameters)
    count = len(case.modes())
    if count != 1:
        raise BadInputError(
            f"plot kind 'zeta' needs a one-mode scene; {case.scene.name}/{case.scenario.name} has {count} modes"
            " (use --kind time or phase)"
        )
    modes = scenes.case(scene_name, scenario_name, {**parameters, "damping": 1.0}).modes()
    if len(modes) < 1 or modes[0][1] <= 0:
        raise BadInputError(
            f"plot kind 'zeta' needs a single damped mode; {case.scene.name}/{case.scenario.name} has {len(modes)}"
            " modes"
        )
    return 1.0 / modes[0][1]


def run_zeta_family(
    scene: str,
    scenario: str | None = None,
    *,
    zetas: Sequence[float] = ZETAS,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    **parameters: Any,
) -> ZetaFamily:
    """The scenario at several damping ratios, each run with its exact reference.

    Damping d = zeta x (d per unit zeta), found from the scene's single mode
    (zeta is linear in d for fixed mass and stiffness), so any linear scene
    with a `damping` parameter and one mode works.

    Parameters
    ----------
    scene, scenario
        names (scenario None: the scene's default).
    zetas
        damping ratios [-].
    integrator, dt, duration
        the setting of every run (None: the scenario's; dt and duration in [s]).
    **parameters
        scene parameters in SI units, except `damping` (the family sets it).

    Raises
    ------
    BadInputError
        The scene has no `damping` parameter, no exact linear reference for
        this scenario, or more than one mode; or `damping` was given.
    """
    scene_obj = scenes.get(scene)
    chosen = scene_obj.scenario(scenario)
    if "damping" not in scene_obj.parameters or not chosen.exact:
        raise BadInputError(
            f"plot kind 'zeta' needs a 'damping' parameter and an exact reference; "
            f"{scene}/{chosen.name} has not (use --kind time or phase)"
        )
    if "damping" in parameters:
        raise BadInputError("plot kind 'zeta' sets the damping itself; drop --set damping=...")
    per_ratio = _damping_per_ratio(scene, chosen.name, parameters)
    runs = []
    for zeta in zetas:
        run = run_scenario(
            scene, chosen.name, integrator=integrator, dt=dt, duration=duration, damping=zeta * per_ratio, **parameters
        )
        if len(run.pos) != 1 or not run.ref_pos:
            raise BadInputError(
                f"plot kind 'zeta' needs one joint with an exact reference; "
                f"{scene}/{chosen.name} reports {', '.join(run.pos)}"
            )
        runs.append((float(zeta), run))
    return ZetaFamily(scene=scene, scenario=chosen.name, damping_per_ratio=per_ratio, runs=tuple(runs))
