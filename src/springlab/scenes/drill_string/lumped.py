"""The N-element string as MuJoCo compiled it, solved exactly: M, K read back, modes, stick and slip.

`LumpedString.of(model)` reads the diagonal mass matrix (the rotors' inertias about their hinges) and
the stiffness matrix (every element tendon's k c c^T, c its joint coefficients) from the compiled
model, and the bit's frictionloss. Its exact answers are the ones the MuJoCo run is held to, so the
integration error is measured apart from the discretization error (the gap between these and the
continuum, springlab.scenes.drill_string.continuum):

* `modes`: the generalized eigenproblem K phi = w^2 M phi (the top drive's rigid rotation dropped).
* `flow`: q(t), v(t) of M q'' + K q = f, f constant, in closed form per mode (`ModalFlow`).
* `stick_slip`: the bit stuck (its hinge held) until the string's torque on it reaches the friction
  torque, then slipping against a constant Coulomb torque until its speed falls to zero, where it sticks
  again if the string's torque is within the friction torque, or turns; each phase is the exact flow,
  each event a root of an exact function (brentq on a grid finer than the fastest mode).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import mujoco
import numpy as np
import scipy.linalg


def _optimize():  # noqa: ANN202 - the module
    """scipy.optimize, imported on first use: every command imports the scene registry, which must stay light."""
    import scipy.optimize

    return scipy.optimize


#: joint names of the top drive and the bit; rotors in between are e1 ... e<N-1>
TOP, BIT = "top", "bit"
#: the root-finding grid samples every phase at this fraction of the fastest mode's period
GRID_PER_PERIOD = 16


def joint_names(model: mujoco.MjModel) -> list[str]:
    """The string's hinges from the top drive down: top, e1, ..., e<N-1>, bit."""
    rotors = sum(1 for j in range(model.njnt) if (model.joint(j).name or "").startswith("e"))
    return [TOP, *(f"e{i}" for i in range(1, rotors + 1)), BIT]


