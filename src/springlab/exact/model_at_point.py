"""A model at its operating point, with what every study asks of it there computed once.

The audit and the frequency response study one compiled model at one operating point many times over:
its forward pass there (constraints, accelerations, sensors), its linearization (M, C, K, A, the modes and
the eigenvectors of A), the continuous-time rates with a held control, and the one-step maps of each
integrator. `ModelAtPoint` is that model and that point in one frozen object; what depends on nothing
else (`data`, `constraints`, `continuous`, `linear`) is computed on first use and kept, so a study passes
one object around instead of a model, a point and a linearization that each callee rebuilds.

    at = ModelAtPoint.at(model, keyframe="home", settle_s=None)
    at.linear.modes, at.constraints.describe(), at.one_step_map("rk4", 1e-3)
    ModelAtPoint(model, another_point)      # the same model elsewhere (a state along a motion)

Nothing here modifies `model`: integrators and timesteps are set on copies (`scratch`).
"""

from __future__ import annotations

import copy
import dataclasses
import functools

import mujoco
import numpy as np

from springlab.exact.constraints import ConstraintState, active_constraints, summarize_constraints
from springlab.exact.linearize import (
    FD_STEP,
    Linearization,
    input_column,
    linearize,
    map_on,
    sensor_rows,
    step_input_column,
)
from springlab.exact.operating_point import OperatingPoint, operating_point, settle
from springlab.sim.simulate import Setup, Trajectory, integrator_id, quiet_mujoco, simulate


