"""A sampled-data controller in a run's loop: what a scene's `Setup.controller` is, and the loop that runs it.

springlab.sim.simulate runs a `Controller` with `closed_loop` instead of an open-loop rollout: at each sample
`mj_forward` (after `mj_step` the sensors hold the state before the last step), the law reads
`sensordata` and sets `ctrl`, held over the sample's steps, one `mj_step` each (so every step is recorded).
springlab.sim.sampled has the sample-by-sample runner and the controller's period in steps.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import mujoco
import numpy as np

__all__ = ["BAD_WARNINGS", "Controller", "Law", "closed_loop"]

#: MuJoCo's warnings that mean a blow-up (it then resets the state silently)
BAD_WARNINGS = [
    int(mujoco.mjtWarning.mjWARN_BADQPOS),
    int(mujoco.mjtWarning.mjWARN_BADQVEL),
    int(mujoco.mjtWarning.mjWARN_BADQACC),
]
#: a controller's law: u_k = law(k, sensordata_k) [actuator units], (nu,), at sample k
Law = Callable[[int, np.ndarray], np.ndarray]
_FULL = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)


@dataclasses.dataclass(frozen=True)
class Controller:
    """A sampled-data controller in a run's loop (`Setup.controller`; springlab.sim.simulate runs it).

    Attributes
    ----------
    steps_per_sample
        MuJoCo steps per controller period (`steps_per_sample`), >= 1.
    law
        called once at the start of every run: a fresh law (its own memory, its own seeded sensor noise), so
        a controller serves any number of runs alike.
    """

    steps_per_sample: int
    law: Callable[[], Law]

    def __post_init__(self) -> None:
        if self.steps_per_sample < 1:
            raise ValueError(f"steps_per_sample must be >= 1, got {self.steps_per_sample}")


def closed_loop(
    model: mujoco.MjModel, data: mujoco.MjData, state0: np.ndarray, controller: Controller, steps: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """Run `steps` steps from the full physics state `state0` with `controller` in the loop, recording every step.

    At each sample (every `controller.steps_per_sample` steps from step 0) the module docstring's sequence:
    `mj_forward`, the law reads `sensordata`, `ctrl` is set and held; then one `mj_step` per step (the
    model's integrator and timestep as set).

    Returns
    -------
    tuple
        (states (m + 1, full state size) with t = 0, sensordata (m + 1, nsensordata) at each state, controls
        (m, nu) held over each step, whether MuJoCo flagged a blow-up): m = steps, or fewer when the run blew
        up (it stops at the step that did).
    """
    mujoco.mj_setState(model, data, state0, _FULL)
    for warning in BAD_WARNINGS:
        data.warning[warning].number = 0
    law = controller.law()
    size = state0.size
    states = np.empty((steps + 1, size))
    sensors = np.empty((steps + 1, model.nsensordata))
    controls = np.empty((steps, model.nu))
    states[0] = state0
    flagged = False
    taken = steps
    counts = data.warning.number  # a view of data's warning counters: read in place each step
    for j in range(steps):
        if j % controller.steps_per_sample == 0:
            mujoco.mj_forward(model, data)
            data.ctrl[:] = np.asarray(law(j // controller.steps_per_sample, data.sensordata.copy()), dtype=float)
        controls[j] = data.ctrl
        mujoco.mj_step(model, data)
        sensors[j] = data.sensordata  # mj_step leaves the sensors of the state it started from
        mujoco.mj_getState(model, data, states[j + 1], _FULL)
        if any(counts[w] for w in BAD_WARNINGS) or not np.isfinite(states[j + 1]).all():
            flagged, taken = True, j + 1
            break
    with np.errstate(all="ignore"):
        mujoco.mj_forward(model, data)
    sensors[taken] = data.sensordata
    return states[: taken + 1], sensors[: taken + 1], controls[:taken], flagged
