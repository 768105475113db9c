"""What the design studies share: which scenes declare a design question, the parameters a study starts
from, and the scene's batched move simulations cut into chunks on an executor.

A scene answers a design question by declaring it (`Scene.design`, a
springlab.scenes.capabilities.design.DesignSpec); this package reads the declaration and never names a scene.
The simulation of a configuration is the scene's (`DesignSpec.hooks.simulate`, e.g. one
`mujoco.batch.Batch` per chunk, each simulation stopped once its settling is certified); here the
configurations are cut into chunks of plain data that run locally or on dask workers, and the chunks'
results are joined in order, so the numbers are the same whichever executor ran them.
"""

from __future__ import annotations

import dataclasses
import time as _time
import types
from collections.abc import Mapping
from typing import Any

import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, ParameterError, UnknownNameError
from springlab.scenes.base import Case, Parameter, Scene
from springlab.scenes.capabilities.design import DesignProperty, DesignSpec, MoveRuns
from springlab.studies.executor import Executor, chunked

#: omega_n * dt of every simulation
OMEGA_DT = 0.1
#: simulated time [s] after which an unsettled configuration is given up (reported as inf)
MAX_DURATION = 5.0
#: configurations per chunk: one batched call each (about 2 s on one core), the unit of work on a cluster
CHUNK_CONFIGURATIONS = 256
#: the (n,) arrays of MoveRuns, joined over the chunks
_PER_CONFIGURATION = ("move_time_s", "settling_time_s", "positioning_time_s", "residual_amplitude_m", "dt_s", "steps")


def design_scenes() -> list[str]:
    """The names of the scenes that declare a design question (`Scene.design`), in catalogue order."""
    return [name for name, scene in scenes.SCENES.items() if scene.design is not None]


def declaration(scene: str | Scene) -> tuple[Scene, DesignSpec]:
    """The scene and its design declaration.

    Parameters
    ----------
    scene
        a scene or its name.

    Raises
    ------
    UnknownNameError
        no such scene, or it declares no design question (the message lists those that do).
    """
    found = scenes.SCENES.get(scene) if isinstance(scene, str) else scene
    if found is None or found.design is None:
        raise UnknownNameError("design study", str(getattr(scene, "name", scene)), design_scenes())
    return found, found.design


def base_parameters(scene: str | Scene, overrides: Mapping[str, Any] | None = None) -> dict[str, float]:
    """The parameters (SI) a design study of `scene` starts from: MJCF defaults < its scenario < overrides.

    A derived property the design declares (e.g. a damping ratio) is accepted among the overrides
    too: it sets the scene parameter it derives from (the declaration's hook converts it).

    Raises
    ------
    UnknownNameError
        an unknown scene or parameter.
    ParameterError
        a bad value, or a derived property given together with the parameter it sets.
    """
    scene, spec = declaration(scene)
    scenario = scene.scenario(spec.scenario)
    overrides = dict(overrides or {})
    derived = {p.name: p for p in (*spec.properties, *spec.extra) if p.derived}
    for name in overrides:
        if name not in derived and name not in scene.parameters:
            raise UnknownNameError(f"parameter of the {scene.name} design study", name, [*scene.parameters, *derived])
    given = {name: overrides.pop(name) for name in list(derived) if name in overrides}
    if not given:
        return scene.resolve(scenario, overrides)
    checked = {}
    for name, value in given.items():
        prop = derived[name]
        if prop.parameter in overrides:
            raise ParameterError(
                f"give {name} or {prop.parameter}, not both ({name} sets the {prop.parameter.replace('_', ' ')})"
            )
        checked[name] = Parameter(name, prop.unit, prop.description, minimum=prop.minimum).check(value)
    base = scene.resolve(scenario, overrides)
    for name, value in checked.items():
        overrides.update(spec.hooks.parameters_for(name, value, base))
    return scene.resolve(scenario, overrides)


def spanned(
    defaults: Mapping[str, float],
    properties: tuple[DesignProperty, ...],
    exponents: np.ndarray,
    *,
    study: str = "design",
    verb: str = "sweeps",
) -> dict[str, np.ndarray]:
    """Property -> default x span^u for the exponents u [-], for each of `properties`.

    Raises
    ------
    BadInputError
        a property's default is not > 0 (a log span needs one); `study` and `verb` word the message.
    """
    for prop in properties:
        if defaults[prop.name] <= 0:
            raise BadInputError(
                f"the {study} study needs {prop.source} > 0 (it {verb} the {prop.description or prop.name} around it)"
            )
    return {prop.name: defaults[prop.name] * prop.span ** np.asarray(exponents) for prop in properties}


