"""What MuJoCo does with a model at its operating point, measured in one pass and kept as frozen facts.

A study that judges a model at its point (springlab.studies.audit) first settles where its runs start
(`start_near`: a scenario's state, else the point perturbed by a seeded pattern, refused where MuJoCo itself
would reject it), then asks MuJoCo three things there (`PointFacts.measure`):

* the fine run from the start (`springlab.exact.constraints.watch`): the peak speed, and every constraint
  that becomes active along it;
* where the one-step map is the dynamics (nothing active at the point or along the fine run), each
  integrator's measured map limit and the map just above it (`springlab.exact.map_limits.map_limit`);
* where the point drifts by itself over the duration (|qvel| T + |qacc| T^2 / 2 beyond a given bound), the run
  from the point itself at the model's own setting, unperturbed, its controls held: the motion that keeps it
  from rest (a body dry friction holds creeping, or motion dying out).

The study judges the facts afterwards (whether the point is at rest, what creeps, which limits runs confirm),
so the measuring is one pass through MuJoCo rather than one per verdict.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import mujoco
import numpy as np

from springlab.errors import BadInputError, DivergedError
from springlab.exact.constraints import Watch, watch
from springlab.exact.map_limits import MapLimit, map_limit
from springlab.exact.model_at_point import ModelAtPoint
from springlab.sim.simulate import INTEGRATORS, Setup, Trajectory, beyond_mujoco_limits

_NAMES = {value: name for name, value in INTEGRATORS.items()}

#: where a start comes from
PERTURBED, SCENARIO_START = "perturbed operating point", "scenario start"


@dataclasses.dataclass(frozen=True)
class Start:
    """Where every run from the model at its point starts (`start_near`).

    Attributes
    ----------
    setup
        the initial state and held control of every run.
    control_offset
        every actuator's control offset as a fraction of its half range [-] (None: no actuator, or a scene's
        scenario start).
    source
        PERTURBED ("perturbed operating point") or SCENARIO_START ("scenario start").
    """

    setup: Setup
    control_offset: float | None
    source: str

    @property
    def perturbed(self) -> bool:
        """Whether the start is the perturbed operating point (not a scene's scenario start)."""
        return self.source == PERTURBED


def start_near(at: ModelAtPoint, perturb: float, duration: float, scenario: Setup | None = None) -> Start:
    """Every run's start: a scenario's state where it differs from the operating point, else the perturbed
    operating point (`perturbed_start`).

    Raises
    ------
    BadInputError
        MuJoCo itself rejects the start (a position, velocity or acceleration past 1e10).
    """
    point = at.point
    start = None
    if scenario is not None and scenario.qpos is not None:
        qvel = np.asarray(scenario.qvel if scenario.qvel is not None else point.qvel, float)
        qpos = np.asarray(scenario.qpos, float)
        if np.any(qpos != point.qpos) or np.any(qvel != point.qvel):  # a scenario driven by inputs alone does not
            start = Start(Setup(qpos, qvel, point.act, point.ctrl), None, SCENARIO_START)  # move here: perturb it
    start = start or perturbed_start(at, perturb, duration)
    setup = start.setup
    bad = beyond_mujoco_limits(at.model, setup.qpos, setup.qvel, setup.act, setup.control)
    if bad is not None:
        raise BadInputError(f"--perturb {perturb:g} gives {bad} at the start, past MuJoCo's limit; use a smaller one")
    return start


def perturbed_start(at: ModelAtPoint, perturb: float, duration: float) -> Start:
    """The operating point moved by between perturb / 2 and perturb [m or rad] along every degree of freedom,
    given a velocity of between perturb / duration / 2 and perturb / duration [m/s or rad/s] along every one
    (so a model with no position-dependent force moves too), and, for an actuated model, every control offset
    by perturb x its half range (1 where unlimited), held. Signs and sizes are seeded, so studies repeat."""
    model, point = at.model, at.point
    rng = np.random.default_rng(0)

    def pattern(size: int) -> np.ndarray:
        return rng.uniform(0.5, 1.0, size) * rng.choice([-1.0, 1.0], size)

    qpos = point.qpos.copy()
    mujoco.mj_integratePos(model, qpos, perturb * pattern(model.nv), 1.0)
    qvel = point.qvel + perturb / duration * pattern(model.nv)
    ctrl = point.ctrl.copy()
    offset = None
    if model.nu and perturb > 0:
        offset = perturb
        low, high = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
        limited = np.asarray(model.actuator_ctrllimited, bool) & (high > low)
        half = np.where(limited, 0.5 * (high - low), 1.0)
        ctrl = ctrl + perturb * half * pattern(model.nu)
        ctrl = np.where(limited, np.clip(ctrl, low, high), ctrl)
    return Start(Setup(qpos, qvel, point.act.copy(), ctrl), offset, PERTURBED)


@dataclasses.dataclass(frozen=True, eq=False)
class PointFacts:
    """What MuJoCo does at and near a model's operating point (module docstring).

    Attributes
    ----------
    watch
        the fine run from the start: peak speed [m/s or rad/s], constraints active along it.
    drift_m
        how far the point moves by itself over the duration [m or rad] (`ConstraintState.drift`).
    rest
        the run from the point at the model's own setting over the duration, or the DivergedError it raised
        (None: the point's drift is within the bound given, so it was not run).
    maps
        integrator -> its measured one-step-map limit (None: something is active at the point or along the fine
        run, so the map is not the dynamics and was not measured).
    """

    watch: Watch
    drift_m: float
    rest: Trajectory | DivergedError | None
    maps: Mapping[str, MapLimit] | None

    @property
    def smooth(self) -> bool:
        """Nothing is active at the point or along the fine run: MuJoCo's one-step map is the dynamics."""
        return self.maps is not None

    @classmethod
    def measure(
        cls,
        at: ModelAtPoint,
        start: Setup,
        duration: float,
        *,
        guesses: Mapping[str, float | None],
        above: float,
        rest_within: float,
    ) -> PointFacts:
        """The facts at `at` for runs from `start` over `duration` [s].

        Parameters
        ----------
        at
            the model at its operating point.
        start
            where the fine run starts (the study's perturbed point, or a scenario's state).
        duration
            of the runs [s]; also the largest timestep the map scans reach.
        guesses
            integrator -> its predicted limit [s] (None: no prediction): the integrators whose map limits are
            measured, each scan seeded with its guess.
        above
            where each map is read above its limit, as a multiple of it [-] (where a study confirms it).
        rest_within
            the drift [m or rad] within which the point counts as at rest (no run from it).
        """
        seen = watch(at.model, start, duration)
        maps = None
        if at.constraints.smooth and seen.along.smooth:
            maps = {name: map_limit(at, name, duration, guess, above) for name, guess in guesses.items()}
        drift = at.constraints.drift(duration)
        rest: Trajectory | DivergedError | None = None
        if drift > rest_within:  # from the point itself, controls held (held.run_hold's run)
            own = at.model.opt
            try:
                rest = at.simulate(_NAMES[int(own.integrator)], float(own.timestep), duration)
            except DivergedError as error:
                rest = error
        return cls(seen, drift, rest, maps)
