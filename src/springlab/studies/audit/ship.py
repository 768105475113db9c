"""The audit's runs on a dask cluster: the user's model travels as plain data, one module-level chunk function.

`springlab audit MODEL --workers N` (or `--scheduler ADDRESS`) sends its simulations (the limit
confirmation runs, the integrator x timestep sweep, the converged RK4 reference's levels) to
springlab.studies.executor. A compiled MjModel never travels; what does is one of

* `SceneModel(name)`: a shipped scene, rebuilt on the worker as `audit.load` builds it;
* `MjcfModel(name, xml, assets, digest)`: the text of the model file and the bytes of every file it
  names (includes, meshes, textures, height fields, skins, nested models), keyed as MuJoCo looks them
  up, compiled on the worker by ``mujoco.MjModel.from_xml_string(xml, assets)``.

A chunk (`RunsChunk`) is that model and its runs (`AuditRun`: integrator, dt, steps and start).

Before anything is sent, the caller compiles that payload itself and checks that every numeric field of
the result equals the model it loaded from the path (only the recorded asset paths may differ): a file
the gathering missed is one clear error here, not a different model on the workers. An MjModel passed
in memory cannot travel (MuJoCo cannot write an arbitrary compiled model back as MJCF with its
assets): asking for workers with one is a BadInputError; locally it runs as always.

Locally (no workers, no scheduler) the runs are one `batch.run_batched` call, exactly as before. On dask
they are cut into at most SHIP_CHUNKS chunks of about equal steps (the cut depends only on the runs).
Either way every run's trajectory is bit-identical: a run depends only on its own model and start
(`run_batched` is bit-identical to `simulate` per job), and the workers' model equals the caller's.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import os
import pathlib
import posixpath
from collections.abc import Sequence
from typing import Any, TypeAlias
from xml.etree import ElementTree

import mujoco
import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, DivergedError
from springlab.sim.batch import Job, run_batched
from springlab.sim.simulate import Setup, Trajectory, quiet_mujoco
from springlab.studies.executor import Executor

#: on dask, the runs of one call are cut into at most this many chunks of about equal steps
SHIP_CHUNKS = 16
#: compiler attributes whose folders prefix the asset files' names
_DIR_ATTRIBUTES = ("meshdir", "texturedir", "assetdir")
#: fields of MjModel that record where the assets were read from (and the buffer size holding that), not what they are
_PATH_FIELDS = {"paths", "npaths", "nbuffer", "mesh_pathadr", "skin_pathadr", "hfield_pathadr", "tex_pathadr"}
#: models compiled on this process from payloads, by digest (a worker runs many chunks of one audit)
_COMPILED: dict[str, mujoco.MjModel] = {}


def _gather(path: pathlib.Path) -> dict[str, bytes]:
    """The bytes of every file the MJCF (or URDF) at `path` names, keyed by name as MuJoCo looks it up in
    a VFS when compiling the text alone: the name as written, under each compiler folder (meshdir, ...)
    and the including file's folder, and its bare file name (URDF strips paths). Included files are read
    recursively. Extra entries are harmless; a missing one shows in `ship`'s check."""
    root = path.parent
    mentioned: list[tuple[str, str]] = []  # (name as written, folder of the file naming it, relative to root)
    folders = {""}
    pending, seen = [path], {path.resolve()}
    while pending:
        current = pending.pop()
        try:
            tree = ElementTree.parse(current)
        except (ElementTree.ParseError, OSError):
            continue  # not XML (a mesh named .xml?) or unreadable: MuJoCo's compile says what is wrong
        here = posixpath.normpath(os.path.relpath(current.parent, root).replace(os.sep, "/"))
        for element in tree.iter():
            if element.tag == "compiler":
                folders.update(element.attrib[a] for a in _DIR_ATTRIBUTES if a in element.attrib)
            for key, value in element.attrib.items():
                if not key.startswith("file"):  # file, fileleft ... fileback, URDF's filename
                    continue
                mentioned.append((value, here))
                if value.lower().endswith((".xml", ".urdf")):
                    for candidate in (root / value, current.parent / value):
                        if candidate.is_file() and candidate.resolve() not in seen:
                            seen.add(candidate.resolve())
                            pending.append(candidate)
    assets: dict[str, bytes] = {}
    for value, here in mentioned:
        if os.path.isabs(value):
            if os.path.isfile(value):
                assets[value] = pathlib.Path(value).read_bytes()
            continue
        for folder in folders | {here}:
            for name in {value, posixpath.basename(value.replace("\\", "/"))}:
                key = posixpath.normpath(posixpath.join(folder, name))
                file = root / key
                if key not in assets and file.is_file():
                    assets[key] = file.read_bytes()
    return assets


