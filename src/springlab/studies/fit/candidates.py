"""What the candidates of one fit share, kept for the optimizer's next asks (springlab.studies.fit.engine).

MuJoCo's Levenberg-Marquardt asks for some candidates again: a finite-difference Jacobian's columns in the
initial state and the offset change no scene parameter (the model is its point's, compiled a moment before), its
offset column changes neither the model nor the initial state (the rollout is its point's), and the residual at the
estimate repeats the best point's. The simulation is deterministic, so what was made for them serves again: the
same numbers, without compiling or simulating twice. Keys are exact (a number's repr, an array's bytes), never a
tolerance. The rollouts' MjData are made once per fit rather than once per residual.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import mujoco

#: compiled models and rollouts a fit keeps: the optimizer's latest points are the ones it asks for again
KEPT = 8
#: ... and at most this many bytes of kept rollouts [B] (a long record's rollouts are large)
KEPT_BYTES = 2**25

#: per MjModel type, the names of its integer sizes (nq, nv, nbody, ..., nbuffer)
_SIZE_NAMES: dict[type, tuple[str, ...]] = {}


class Kept:
    """One fit's latest compiled models (by dt and scene parameters), rollouts (by what they depend on) and the
    rollouts' MjData."""

    def __init__(self) -> None:
        self._models: dict[tuple[Any, ...], mujoco.MjModel] = {}
        self._rollouts: dict[tuple[Any, ...], Any] = {}
        self._datas: tuple[tuple[int, ...], list[mujoco.MjData]] | None = None

    def model(
        self, dt: float, scene_params: Mapping[str, Any], compile: Callable[[], mujoco.MjModel]
    ) -> mujoco.MjModel:
        """The model of these scene parameters at dt [s]: a kept one, or `compile()`'s (kept)."""
        key = (repr(dt), *exact(scene_params))
        model = self._models.get(key)
        if model is None:
            model = _keep(self._models, key, compile(), KEPT)
        return model

    def datas(self, model: mujoco.MjModel, count: int) -> list[mujoco.MjData]:
        """`count` MjData for rollouts of `model` and every model of its sizes (mujoco.rollout's premise for a
        batch, which sysid makes them for from its first model), made once per fit."""
        sizes = model_sizes(model)
        if self._datas is None or self._datas[0] != sizes or len(self._datas[1]) != count:
            self._datas = (sizes, [mujoco.MjData(model) for _ in range(count)])
        return self._datas[1]

    def rollouts(self, keys: Sequence[tuple[Any, ...]], simulate: Callable[[list[int]], Sequence[Any]]) -> list[Any]:
        """The rollout of each key (`rollout_key`): a kept one, or made by `simulate(indices)` for the keys not kept
        (each once), whose rollouts are kept as far as KEPT and KEPT_BYTES allow."""
        new = [i for i, key in enumerate(keys) if key not in self._rollouts and key not in keys[:i]]
        made = dict(zip((keys[i] for i in new), simulate(new) if new else []))
        found = [made[key] if key in made else self._rollouts[key] for key in keys]
        for key, trajectory in made.items():
            size = sum(s.data.nbytes for s in (trajectory.state, trajectory.sensordata) if s is not None)
            _keep(self._rollouts, key, trajectory, min(KEPT, KEPT_BYTES // max(size, 1)))
        return found


def rollout_key(dt: float, steps: int, scene_params: Mapping[str, Any], state: Any, control: Any) -> tuple[Any, ...]:
    """What a rollout depends on: the grid (dt [s], steps), the model (the scene's parameters), the initial state
    and the controls (arrays, by their bytes)."""
    return (repr(dt), steps, *exact(scene_params), state.tobytes(), control.tobytes())


def exact(values: Mapping[str, Any]) -> tuple[tuple[str, str], ...]:
    """(name, repr(value)) pairs in name order: equal only for the same numbers (0.0 and -0.0 differ)."""
    return tuple(sorted((name, repr(value)) for name, value in values.items()))


def model_sizes(model: mujoco.MjModel) -> tuple[int, ...]:
    """`model`'s sizes (nq, nv, nbody, ..., narena, nbuffer): what an MjData's layout depends on."""
    names = _SIZE_NAMES.get(type(model))
    if names is None:
        names = tuple(n for n in dir(model) if n.startswith("n") and type(getattr(model, n)) is int)
        _SIZE_NAMES[type(model)] = names
    return tuple(getattr(model, n) for n in names)


def _keep(kept: dict[Any, Any], key: Any, value: Any, limit: int) -> Any:
    """Store `value` under `key` in `kept`, dropping the oldest entries beyond `limit` (none kept at 0); return
    `value`."""
    kept[key] = value
    while len(kept) > limit:
        del kept[next(iter(kept))]
    return value
