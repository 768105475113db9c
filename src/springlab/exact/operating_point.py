"""Where a model is studied: its operating point (a keyframe, qpos0 at rest, or where it comes to rest).

* `OperatingPoint`: qpos, qvel, act and ctrl, with a label saying where they came from.
* `operating_point(model, keyframe)`: a keyframe by name or index, else the first one, else qpos0 at rest.
* `settle(model, point, seconds)`: the point after the model's own motion (a robot lying on the floor).

`springlab.exact.model_at_point.ModelAtPoint` holds a model at one of these points with what the studies
ask of it there (its forward pass, what constrains it, its linearization), each computed once.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Any

import mujoco
import numpy as np

from springlab.errors import BadInputError
from springlab.sim.simulate import BAD_WARNINGS, quiet_mujoco


@dataclasses.dataclass(frozen=True)
class OperatingPoint:
    """Where a model is linearized: qpos (nq,) [m, rad, quaternion], qvel (nv,) [m/s, rad/s],
    act (na,) and ctrl (nu,) [actuator units]; `label` says where it came from (e.g. "keyframe 'home'")."""

    qpos: np.ndarray
    qvel: np.ndarray
    act: np.ndarray
    ctrl: np.ndarray
    label: str = "qpos0"

    @classmethod
    def at(
        cls,
        model: mujoco.MjModel,
        qpos: np.ndarray | None = None,
        qvel: np.ndarray | None = None,
        act: np.ndarray | None = None,
        ctrl: np.ndarray | None = None,
        label: str = "given state",
    ) -> OperatingPoint:
        """A point from whatever the caller has (the rest: qpos0, zero velocity, activation and control),
        e.g. `linearize(model, OperatingPoint.at(model, qpos=sag))` for a scene's own linearization."""

        def given(value, default):
            return np.array(default if value is None else value, float)

        return cls(
            given(qpos, model.qpos0),
            given(qvel, np.zeros(model.nv)),
            given(act, np.zeros(model.na)),
            given(ctrl, np.zeros(model.nu)),
            label,
        )

    def to_dict(self) -> dict[str, Any]:
        """{"label", "qpos", "qvel", "act", "ctrl"} as plain lists."""
        return {
            "label": self.label,
            "qpos": self.qpos.tolist(),
            "qvel": self.qvel.tolist(),
            "act": self.act.tolist(),
            "ctrl": self.ctrl.tolist(),
        }

    def load(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        """Reset `data` and put this point into it (time 0, MuJoCo's other defaults)."""
        mujoco.mj_resetData(model, data)
        data.qpos[:] = self.qpos
        data.qvel[:] = self.qvel
        data.act[:] = self.act
        data.ctrl[:] = self.ctrl


def operating_point(model: mujoco.MjModel, keyframe: str | int | None = None) -> OperatingPoint:
    """The model's operating point: the keyframe named or numbered `keyframe`; None: the first keyframe
    if the model has one, else qpos0 at rest.

    Raises
    ------
    BadInputError
        no such keyframe (the message lists the valid ones).
    """
    if keyframe is None and model.nkey == 0:
        return OperatingPoint(
            model.qpos0.copy(), np.zeros(model.nv), np.zeros(model.na), np.zeros(model.nu), "qpos0 (no keyframe)"
        )
    names = [model.key(i).name or str(i) for i in range(model.nkey)]
    index = 0 if keyframe is None else None
    if keyframe is not None:
        text = str(keyframe)
        if text in names:
            index = names.index(text)
        elif text.lstrip("-").isdigit() and 0 <= int(text) < model.nkey:
            index = int(text)
    if index is None:
        valid = ", ".join(f"{i} ({n})" if n != str(i) else str(i) for i, n in enumerate(names)) or "none"
        raise BadInputError(f"unknown keyframe {str(keyframe)!r}; valid: {valid}")
    key = model.key(index)
    label = f"keyframe {names[index]!r}" if names[index] != str(index) else f"keyframe {index}"
    return OperatingPoint(
        np.array(key.qpos, float), np.array(key.qvel, float), np.array(key.act, float), np.array(key.ctrl, float), label
    )


def settle(model: mujoco.MjModel, point: OperatingPoint, seconds: float) -> OperatingPoint:
    """`point` after `seconds` [s] of the model's own motion (its own integrator and timestep, controls
    held): where a robot comes to rest, or to its steady contact state, before it is linearized.

    Raises
    ------
    BadInputError
        the model blows up while settling (MuJoCo flags a bad position, velocity or acceleration).
    """
    work = copy.copy(model)
    data = mujoco.MjData(work)
    steps = max(1, round(seconds / work.opt.timestep))
    with quiet_mujoco():
        point.load(work, data)
        mujoco.mj_step(work, data, nstep=steps)  # MuJoCo's loop of mj_step: the same steps, none from Python
    flagged = any(data.warning[int(w)].number for w in BAD_WARNINGS)
    if flagged or not (np.isfinite(data.qpos).all() and np.isfinite(data.qvel).all()) or data.time < 0.5 * seconds:
        raise BadInputError(
            f"the model blew up while settling for {seconds:g} s at its own setting; settle for less or fix the model"
        )
    return OperatingPoint(
        data.qpos.copy(),
        data.qvel.copy(),
        data.act.copy(),
        data.ctrl.copy(),
        f"{point.label} settled for {seconds:g} s",
    )