@dataclasses.dataclass(frozen=True)
class SceneModel:
    """A shipped scene by name: the worker rebuilds it with its default scenario and parameters."""

    name: str


@dataclasses.dataclass(frozen=True, eq=False)  # a mapping of bytes: compare fields, not payloads
class MjcfModel:
    """A model file as plain data: its text and the bytes of every file it names.

    Attributes
    ----------
    name
        the path it was loaded from (for messages).
    xml
        the file's text.
    assets
        file name as MuJoCo looks it up -> its bytes.
    digest
        SHA-256 of the text and the assets (the worker's cache key).
    """

    name: str
    xml: str
    assets: dict[str, bytes]
    digest: str


#: what `ship` sends: the model a worker rebuilds
Shipped: TypeAlias = SceneModel | MjcfModel


@dataclasses.dataclass(frozen=True, eq=False)  # arrays: compare fields, not results
class AuditRun:
    """One run of a chunk: integrator, timestep dt [s], steps, and the start (qpos, qvel, act, control; None:
    the model's, as in `Setup`)."""

    integrator: str
    dt: float
    steps: int
    qpos: np.ndarray | None
    qvel: np.ndarray | None
    act: np.ndarray | None
    control: np.ndarray | None

    @classmethod
    def of(cls, job: Job) -> AuditRun:
        """A job's run as plain data (its model travels once per chunk)."""
        setup = job.setup
        qpos, qvel, act, control = (
            None if a is None else np.asarray(a, float) for a in (setup.qpos, setup.qvel, setup.act, setup.control)
        )
        return cls(job.integrator, job.dt, job.steps, qpos, qvel, act, control)

    def setup(self) -> Setup:
        return Setup(self.qpos, self.qvel, self.act, self.control)


@dataclasses.dataclass(frozen=True)
class RunsChunk:
    """A chunk of audit runs: the model a worker rebuilds and the runs on it."""

    model: Shipped
    runs: tuple[AuditRun, ...]


def _digest(xml: str, assets: dict[str, bytes]) -> str:
    digest = hashlib.sha256(xml.encode())
    for key in sorted(assets):
        digest.update(key.encode() + b"\0" + hashlib.sha256(assets[key]).digest())
    return digest.hexdigest()


def _scene_model(name: str) -> mujoco.MjModel:
    """A shipped scene with its default scenario and parameters, built as `audit.load` builds it."""
    return scenes.case(name).model


def compiled(payload: Shipped) -> mujoco.MjModel:
    """The model a payload of `ship` describes (a scene rebuilt, an MJCF compiled), cached per process."""
    if isinstance(payload, SceneModel):
        return _scene_model(payload.name)
    key = payload.digest
    if key not in _COMPILED:
        with quiet_mujoco():
            model = mujoco.MjModel.from_xml_string(payload.xml, payload.assets)
        _COMPILED.clear()  # one audit at a time: keep the newest only
        _COMPILED[key] = model
    return _COMPILED[key]


def _same_model(a: Any, b: Any, depth: int = 0) -> bool:
    """Whether two MjModels (or their opt / stat / vis structs) hold the same numbers, asset paths aside."""
    for name in dir(a):
        if name.startswith("_") or name in _PATH_FIELDS:
            continue
        x, y = getattr(a, name), getattr(b, name)
        if callable(x):
            continue
        if isinstance(x, np.ndarray):
            if x.shape != y.shape or not np.array_equal(x, y, equal_nan=x.dtype.kind in "fc"):
                return False
        elif isinstance(x, (int, float, str, bytes)):
            if x != y and not (isinstance(x, float) and math.isnan(x) and math.isnan(y)):
                return False
        elif depth < 2 and hasattr(x, "__dir__") and not isinstance(x, type):
            if not _same_model(x, y, depth + 1):
                return False
    return True


