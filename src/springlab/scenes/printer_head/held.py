"""The exact run of the printer head under a held force that is not known in advance (a loop, a long chirp).

The closed loop's force depends on the state, and a chirp switches at every step: neither is a handful of
segments for analytic.linear_response. Both are exact all the same, one step at a time: the two-mass model's
exact step map with the force held (springlab.exact.sampled_loop.held_run), the force computed from the exact
state at each sample. Their tolerance is derived the way springlab.runs.compare derives a linear scene's,
but summed exactly through the held input's switches and, for a loop, back through the law
(sampled_loop.held_run_error): SAFETY x the leading-order global error of the run's integrator, relative to
each column's largest value, the largest of the four columns, plus ROUNDOFF_PER_STEP per step.
Positions [m], velocities [m/s], forces [N], times [s].
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from springlab.exact import sampled_loop
from springlab.scenes.declarations import Reference
from springlab.sim.simulate import ERROR_CONSTANTS, ORDERS, ROUNDOFF_PER_STEP, SAFETY

from .control import belt_plant
from .moves import initial_state

if TYPE_CHECKING:
    from springlab.scenes.base import Case

__all__ = ["TOLERANCE_BASIS", "held_reference", "initial_vector"]

#: why a held run's tolerance is what it is (Reference.tolerance_basis)
TOLERANCE_BASIS = (
    "2 x the leading-order global error of the integrator (C h^p A_z^(p+1) z per step, C = 1/120 for rk4, 1/2"
    " for first-order), carried by the exact step map through every switch of the held force{loop}, relative"
    " to each column's largest value, the largest column + 100 eps per step"
)


def initial_vector(case: Case) -> np.ndarray:
    """x0 = (q_c, q_m, v_c, v_m) [m, m/s] of the case's initial state (moves.initial_state)."""
    q0, v0 = initial_state(case.params)
    return np.concatenate([q0, v0])


def held_reference(
    case: Case,
    time: np.ndarray,
    dt: float,
    states: np.ndarray,
    forces: np.ndarray,
    steps_per_sample: int = 1,
    response: Callable[[], Callable[[int, np.ndarray], float]] | None = None,
) -> Reference:
    """The Reference of an exact held run (`states` x (m + 1, 4), `forces` (m,)) at `time` [s], with its tolerance.

    The tolerance depends on the run's integrator (`Reference.tolerance_of`, computed when asked, once each).

    Parameters
    ----------
    case
        The printer head's case (its plant: control.belt_plant).
    time
        The run's times [s], one per step from 0: the first len(time) states are compared.
    dt
        The run's step [s].
    states, forces
        The exact run (sampled_loop.held_run), at least as long as `time`.
    steps_per_sample, response
        The law's period in steps, and a factory of its linear response to a state error (a fresh one per
        propagation, sampled_loop.held_run_error; None: open loop).
    """
    count = len(time)
    a, b = belt_plant(case.model)
    states, forces = states[:count], forces[: count - 1]
    scales = np.max(np.abs(states), axis=0)
    known: dict[str, float] = {}

    def tolerance_of(integrator: str) -> float:
        if integrator not in known:
            errors = sampled_loop.held_run_error(
                a,
                b,
                dt,
                ORDERS[integrator],
                ERROR_CONSTANTS[integrator],
                states,
                forces,
                steps_per_sample,
                None if response is None else response(),
            )
            relative = np.max(np.abs(errors), axis=0) / np.where(scales > 0, scales, 1.0)
            known[integrator] = SAFETY * float(np.max(relative)) + ROUNDOFF_PER_STEP * (count - 1)
        return known[integrator]

    loop = "" if response is None else " and back through the controller's law at each sample"
    # the plant with the held force as a generator state: the modes the integrator must resolve within a step,
    # for the range in which a leading-order estimate holds (the run is "not validated" outside it)
    system = np.zeros((5, 5))
    system[:4, :4], system[:4, 4] = a, np.asarray(b, dtype=float).reshape(-1)
    q, v = states[:, :2], states[:, 2:]
    return Reference(
        pos={"carriage": q[:, 0], "motor": q[:, 1]},
        vel={"carriage": v[:, 0], "motor": v[:, 1]},
        system=system,
        tolerance_of=tolerance_of,
        tolerance_basis=TOLERANCE_BASIS.format(loop=loop),
    )