@dataclasses.dataclass(frozen=True, eq=False)
class ModelAtPoint:
    """A compiled model at an operating point; its derived facts are computed on first use and kept.

    Attributes
    ----------
    model
        the compiled model (never modified here: `scratch` gives copies to set integrators and timesteps on).
    point
        the operating point: qpos [m, rad, quaternion], qvel [m/s, rad/s], act and ctrl [actuator units].
    step
        finite-difference step of the linearization and the maps [m, rad, m/s, rad/s or activation units].
    """

    model: mujoco.MjModel
    point: OperatingPoint
    step: float = FD_STEP

    @classmethod
    def at(
        cls, model: mujoco.MjModel, keyframe: str | int | None = None, *, settle_s: float | None = None
    ) -> ModelAtPoint:
        """`model` at its keyframe (`operating_point`: by name or index; None: the first, else qpos0 at rest),
        left to move for `settle_s` [s] first where given (`settle`: where a robot comes to rest).

        Raises
        ------
        BadInputError
            no such keyframe, or the model blows up while settling.
        """
        point = operating_point(model, keyframe)
        if settle_s:
            point = settle(model, point, settle_s)
        return cls(model, point)

    @functools.cached_property
    def data(self) -> mujoco.MjData:
        """MjData after `mj_forward` at the point with the model's own options: read it (qacc, contacts,
        sensordata, efc rows); to step from the point, step a `scratch` copy instead."""
        data = mujoco.MjData(self.model)
        with quiet_mujoco():
            self.point.load(self.model, data)
            mujoco.mj_forward(self.model, data)
        return data

    @functools.cached_property
    def constraints(self) -> ConstraintState:
        """What constrains the model at the point: active contacts, joint and tendon limits, equality
        constraints and dry friction, with max |qvel| [m/s or rad/s] and |qacc| [m/s^2 or rad/s^2] there."""
        elements, dry = active_constraints(self.model, self.data)
        qvel = float(np.max(np.abs(self.data.qvel), initial=0.0))
        qacc = float(np.max(np.abs(self.data.qacc), initial=0.0))
        return summarize_constraints(elements, dry, qvel, qacc)

    @functools.cached_property
    def linear(self) -> Linearization:
        """The continuous-time linearization at the point (`springlab.exact.linearize.linearize`): M, C, K
        [SI], A [1/s], its eigenvalues and modes; `linear.eigenvectors` is cached on it too."""
        return linearize(self.model, self.point, step=self.step)

    @functools.cached_property
    def continuous(self) -> mujoco.MjModel:
        """A copy of the model whose forward pass is the continuous-time dynamics (the Euler integrator's:
        'discrete' folds dt^2 K into qacc), for rates and tangent-space arithmetic."""
        work = copy.copy(self.model)
        work.opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
        return work

    @functools.cached_property
    def rates(self) -> np.ndarray:
        """dx/dt = (qvel, qacc, act_dot) at the point, its control held [m/s or rad/s, m/s^2 or rad/s^2,
        activation/s], (2 nv + na,): zero at an equilibrium (the continuous forward pass, `continuous`)."""
        work = self.continuous
        data = mujoco.MjData(work)
        with quiet_mujoco():
            self.point.load(work, data)
            mujoco.mj_forward(work, data)
        return np.concatenate([data.qvel, data.qacc, data.act_dot])

    @functools.cached_property
    def workspace(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """One `scratch()` pair kept on the object for the maps and probes of one study at this point: each
        user sets the integrator and timestep and reloads the point before it steps (not for threads)."""
        return self.scratch()

    def scratch(self, integrator: str | None = None, dt: float | None = None) -> tuple[mujoco.MjModel, mujoco.MjData]:
        """A copy of the model (with `integrator` and timestep `dt` [s] set where given) and an MjData for it
        loaded with the point: for loops that step or difference from the point without touching `model`."""
        work = copy.copy(self.model)
        if integrator is not None:
            work.opt.integrator = integrator_id(integrator)
        if dt is not None:
            work.opt.timestep = dt
        data = mujoco.MjData(work)
        self.point.load(work, data)
        return work, data

    def simulate(self, integrator: str, dt: float, duration: float, start: Setup | None = None) -> Trajectory:
        """A run of the model with `integrator` at timestep `dt` [s] over `duration` [s] from `start` (None: the
        point itself, its control held) (`springlab.sim.simulate.simulate`: the model is not modified).

        Raises
        ------
        DivergedError
            the run blew up.
        """
        if start is None:
            point = self.point
            start = Setup(point.qpos, point.qvel, point.act, point.ctrl if self.model.nu else None)
        return simulate(
            self.model,
            integrator=integrator,
            dt=dt,
            duration=duration,
            qpos=start.qpos,
            qvel=start.qvel,
            act=start.act,
            control=start.control,
        )

    def one_step_map(
        self, integrator: str, dt: float, scratch: tuple[mujoco.MjModel, mujoco.MjData] | None = None
    ) -> np.ndarray:
        """MuJoCo's one-step map Phi (n, n) of `integrator` at timestep `dt` [s] at the point
        (`springlab.exact.linearize.map_on`); `scratch`: a pair from `scratch()` reused across calls
        (its model takes the integrator and timestep), so a scan over dt copies the model once."""
        return self.step_maps(integrator, scratch)(dt)

    def step_maps(self, integrator: str, scratch: tuple[mujoco.MjModel, mujoco.MjData] | None = None) -> StepMaps:
        """`integrator`'s one-step maps at the point as a function of dt (`StepMaps`): its name resolved once,
        for a scan over many timesteps; `scratch` as in `one_step_map`.

        Raises
        ------
        UnknownNameError
            no such integrator.
        """
        return StepMaps(self, integrator_id(integrator), self.scratch() if scratch is None else scratch)

    def input_column(self, kind: str, index: int) -> np.ndarray:
        """b = d(dx/dt)/du (n,) of input `kind` ('ctrl' or 'force') `index` at the point [1/s per input unit]
        (`springlab.exact.linearize.input_column`)."""
        return input_column(self.model, kind, index, self.point, step=self.step)

    def step_input_column(self, integrator: str, kind: str, index: int, dt: float) -> np.ndarray:
        """gamma = d x_{n+1} / d u (n,) of one step of `integrator` at `dt` [s], the input held over it [per
        input unit] (`springlab.exact.linearize.step_input_column`)."""
        return step_input_column(self.model, integrator, kind, index, dt, self.point, step=self.step)

    def sensor_rows(
        self, kind: str, index: int, integrator: str | None = None, dt: float | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(C, d) of the sensors at the point, as one step of `integrator` at `dt` [s] computes them (None:
        the continuous forward pass) (`springlab.exact.linearize.sensor_rows`)."""
        return sensor_rows(self.model, kind, index, self.point, integrator=integrator, dt=dt, step=self.step)


@dataclasses.dataclass(frozen=True, eq=False)
class StepMaps:
    """One integrator's one-step map Phi(dt) (n, n) at a model's operating point, per timestep dt [s]
    (`ModelAtPoint.step_maps`): `maps(dt)` steps the scratch pair, which takes the integrator and dt.

    Attributes
    ----------
    at
        the model at its operating point.
    kind
        MuJoCo's integrator enum value.
    scratch
        the model copy and MjData the maps are taken on (from `ModelAtPoint.scratch`).
    """

    at: ModelAtPoint
    kind: int
    scratch: tuple[mujoco.MjModel, mujoco.MjData]

    def __call__(self, dt: float) -> np.ndarray:
        """Phi(dt) (n, n) [-] at timestep `dt` [s] (`springlab.exact.linearize.map_on`).

        Raises
        ------
        BadInputError
            dt not a finite number > 0.
        """
        work, data = self.scratch
        return map_on(work, self.kind, dt, self.at.point, step=self.at.step, data=data)