def ship(origin: tuple[str, str] | None, model: mujoco.MjModel) -> Shipped:
    """The plain-data payload that rebuilds `model` on a dask worker (module docstring).

    Parameters
    ----------
    origin
        ("scene", name), ("path", path of the MJCF / URDF it was loaded from), or None (an MjModel
        passed in memory).
    model
        the model as the caller loaded it; the payload is checked to compile to the same numbers.

    Raises
    ------
    BadInputError
        an in-memory model, or a file whose named files could not all be gathered.
    """
    if origin is None:
        raise BadInputError(
            "an MjModel passed in memory cannot be sent to dask workers (MuJoCo cannot write it back as MJCF"
            " with its assets); pass the path of its MJCF file, or run without workers/scheduler"
        )
    kind, where = origin
    if kind == "scene":
        return SceneModel(where)
    path = pathlib.Path(where)
    xml = path.read_text(encoding="utf-8")
    assets = _gather(path)
    payload = MjcfModel(where, xml, assets, _digest(xml, assets))
    try:
        rebuilt = compiled(payload)
    except Exception as error:  # MuJoCo's ValueError: a file it names was not gathered
        message = " ".join(str(error).split())
        raise BadInputError(
            f"cannot send {where!r} to dask workers: compiled from its files alone, {message}"
        ) from None
    if not _same_model(rebuilt, model):
        raise BadInputError(
            f"cannot send {where!r} to dask workers: compiled from its text and named files it differs from"
            " the model loaded from its path; run without workers/scheduler"
        )
    return payload


def runs_chunk(payload: RunsChunk, nthread: int = 0) -> list[Trajectory | DivergedError]:
    """One chunk of audit runs as one batched MuJoCo call (a module-level function of plain data for dask).

    Returns per run its Trajectory or DivergedError, as `batch.run_batched`.
    """
    model = compiled(payload.model)
    jobs = [Job(model, run.integrator, run.dt, run.steps, run.setup()) for run in payload.runs]
    return run_batched(jobs, nthread=nthread)


def cut(steps: Sequence[int], chunks: int = SHIP_CHUNKS) -> list[range]:
    """Consecutive index ranges of about equal total steps, at most `chunks` of them: run i goes to the
    chunk its middle step falls in when the total is split into `chunks` equal parts (empty parts dropped)."""
    total = sum(steps)
    if not steps or total <= 0:
        return [range(0, len(steps))] if steps else []
    owner, before = [], 0
    for count in steps:
        owner.append(min(chunks - 1, int((before + count / 2) * chunks // total)))
        before += count
    pieces, first = [], 0
    for index in range(1, len(steps) + 1):
        if index == len(steps) or owner[index] != owner[first]:
            pieces.append(range(first, index))
            first = index
    return pieces


class Runner:
    """Runs lists of audit jobs on one model: locally in one batch, or in chunks on a dask executor.

    Parameters
    ----------
    executor
        where the runs go (None or a local executor: this process, `nthread` threads).
    shipped
        the model's `ship` payload (needed only with a distributed executor).
    nthread
        threads of a local batch (0: one per CPU) when no executor is given.
    """

    def __init__(self, executor: Executor | None, shipped: Shipped | None, nthread: int = 0):
        self.executor, self.shipped = executor, shipped
        self.nthread = executor.nthread if executor is not None else nthread

    @property
    def distributed(self) -> bool:
        return self.executor is not None and self.executor.distributed

    def __call__(self, jobs: Sequence[Job], description: str = "audit runs") -> list[Trajectory | DivergedError]:
        if not self.distributed:
            return run_batched(jobs, nthread=self.nthread)
        assert self.executor is not None and self.shipped is not None, "a distributed runner ships its model"
        assert all(job.stop is None for job in jobs), "audit runs have no stop condition"
        pieces = cut([job.steps for job in jobs])
        shipped = self.shipped
        payloads = [RunsChunk(shipped, tuple(AuditRun.of(jobs[i]) for i in piece)) for piece in pieces]
        sizes = [len(piece) for piece in pieces]
        results = self.executor.map(runs_chunk, payloads, description=description, sizes=sizes, unit="run")
        return [outcome for part in results for outcome in part]