def simulate(
    scene: str | Scene,
    base: Mapping[str, float],
    values: Mapping[str, np.ndarray],
    *,
    omega_dt: float = OMEGA_DT,
    nthread: int = 0,
    max_duration: float = MAX_DURATION,
) -> MoveRuns:
    """The scene's move of every configuration, in one call of its simulation hook (no chunks).

    Parameters
    ----------
    scene
        a scene that declares a design question, or its name.
    base
        the scene's parameters (SI), e.g. from `base_parameters`.
    values
        property -> (n,) values; the properties not in it stay at `base`.
    omega_dt
        omega_n dt [-] of every simulation.
    nthread
        threads (0: one per CPU).
    max_duration
        simulated time [s] after which an unsettled configuration is given up.

    Returns
    -------
    MoveRuns
        per configuration, in order.
    """
    scene, spec = declaration(scene)
    case = Case.compiled(scene, scene.scenario(spec.scenario), base)
    return spec.hooks.simulate(case, values, omega_dt=omega_dt, nthread=nthread, max_duration=max_duration)


@dataclasses.dataclass(frozen=True, eq=False)  # arrays: compare fields, not results
class MovesChunk:
    """A chunk of a design study: plain data, the worker rebuilds the scene's model (`simulate`).

    Attributes
    ----------
    scene
        the scene's name.
    base
        (name, value) pairs: the scene's parameters, SI.
    values
        (property, (n,) values) pairs: this chunk's configurations.
    omega_dt
        omega_n dt [-] of every simulation.
    """

    scene: str
    base: tuple[tuple[str, float], ...]
    values: tuple[tuple[str, np.ndarray], ...]
    omega_dt: float


def moves_chunk(payload: MovesChunk, nthread: int = 0) -> MoveRuns:
    """One chunk of a design study (a module-level function of plain data, for dask workers):
    `simulate` of the payload's scene on its base, values and omega_dt."""
    return simulate(payload.scene, dict(payload.base), dict(payload.values), omega_dt=payload.omega_dt, nthread=nthread)


@dataclasses.dataclass(frozen=True)
class Simulated:
    """The moves of many configurations, run in chunks.

    Attributes
    ----------
    runs
        the chunks' results joined in order.
    wall_time_s
        wall time of the whole map [s].
    executor
        where the chunks ran ('local', '2 local dask workers', ...).
    """

    runs: MoveRuns
    wall_time_s: float
    executor: str

    @property
    def steps_total(self) -> int:
        """Physics steps taken by all simulations."""
        return int(self.runs.steps.sum())


def run_moves(
    scene: str | Scene,
    base: Mapping[str, float],
    values: Mapping[str, np.ndarray],
    *,
    omega_dt: float = OMEGA_DT,
    executor: Executor | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    description: str = "design",
) -> Simulated:
    """`simulate` over every configuration, cut into chunks of `chunk_size` on `executor`.

    Each simulation's result depends only on its own parameters, and the chunks are joined in
    order, so the arrays are identical whichever executor runs them (and whatever the chunk size).
    """
    scene, _ = declaration(scene)
    runner = Executor(progress=False) if executor is None else executor
    n = len(next(iter(values.values())))
    pieces = chunked(n, chunk_size)
    payloads = [
        MovesChunk(
            scene.name,
            tuple(base.items()),
            tuple((name, np.asarray(v)[piece.start : piece.stop]) for name, v in values.items()),
            omega_dt,
        )
        for piece in pieces
    ]
    start = _time.perf_counter()
    parts = runner.map(moves_chunk, payloads, description=description, sizes=[len(p) for p in pieces], unit="config")
    joined = {key: np.concatenate([getattr(part, key) for part in parts]) for key in _PER_CONFIGURATION}
    runs = MoveRuns(**joined, nthread=int(parts[0].nthread) if parts else 0)
    return Simulated(runs=runs, wall_time_s=_time.perf_counter() - start, executor=runner.describe())


def frozen_mapping(mapping: Mapping[str, Any]) -> Mapping[str, Any]:
    """A read-only view of a copy of `mapping` (a result's field that must not change once returned)."""
    return types.MappingProxyType(dict(mapping))


def frozen_array(array: np.ndarray) -> np.ndarray:
    """`array` as a read-only array: a read-only view where it is writeable (cheap: no copy)."""
    out = np.asarray(array)
    if out.flags.writeable:
        out = out.view()
        out.flags.writeable = False
    return out
