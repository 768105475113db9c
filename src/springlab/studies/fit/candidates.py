"""What the candidates of one fit share, kept for the optimizer's next asks (springlab.studies.fit.engine).

MuJoCo's Levenberg-Marquardt asks for some candidates again: a finite-difference Jacobian's columns in the
initial state and the offset change nothing the model is compiled from (the model is its point's, compiled a moment
before), its offset column changes neither the model nor the initial state (the rollout is its point's), and the
residual at the estimate repeats the best point's. Compiling and simulating are deterministic, so what was made for
them serves again: the same numbers, without compiling or simulating twice. Keys are exact (a number's repr, an
array's bytes), never a tolerance. A model's key is the scene parameters `Scene.edit` read while it was compiled
(`Noted`: a scene whose edit reads x0 compiles a model per x0; one that does not, one model for every x0). The
rollouts' MjData are made once per fit rather than once per residual.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import mujoco

from springlab.sim.simulate import model_sizes

#: compiled models and rollouts a fit keeps: the optimizer's latest points are the ones it asks for again
KEPT = 8
#: ... and at most this many bytes of kept rollouts [B] (a long record's rollouts are large)
KEPT_BYTES = 2**25


class Kept:
    """One fit's latest compiled models (by dt and scene parameters), rollouts (by what they depend on) and the
    rollouts' MjData."""

    def __init__(self) -> None:
        self._models: dict[tuple[Any, ...], mujoco.MjModel] = {}
        self._rollouts: dict[tuple[Any, ...], Any] = {}
        self._datas: tuple[tuple[int, ...], list[mujoco.MjData]] | None = None

    def model(
        self, dt: float, scene_params: Mapping[str, Any], compile: Callable[[Noted], mujoco.MjModel]
    ) -> mujoco.MjModel:
        """The model of these scene parameters at dt [s]: a kept one compiled from the same values of every
        parameter its edit read, or `compile(noted)`'s, which hands `noted` (the parameters, noting what is read)
        to `Scene.edit` (kept, under what the edit read)."""
        step = repr(dt)
        for (kept_step, *read), model in self._models.items():
            if kept_step == step and all(_exact_value(scene_params, name) == value for name, value in read):
                return model
        noted = Noted(scene_params)
        model = compile(noted)
        return _keep(self._models, (step, *noted.read()), model, KEPT)

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


class Noted(dict):  # Scene.edit takes a dict
    """Scene parameters handed to `Scene.edit` that note which of them it reads: by key (`[]`, `get`, `in`,
    `setdefault`, `pop`), or all of them once it reads them whole (iterates, copies, counts, compares, prints them).
    Python reads a dict subclass with its own `__iter__` through these methods: `dict(p)`, `{**p}` and `f(**p)`
    call `keys()`."""

    def __init__(self, values: Mapping[str, Any]):
        super().__init__(values)
        self._original = dict(values)
        self._names: set[str] = set()
        self._whole = False

    def read(self) -> tuple[tuple[str, str], ...]:
        """(name, exact value) of what was read, in name order; with the names themselves when read whole."""
        if self._whole:
            return (("", _exact_value(self._original, "")), *exact(self._original))
        return tuple(sorted((name, _exact_value(self._original, name)) for name in self._names))

    def _name(self, key: Any) -> Any:
        self._names.add(key)
        return key

    def _all(self) -> None:
        self._whole = True

    def __getitem__(self, key: Any) -> Any:
        return super().__getitem__(self._name(key))

    def get(self, key: Any, default: Any = None) -> Any:
        return super().get(self._name(key), default)

    def __contains__(self, key: object) -> bool:
        return super().__contains__(self._name(key))

    def setdefault(self, key: Any, default: Any = None) -> Any:
        return super().setdefault(self._name(key), default)

    def pop(self, key: Any, *default: Any) -> Any:
        return super().pop(self._name(key), *default)

    def __iter__(self) -> Any:
        self._all()
        return super().__iter__()

    def keys(self) -> Any:
        self._all()
        return super().keys()

    def values(self) -> Any:
        self._all()
        return super().values()

    def items(self) -> Any:
        self._all()
        return super().items()

    def copy(self) -> dict[str, Any]:
        self._all()
        return dict(super().items())

    def __len__(self) -> int:
        self._all()
        return super().__len__()

    def __eq__(self, other: object) -> bool:
        self._all()
        return super().__eq__(other)

    def __ne__(self, other: object) -> bool:
        self._all()
        return super().__ne__(other)

    __hash__ = None  # as a dict

    def __or__(self, other: Any) -> Any:
        self._all()
        return super().__or__(other)

    def __ror__(self, other: Any) -> Any:
        self._all()
        return super().__ror__(other)

    def __repr__(self) -> str:
        self._all()
        return super().__repr__()

    def __reduce_ex__(self, protocol: Any) -> Any:
        self._all()
        return super().__reduce_ex__(protocol)


def rollout_key(dt: float, steps: int, scene_params: Mapping[str, Any], state: Any, control: Any) -> tuple[Any, ...]:
    """What a rollout depends on: the grid (dt [s], steps), the model (the scene's parameters), the initial state
    and the controls (arrays, by their bytes)."""
    return (repr(dt), steps, *exact(scene_params), state.tobytes(), control.tobytes())


def exact(values: Mapping[str, Any]) -> tuple[tuple[str, str], ...]:
    """(name, repr(value)) pairs in name order: equal only for the same numbers (0.0 and -0.0 differ)."""
    return tuple(sorted((name, repr(value)) for name, value in values.items()))


def _exact_value(values: Mapping[str, Any], name: str) -> str:
    """`name`'s value in `values` as `exact` writes it ('<absent>' when missing; name '': the names, as `Noted`
    notes them when read whole)."""
    if name == "":
        return repr(sorted(values))
    return repr(values[name]) if name in values else "<absent>"


def _keep(kept: dict[Any, Any], key: Any, value: Any, limit: int) -> Any:
    """Store `value` under `key` in `kept`, dropping the oldest entries beyond `limit` (none kept at 0); return
    `value`."""
    kept[key] = value
    while len(kept) > limit:
        del kept[next(iter(kept))]
    return value