@dataclasses.dataclass(frozen=True)
class ModalFlow:
    """Exact motion of M q'' + K q = f (f constant) from (q0, v0), mode by mode.

    With mass-normalized modes Phi (Phi^T M Phi = I, Phi^T K Phi = diag w^2) each modal coordinate is
    eta(t) = eta0 cos wt + eta0' sin(wt)/w + g (1 - cos wt)/w^2, written with sinc so a rigid mode
    (w = 0: eta0 + eta0' t + g t^2/2) needs no special case.

    Attributes
    ----------
    mass, stiffness
        (n, n) M [kg m^2] and K [N m/rad].
    omega
        (n,) w [rad/s], ascending (rigid modes 0).
    shapes
        (n, n) Phi, mass-normalized columns.
    """

    mass: np.ndarray
    stiffness: np.ndarray
    omega: np.ndarray
    shapes: np.ndarray

    @classmethod
    def of(cls, mass: np.ndarray, stiffness: np.ndarray) -> ModalFlow:
        """The modes of (M, K) (M diagonal positive, K symmetric positive semi-definite)."""
        squared, shapes = scipy.linalg.eigh(stiffness, mass)
        return cls(mass, stiffness, np.sqrt(np.clip(squared, 0.0, None)), shapes)

    def state(
        self, time: np.ndarray, q0: np.ndarray, v0: np.ndarray, force: np.ndarray, rows: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q, v) at `time` [s] after the start, (len(time), len(rows)) each; rows None: every coordinate."""
        t = np.asarray(time, float)[:, None]
        w = self.omega[None, :]
        eta0 = self.shapes.T @ (self.mass @ q0)
        rate0 = self.shapes.T @ (self.mass @ v0)
        g = self.shapes.T @ force
        sine = t * np.sinc(w * t / np.pi)  # sin(wt)/w
        versine = 0.5 * t**2 * np.sinc(w * t / (2 * np.pi)) ** 2  # (1 - cos wt)/w^2
        cosine = np.cos(w * t)
        eta = eta0 * cosine + rate0 * sine + g * versine
        rate = -eta0 * w**2 * sine + rate0 * cosine + g * sine
        shapes = self.shapes if rows is None else self.shapes[rows]
        return eta @ shapes.T, rate @ shapes.T


@dataclasses.dataclass(frozen=True)
class Phase:
    """One phase of the exact stick-slip motion.

    Attributes
    ----------
    start, end
        [s].
    kind
        'stuck' or 'slip'.
    direction
        +1 or -1 while slipping (the friction torque is -direction T_f), 0 stuck.
    q0, v0
        the full state at `start` (every hinge, top first) [rad, rad/s].
    """

    start: float
    end: float
    kind: str
    direction: float
    q0: np.ndarray
    v0: np.ndarray


@dataclasses.dataclass(frozen=True)
class StickSlipSolution:
    """The exact motion of the lumped string under dry friction at the bit (`LumpedString.stick_slip`).

    Attributes
    ----------
    phases
        the phases, in time order.
    events
        [(time [s], 'slip' | 'stick' | 'reverse')].
    peak_speed, peak_time
        the bit's largest speed [rad/s] and when [s].
    """

    phases: tuple[Phase, ...]
    events: tuple[tuple[float, str], ...]
    peak_speed: float
    peak_time: float

    def first(self, kind: str) -> float:
        """The first event of `kind` [s], nan if none."""
        return next((t for t, k in self.events if k == kind), math.nan)


@dataclasses.dataclass(frozen=True)
class LumpedString:
    """The compiled model's string: M, K, the bit's friction and the drive.

    Attributes
    ----------
    names
        hinges from the top drive down.
    mass
        (n,) the rotors' inertias about their hinges [kg m^2] (M is diagonal).
    stiffness
        (n, n) K [N m/rad].
    friction
        the bit's frictionloss [N m].
    drive_gear
        the top drive motor's gear [N m per unit control].
    """

    names: tuple[str, ...]
    mass: np.ndarray
    stiffness: np.ndarray
    friction: float
    drive_gear: float

    @classmethod
    def of(cls, model: mujoco.MjModel) -> LumpedString:
        """Read M, K, the bit's frictionloss and the drive's gear back from a compiled tendon-encoded model."""
        names = joint_names(model)
        index = {int(model.joint(name).dofadr[0]): i for i, name in enumerate(names)}
        mass = np.array([float(model.body_inertia[model.jnt_bodyid[model.joint(name).id]][2]) for name in names])
        stiffness = np.zeros((len(names), len(names)))
        for t in range(model.ntendon):
            coefficients = np.zeros(len(names))
            for w in range(model.tendon_adr[t], model.tendon_adr[t] + model.tendon_num[t]):
                joint = int(model.wrap_objid[w])
                coefficients[index[int(model.jnt_dofadr[joint])]] += float(model.wrap_prm[w])
            stiffness += float(model.tendon_stiffness[t]) * np.outer(coefficients, coefficients)
        bit = int(model.joint(BIT).dofadr[0])
        return cls(
            names=tuple(names),
            mass=mass,
            stiffness=stiffness,
            friction=float(model.dof_frictionloss[bit]),
            drive_gear=float(model.actuator_gear[model.actuator("drive").id][0]),
        )

    @property
    def size(self) -> int:
        """Hinges (the top drive included)."""
        return len(self.names)

    def drive_control(self, acceleration: float) -> float:
        """The control that accelerates the top drive at `acceleration` [rad/s^2] (its inertia over the gear)."""
        return acceleration * self.mass[0] / self.drive_gear

    def drive_torque(self, control: float) -> np.ndarray:
        """(n,) generalized force [N m] of the drive at `control`."""
        force = np.zeros(self.size)
        force[0] = control * self.drive_gear
        return force

    def bit_torque(self, q: np.ndarray) -> np.ndarray:
        """The string's torque on the bit [N m] at positions q (..., n): -(K q)_bit."""
        return -(np.asarray(q) @ self.stiffness[-1])

    # -- modes ----------------------------------------------------------------

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """(w [rad/s], shapes (n, count)) of the flexible modes, slowest first (the rigid rotation dropped).

        Shapes are scaled to 1 at the bit.
        """
        flow = ModalFlow.of(np.diag(self.mass), self.stiffness)
        omega, shapes = flow.omega[1:], flow.shapes[:, 1:]
        return omega, shapes / shapes[-1]

    # -- stick and slip ------------------------------------------------------------

    def stick_slip(self, duration: float, control: float, ramp_time: float) -> StickSlipSolution:
        """The exact motion from rest: the drive at `control` until `ramp_time` [s], then 0; bit under friction.

        Parameters
        ----------
        duration
            [s].
        control
            the drive's control while it spins up (`drive_control`).
        ramp_time
            when the drive's torque ends [s] (on the run's step grid).
        """
        n = self.size
        full = ModalFlow.of(np.diag(self.mass), self.stiffness)
        held = ModalFlow.of(np.diag(self.mass[:-1]), self.stiffness[:-1, :-1])
        fastest = float(full.omega[-1])
        spacing = 2 * math.pi / fastest / GRID_PER_PERIOD
        q, v, t = np.zeros(n), np.zeros(n), 0.0
        stuck = self.friction > 0
        direction = 0.0
        phases: list[Phase] = []
        events: list[tuple[float, str]] = []
        peak = (0.0, 0.0)
        while t < duration * (1 - 1e-14):
            drive = control if t < ramp_time * (1 - 1e-14) else 0.0
            end = min(duration, ramp_time) if t < ramp_time * (1 - 1e-14) else duration
            force = self.drive_torque(drive)
            if stuck:
                # the bit's hinge held at q[-1]: the rest moves, pulled by K[:, bit] q_bit
                pinned = force[:-1] - self.stiffness[:-1, -1] * q[-1]

                def torque(s: np.ndarray, q=q, v=v, pinned=pinned, t0=t) -> np.ndarray:
                    qs, _ = held.state(np.atleast_1d(s) - t0, q[:-1], v[:-1], pinned)
                    return -(qs @ self.stiffness[-1, :-1]) - self.stiffness[-1, -1] * q[-1]

                at = _first_root(lambda s: np.abs(torque(s)) - self.friction, t, end, spacing)
                stop = end if at is None else at
                phases.append(Phase(t, stop, "stuck", 0.0, q.copy(), v.copy()))
                qs, vs = held.state(np.array([stop - t]), q[:-1], v[:-1], pinned)
                q = np.append(qs[0], q[-1])
                v = np.append(vs[0], 0.0)
                if at is not None:
                    direction = math.copysign(1.0, float(torque(np.array([at]))[0]))
                    stuck = False
                    events.append((at, "slip"))
                t = stop
                continue
            slipping = force.copy()
            slipping[-1] -= direction * self.friction

            def bit_speed(s: np.ndarray, q=q, v=v, slipping=slipping, t0=t, sign=direction) -> np.ndarray:
                """The bit's speed along the slip direction [rad/s]."""
                return sign * full.state(np.atleast_1d(s) - t0, q, v, slipping, rows=np.array([n - 1]))[1][:, 0]

            zero = None
            if self.friction > 0:  # a free bit (no friction) never sticks: it just turns with the string
                zero = _first_root(lambda s: -bit_speed(s), t, end, spacing)
            stop = end if zero is None else zero
            phases.append(Phase(t, stop, "slip", direction, q.copy(), v.copy()))
            best_t, best = maximum(bit_speed, t, stop, spacing)
            if best > peak[1]:
                peak = (best_t, best)
            qs, vs = full.state(np.array([stop - t]), q, v, slipping)
            q, v, t = qs[0], vs[0], stop
            if zero is None:
                continue
            v[-1] = 0.0
            if abs(float(self.bit_torque(q))) <= self.friction:
                stuck = True
                events.append((t, "stick"))
            else:
                direction = -direction
                events.append((t, "reverse"))
        return StickSlipSolution(tuple(phases), tuple(events), peak[1], peak[0])

    def slowdown_time(self, solution: StickSlipSolution, level: float, control: float, ramp_time: float) -> float:
        """The first time [s] after the first breakaway that the bit's speed falls below `level` [rad/s] (nan: never).

        What a simulation can observe of a re-stick (its friction is regularized, so a stuck bit creeps): the
        bit slowing to nearly nothing, whether it then sticks or turns.
        """
        full = ModalFlow.of(np.diag(self.mass), self.stiffness)
        spacing = 2 * math.pi / float(full.omega[-1]) / GRID_PER_PERIOD
        above = False
        for phase in solution.phases:
            if phase.kind != "slip":
                if above:
                    return phase.start
                continue
            force = self.drive_torque(control if phase.start < ramp_time * (1 - 1e-14) else 0.0)
            force[-1] -= phase.direction * self.friction

            def speed(s: np.ndarray, phase: Phase = phase, force: np.ndarray = force) -> np.ndarray:
                rows = np.array([self.size - 1])
                return np.abs(full.state(np.atleast_1d(s) - phase.start, phase.q0, phase.v0, force, rows=rows)[1][:, 0])

            count = max(int(math.ceil((phase.end - phase.start) / spacing)), 2)
            grid = np.linspace(phase.start, phase.end, count + 1)
            values = speed(grid) - level
            for i in range(len(grid)):
                if values[i] >= 0:
                    above = True
                elif above:
                    return (
                        float(
                            _optimize().brentq(
                                lambda s: float(speed(np.array([s]))[0]) - level,
                                grid[i - 1],
                                grid[i],
                                xtol=1e-15,
                                rtol=1e-15,
                            )
                        )
                        if i > 0
                        else float(grid[0])
                    )
        return math.nan

    def solution_at(
        self, solution: StickSlipSolution, time: np.ndarray, control: float, ramp_time: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q, v) of every hinge at `time` [s] along a stick-slip solution, (len(time), n) each."""
        time = np.asarray(time, float)
        q_out, v_out = np.zeros((len(time), self.size)), np.zeros((len(time), self.size))
        full = ModalFlow.of(np.diag(self.mass), self.stiffness)
        held = ModalFlow.of(np.diag(self.mass[:-1]), self.stiffness[:-1, :-1])
        for phase in solution.phases:
            last = phase is solution.phases[-1]
            inside = (time >= phase.start) & ((time <= phase.end) if last else (time < phase.end))
            if not inside.any():
                continue
            drive = control if phase.start < ramp_time * (1 - 1e-14) else 0.0
            force = self.drive_torque(drive)
            s = time[inside] - phase.start
            if phase.kind == "stuck":
                pinned = force[:-1] - self.stiffness[:-1, -1] * phase.q0[-1]
                qs, vs = held.state(s, phase.q0[:-1], phase.v0[:-1], pinned)
                q_out[inside, :-1], v_out[inside, :-1] = qs, vs
                q_out[inside, -1] = phase.q0[-1]
            else:
                force[-1] -= phase.direction * self.friction
                q_out[inside], v_out[inside] = full.state(s, phase.q0, phase.v0, force)
        return q_out, v_out


def _first_root(function, start: float, end: float, spacing: float) -> float | None:
    """The first t in (start, end] where function(t) (vectorized) reaches 0 from below, or None."""
    count = max(int(math.ceil((end - start) / spacing)), 2)
    grid = np.linspace(start, end, count + 1)
    values = function(grid)
    values[0] = min(values[0], -0.0)  # the phase starts below its threshold
    above = np.flatnonzero(values[1:] >= 0)
    if not above.size:
        return None
    i = int(above[0]) + 1
    low, high = float(grid[i - 1]), float(grid[i])
    if function(np.array([low]))[0] >= 0:
        return low
    return float(_optimize().brentq(lambda s: float(function(np.array([s]))[0]), low, high, xtol=1e-15, rtol=1e-15))


def maximum(
    function: Callable[[np.ndarray], np.ndarray], start: float, end: float, spacing: float
) -> tuple[float, float]:
    """(t [s], value) of the largest value of `function` (vectorized in t) on [start, end] [s].

    A grid of `spacing` [s] (finer than a quarter of the fastest oscillation, so no peak falls between two
    samples unseen) finds the best sample; scipy's bounded Brent search between its neighbours then finds the
    continuous maximum to 1e-13 s, so the value is the function's own to round-off (a smooth peak is flat).
    """
    count = max(int(math.ceil((end - start) / spacing)), 2)
    grid = np.linspace(start, end, count + 1)
    values = function(grid)
    i = int(np.argmax(values))
    best_t, best = float(grid[i]), float(values[i])
    low, high = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, count)])
    if high > low:
        found = _optimize().minimize_scalar(
            lambda s: -float(function(np.array([s]))[0]), bounds=(low, high), method="bounded", options={"xatol": 1e-13}
        )
        if -found.fun > best:
            best_t, best = float(found.x), float(-found.fun)
    return best_t, best
