"""A sweep of a model file: its MJCF options and named numeric attributes over a grid, every configuration one run.

`springlab sweep gripper.xml --vary opt.impratio=1:100:5:log --vary geom.box.friction=0.5:1.5:3` runs every
combination from the model's keyframe and reports per configuration what `springlab run MODEL.xml` measures
(springlab.runs.model_run.measures: final positions and velocities, largest excursions, energy at the start
and the end). A model file has no exact solution: no row passes or fails (`passed` None); a row that blows up
is marked `diverged`.

What may vary (`NAME` of `--vary NAME=LOW:HIGH:N[:log]`):

* an option: `opt.timestep` [s], `opt.impratio`, `opt.tolerance`, `opt.iterations`, `opt.ls_iterations`,
  `opt.noslip_iterations`, `opt.noslip_tolerance`, `opt.o_margin` [m] (`impratio` alone means `opt.impratio`);
  `opt.integrator=euler,rk4,...` and `opt.cone=pyramidal,elliptic` take names (their column holds MuJoCo's
  enum value, the row's quantities the name);
* an element's attribute by the element's name, `KIND.NAME.ATTRIBUTE[INDEX]` as the MJCF spells it: `joint`
  (stiffness, damping, frictionloss, armature, margin), `geom` (friction: [0] sliding, [1] torsional,
  [2] rolling; solref, solimp, margin, gap), `body` (mass: its inertia scales with it, the same shape at
  another density), `tendon` (stiffness, damping, frictionloss), `actuator` (gear, gainprm, biasprm); INDEX
  defaults to 0.

The values are set on the compiled model (MuJoCo reads them at every step; nothing is recompiled; after a mass or
an armature, `mj_setConst` recomputes the constants MuJoCo derives from them). Each
configuration is one job of a threaded `mujoco.rollout` call, chunked on the executor (springlab.studies.
executor); a dask worker compiles the model from its text and the files it names (springlab.studies.audit.ship,
as the audit sends a model), so the rows are the same wherever they ran and equal single `springlab run MODEL.xml`
runs at the same setting.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import os
import re
import time as _time
from collections.abc import Mapping, Sequence
from typing import Any, cast

import mujoco
import numpy as np

from springlab import display
from springlab.answer import Answer
from springlab.errors import BadInputError, DivergedError, UnknownNameError
from springlab.exact.operating_point import operating_point
from springlab.runs.model_run import DEFAULT_DURATION, integrator_name, measures
from springlab.sim import model_files
from springlab.sim.batch import Job, run_rollout
from springlab.sim.simulate import INTEGRATORS, Setup, check_timing, integrator_id

from . import answers
from .audit.ship import Shipped, compiled, ship
from .executor import Executor, chunked, resolve
from .sweeps import CHUNK_CONFIGURATIONS, MAX_CONFIGURATIONS, Axis, AxisSpec, Sweep, SweepRow, make_axis, typed_axis

#: numeric options a sweep may vary -> (smallest valid value, whether it must exceed it, whether an integer)
OPTIONS: dict[str, tuple[float, bool, bool]] = {
    "timestep": (0.0, True, False),
    "impratio": (0.0, True, False),
    "tolerance": (0.0, False, False),
    "iterations": (1.0, False, True),
    "ls_iterations": (1.0, False, True),
    "noslip_iterations": (0.0, False, True),
    "noslip_tolerance": (0.0, False, False),
    "o_margin": (0.0, False, False),
}
#: options that take names -> name -> MuJoCo's enum value
CHOICES: dict[str, dict[str, int]] = {
    "integrator": dict(INTEGRATORS),
    "cone": {"pyramidal": int(mujoco.mjtCone.mjCONE_PYRAMIDAL), "elliptic": int(mujoco.mjtCone.mjCONE_ELLIPTIC)},
}
#: element kind -> MJCF attribute -> (compiled field, what indexes it, smallest valid value or None: any sign)
ATTRIBUTES: dict[str, dict[str, tuple[str, str, float | None]]] = {
    "joint": {
        "stiffness": ("jnt_stiffness", "joint", 0.0),
        "damping": ("dof_damping", "dof", 0.0),
        "frictionloss": ("dof_frictionloss", "dof", 0.0),
        "armature": ("dof_armature", "dof", 0.0),
        "margin": ("jnt_margin", "joint", 0.0),
    },
    # a geom's MJCF attribute is its compiled field without the "geom_" prefix
    "geom": {
        field.removeprefix("geom_"): (field, "geom", floor)
        for field, floor in (
            ("geom_friction", 0.0),
            ("geom_solref", None),
            ("geom_solimp", 0.0),
            ("geom_margin", 0.0),
            ("geom_gap", 0.0),
        )
    },
    "body": {"mass": ("body_mass", "body", 0.0)},
    "tendon": {
        "stiffness": ("tendon_stiffness", "tendon", 0.0),
        "damping": ("tendon_damping", "tendon", 0.0),
        "frictionloss": ("tendon_frictionloss", "tendon", 0.0),
    },
    "actuator": {
        "gear": ("actuator_gear", "actuator", None),
        "gainprm": ("actuator_gainprm", "actuator", None),
        "biasprm": ("actuator_biasprm", "actuator", None),
    },
}
_OBJECTS = {
    "joint": mujoco.mjtObj.mjOBJ_JOINT,
    "geom": mujoco.mjtObj.mjOBJ_GEOM,
    "body": mujoco.mjtObj.mjOBJ_BODY,
    "tendon": mujoco.mjtObj.mjOBJ_TENDON,
    "actuator": mujoco.mjtObj.mjOBJ_ACTUATOR,
}
_NAME = re.compile(r"^(?P<kind>\w+)\.(?P<element>.+)\.(?P<attribute>\w+)(\[(?P<index>\d+)\])?$")
FORM = (
    "--vary on a model file takes opt.OPTION (timestep, impratio, tolerance, iterations, ls_iterations,"
    " noslip_iterations, noslip_tolerance, o_margin; integrator and cone by name) or KIND.NAME.ATTRIBUTE[INDEX]"
    f" with KIND one of {', '.join(ATTRIBUTES)}"
)
#: the typed form of one `vary` entry
_TYPED = (
    "(low, high, n) or (low, high, n, 'log'), or names for opt.integrator and opt.cone, e.g."
    " vary={'opt.impratio': (1.0, 100.0, 5, 'log'), 'opt.integrator': ('euler', 'rk4')}"
)


@dataclasses.dataclass(frozen=True)
class Target:
    """What one varied name sets on a compiled model.

    Attributes
    ----------
    name
        the name as given (`opt.impratio`, `geom.box.friction`).
    option
        the option's field of `model.opt` (None: an element's attribute).
    field
        the compiled model's array (`geom_friction`; None for an option).
    rows
        the rows of `field` it sets (a joint's every degree of freedom for a per-dof attribute).
    index
        the column of a vector attribute (0 for a scalar one).
    choices
        name -> MuJoCo enum value for an option that takes names (None: a number).
    """

    name: str
    option: str | None = None
    field: str | None = None
    rows: tuple[int, ...] = ()
    index: int = 0
    choices: dict[str, int] | None = None

    def check(self, value: float) -> None:
        """BadInputError for a value the target cannot take (a negative damping, a zero mass or timestep)."""
        if self.choices is not None:
            return
        if self.option is not None:
            low, strict, integer = OPTIONS[self.option]
            if integer and value != round(value):
                raise BadInputError(f"{self.name} takes whole numbers, got {value:g}")
        else:
            kind = self.name.split(".")[0]
            attribute = self.name.split(".")[-1].split("[")[0]
            floor = ATTRIBUTES[kind][attribute][2]
            if floor is None:
                return
            low, strict = floor, attribute == "mass"
        if not math.isfinite(value) or value < low or (strict and value == low):
            raise BadInputError(f"{self.name} must be {'>' if strict else '>='} {low:g}, got {value:g}")

    def apply(self, model: mujoco.MjModel, value: float) -> None:
        """Set `value` on `model` (a body's mass scales its inertia with it)."""
        if self.option is not None:
            cast = int(value) if self.choices is not None or OPTIONS[self.option][2] else float(value)
            setattr(model.opt, self.option, cast)
            return
        assert self.field is not None, "an element's attribute names its field"
        array = getattr(model, self.field)
        for row in self.rows:
            if self.field == "body_mass":
                old = float(array[row])
                if old > 0:
                    model.body_inertia[row] *= value / old
            if array.ndim == 1:
                array[row] = value
            else:
                array[row, self.index] = value


def target(model: mujoco.MjModel, name: str) -> Target:
    """The Target a varied name sets on `model`.

    Raises
    ------
    BadInputError
        a name that is neither an option nor KIND.NAME.ATTRIBUTE[INDEX], an unknown option, kind, element
        or attribute, an index past the attribute's length (each message lists what is valid).
    """
    option = name[4:] if name.startswith("opt.") else name
    if "." not in option:
        if option in CHOICES:
            return Target(name, option=option, choices=CHOICES[option])
        if option in OPTIONS:
            return Target(name, option=option)
        raise UnknownNameError("option to vary", option, [*OPTIONS, *CHOICES])
    match = _NAME.match(name)
    if match is None:
        raise BadInputError(f"{FORM}; got {name!r}")
    kind, element, attribute = match["kind"], match["element"], match["attribute"]
    if kind not in ATTRIBUTES:
        raise UnknownNameError("element kind", kind, ATTRIBUTES)
    if attribute not in ATTRIBUTES[kind]:
        raise UnknownNameError(f"{kind} attribute", attribute, ATTRIBUTES[kind])
    found = mujoco.mj_name2id(model, _OBJECTS[kind], element)
    if found < 0:
        count = getattr(model, f"n{'jnt' if kind == 'joint' else 'u' if kind == 'actuator' else kind}")
        names = [mujoco.mj_id2name(model, _OBJECTS[kind], i) for i in range(count)]
        raise UnknownNameError(kind, element, [n for n in names if n] or ["(none named)"])
    field, indexed_by, _ = ATTRIBUTES[kind][attribute]
    rows: tuple[int, ...] = (found,)
    if indexed_by == "dof":
        start = int(model.jnt_dofadr[found])
        width = {int(mujoco.mjtJoint.mjJNT_FREE): 6, int(mujoco.mjtJoint.mjJNT_BALL): 3}.get(
            int(model.jnt_type[found]), 1
        )
        rows = tuple(range(start, start + width))
    index = int(match["index"] or 0)
    array = getattr(model, field)
    length = 1 if array.ndim == 1 else array.shape[1]
    if index >= length:
        raise BadInputError(f"{name}: {kind} {attribute} has {length} value(s), index 0 to {length - 1}")
    return Target(name, field=field, rows=rows, index=index)


def _axes(
    model: mujoco.MjModel, vary: Mapping[str, AxisSpec | Sequence[str]]
) -> list[tuple[Axis, Target, list[float] | None]]:
    """(axis, target, the chosen enum values for a named option or None) of each entry of `vary`."""
    if not isinstance(vary, Mapping):
        raise BadInputError(
            f"vary takes a mapping, name -> {_TYPED}, not {vary!r} (the command line's NAME=LOW:HIGH:N[:log] is"
            " springlab sweep --vary's)"
        )
    if not vary:
        raise BadInputError(f"a sweep needs at least one --vary NAME=LOW:HIGH:N[:log] ({FORM})")
    return [_axis(model, str(name), given) for name, given in vary.items()]


def _axis(model: mujoco.MjModel, name: str, given: AxisSpec | Sequence[str]) -> tuple[Axis, Target, list[float] | None]:
    """(axis, target, the chosen enum values for a named option or None) of `vary[name]`."""
    aim = target(model, name)
    if aim.choices is None:
        axis = typed_axis(name, cast(AxisSpec, given))
        for value in (axis.low, axis.high):
            aim.check(value)
        return axis, aim, None
    if isinstance(given, (str, bytes)) or not all(isinstance(label, str) for label in given):
        raise BadInputError(f"vary[{name!r}] takes a sequence of names, e.g. ('euler', 'rk4'), got {given!r}")
    picked = [str(label) for label in given]
    unknown = [p for p in picked if p not in aim.choices]
    if not picked or unknown:
        raise UnknownNameError(name, unknown[0] if unknown else "", aim.choices)
    codes = [float(aim.choices[p]) for p in picked]
    return make_axis(name, min(codes), max(codes), len(codes)), aim, codes


@dataclasses.dataclass(frozen=True)
class ModelSweepChunk:
    """A chunk of a model file's sweep: plain data; the worker rebuilds the model from `path`.

    Attributes
    ----------
    model
        the model file's path (locally), or its shipped text and assets (on dask: springlab.studies.audit.ship,
        compiled on the worker and checked there to equal the caller's).
    keyframe
        where every run starts (None: the first keyframe, else qpos0 at rest).
    integrator
        the integrator of every configuration that does not vary it.
    dt
        the timestep [s] of every configuration that does not vary it.
    duration
        simulated time of every run [s].
    configurations
        each configuration's (name, value) pairs, as the targets take them.
    """

    model: str | Shipped
    keyframe: str | None
    integrator: str
    dt: float
    duration: float
    configurations: tuple[tuple[tuple[str, float], ...], ...]


def run_model_chunk(payload: ModelSweepChunk, nthread: int = 0) -> list[dict[str, Any]]:
    """Run one chunk of a model file's sweep as one batched MuJoCo call; the rows for it (module-level, plain
    data: dask ships it to workers)."""
    base = model_files.load(payload.model) if isinstance(payload.model, str) else compiled(payload.model)
    start = operating_point(base, payload.keyframe)
    setup = Setup(qpos=start.qpos, qvel=start.qvel, act=start.act, control=start.ctrl if base.nu else None)
    jobs: list[Job] = []
    rows: list[dict[str, Any]] = []
    for configuration in payload.configurations:
        model = copy.copy(base)
        model.opt.integrator, model.opt.timestep = integrator_id(payload.integrator), payload.dt
        named: dict[str, Any] = {}
        for name, value in configuration:
            aim = target(model, name)
            aim.apply(model, value)
            if aim.choices is not None:
                named[name] = next(label for label, code in aim.choices.items() if code == value)
        if any(name.endswith((".mass", ".armature")) for name, _ in configuration):
            # constants MuJoCo derives from masses at compile time (subtree masses, inverse weights)
            mujoco.mj_setConst(model, mujoco.MjData(model))
        integrator, dt = integrator_name(model), float(model.opt.timestep)
        jobs.append(Job(model, integrator, dt, check_timing(dt, payload.duration), setup))
        parameters = dict(configuration) | {"opt.timestep": dt}
        rows.append({"parameters": parameters, "quantities": named, "errors": {}, "passed": None, "diverged": False})
    for job, row, outcome in zip(jobs, rows, run_rollout(jobs, nthread=nthread, private_models=True)):
        if isinstance(outcome, DivergedError):
            row.update(diverged=True, detail=f"diverged: {outcome}")
        else:
            row.update(quantities={**row["quantities"], **measures(job.model, outcome)}, detail="")
    return rows


def model_sweep(
    model: str | os.PathLike[str],
    *,
    vary: Mapping[str, AxisSpec | Sequence[str]],
    keyframe: str | None = None,
    samples: int | None = None,
    sample_seed: int = 0,
    integrator: str | None = None,
    dt: float | None = None,
    duration: float | None = None,
    chunk_size: int = CHUNK_CONFIGURATIONS,
    executor: Executor | None = None,
) -> ModelSweep:
    """Run a model file over a grid (or random samples) of its options and named attributes; one row each.

    Parameters
    ----------
    model
        the path of an MJCF (or URDF MuJoCo loads) file.
    vary
        NAME -> (low, high, n) or (low, high, n, "log") [NAME's unit] (n may be None with `samples`);
        opt.integrator and opt.cone take a sequence of names instead, e.g. ("euler", "rk4") (see the module
        docstring for NAME). The command line's 'NAME=LOW:HIGH:N[:log]' strings are a BadInputError.
    keyframe
        where every run starts (None: the first keyframe, else qpos0 at rest); its controls are held.
    samples
        draw this many random points in the box instead of the full grid (a named option: uniformly).
    sample_seed
        seed of the random points (as `springlab.sweep`'s; `seed` before issue 32).
    integrator, dt
        the setting of the configurations that do not vary it (None: the model's own).
    duration
        simulated time of every run [s] (None: 1 s).
    chunk_size
        configurations per batched call.
    executor
        where the chunks run (None: locally).

    Returns
    -------
    ModelSweep
        a Sweep, the rows in configuration order: `scene` is the model file, `scenario` the start, each row's
        quantities what `springlab run MODEL.xml` measures (and the name of a named option), `passed` None.

    Raises
    ------
    BadInputError
        no such file or keyframe, an unknown name (the message lists the valid ones), a bad range or value.
    """
    started = _time.perf_counter()
    text = os.fspath(model)
    mj_model = model_files.load(text)
    start = operating_point(mj_model, keyframe)
    parsed = _axes(mj_model, vary)
    names = [axis.name for axis, _, _ in parsed]
    if integrator == "auto":
        raise BadInputError("a sweep runs one setting for every configuration; name an integrator, not 'auto'")
    integrator = integrator_name(mj_model) if integrator is None else integrator
    integrator_id(integrator)
    dt = float(mj_model.opt.timestep) if dt is None else dt
    duration = DEFAULT_DURATION if duration is None else duration
    check_timing(dt, duration)
    values = _configurations(parsed, samples, sample_seed)
    count = len(values[names[0]])
    for (_, aim, _), column in zip(parsed, values.values()):
        for value in column:
            aim.check(float(value))
        if aim.option == "timestep":
            check_timing(float(np.min(column)), duration)
    runner = resolve(executor)
    source: str | Shipped = ship(("path", text), mj_model) if runner.distributed else text
    pieces = chunked(count, chunk_size)
    payloads = [
        ModelSweepChunk(
            source,
            None if keyframe is None else str(keyframe),
            integrator,
            float(dt),
            float(duration),
            tuple(tuple((name, float(values[name][i])) for name in names) for i in piece),
        )
        for piece in pieces
    ]
    results = runner.map(run_model_chunk, payloads, description="sweep", sizes=[len(p) for p in pieces], unit="run")
    rows = tuple(
        SweepRow(values={name: float(values[name][i]) for name in names}, **row)
        for i, row in enumerate(r for chunk in results for r in chunk)
    )
    return ModelSweep(
        scene=text,
        scenario=start.label,
        integrator=integrator,
        dt=float(dt),
        duration=float(duration),
        axes=tuple(axis for axis, _, _ in parsed),
        samples=samples,
        values=values,
        rows=rows,
        wall_time_s=_time.perf_counter() - started,
        executor=runner.describe(),
        chunks=len(pieces),
    )


def _configurations(
    parsed: Sequence[tuple[Axis, Target, list[float] | None]], samples: int | None, sample_seed: int
) -> dict[str, np.ndarray]:
    """Name -> (n,) values: the full grid (last axis fastest) or `samples` random points; a named option
    takes its listed values (uniformly drawn among them with `samples`)."""
    axes = [axis for axis, _, _ in parsed]
    if samples is not None:
        if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 1:
            raise BadInputError(f"--samples must be an integer >= 1, got {samples!r}")
        unit = np.random.default_rng(sample_seed).random((int(samples), len(axes)))
        out = {}
        for j, (axis, _, codes) in enumerate(parsed):
            if codes is None:
                out[axis.name] = axis.sample(unit[:, j])
            else:
                out[axis.name] = np.array(codes)[np.minimum((unit[:, j] * len(codes)).astype(int), len(codes) - 1)]
        return out
    missing = [axis.name for axis, _, codes in parsed if codes is None and axis.count is None]
    if missing:
        raise BadInputError(f"--vary {missing[0]} needs N (NAME=LOW:HIGH:N) unless --samples is given")
    grids = [np.array(codes) if codes is not None else axis.values() for axis, _, codes in parsed]
    total = math.prod(len(grid) for grid in grids)
    if total > MAX_CONFIGURATIONS:
        raise BadInputError(f"the grid has {total} configurations, more than {MAX_CONFIGURATIONS}; use --samples")
    mesh = np.meshgrid(*grids, indexing="ij")
    return {axis.name: m.ravel() for axis, m in zip(axes, mesh)}


@dataclasses.dataclass(frozen=True, repr=False)
class ModelSweep(Sweep):
    """A model file's sweep: a `Sweep` whose `scene` is the file and `scenario` the start, whose rows are measured,
    never validated (`passed` None), and whose answer says so."""

    def _shown(self) -> display.Summary:
        """The sweep as a notebook shows it: no verdict (nothing validated), the counts, the setting, the rows."""
        shown = super()._shown()
        return dataclasses.replace(
            shown,
            kind="ModelSweep",
            title=f"{self.scene} from {self.scenario}",
            verdict="not validated",
            ok=None,
            message=f"{self.size} configurations measured, {self.diverged} diverged (a model file has no exact solution)",
        )

    @property
    def headline(self) -> str | None:
        """What the answer and sweep.png quote by default (`default_quantity`)."""
        return default_quantity(self)

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: how the headline quantity ranges over the configurations that ran, and
        how many diverged; nothing passes or fails."""
        say = answers.Quoter()
        varied = ", ".join(a.name for a in self.axes)
        name = self.headline or "energy_final_J"
        question = (
            f"How does {name} of {self.scene} from {self.scenario} vary with {varied} over {self.size}"
            f" configurations ({self.integrator}, dt = {answers.written(self.dt, '~s')} unless varied)?"
        )
        counts = (
            f"{say('configurations', self.size, spec='d')} configurations ran, {say('diverged', self.diverged, spec='d')}"
            " diverged; measured, not validated (a model file has no exact solution)"
        )
        values = self.column(name)
        finite = np.flatnonzero(np.isfinite(values))
        if not finite.size:
            return say.answer(question, f"{counts}; no configuration has a value of {name}.")
        low, high = int(finite[np.argmin(values[finite])]), int(finite[np.argmax(values[finite])])
        unit = answers.unit_of(name)
        words = {
            i: ", ".join(f"{n} = {answers.written(float(self.values[n][i]))}" for n in self.values) for i in (low, high)
        }
        return say.answer(
            question,
            f"{counts}. {name} ranges from {say(f'{name}_min', float(values[low]), unit)} ({words[low]}) to"
            f" {say(f'{name}_max', float(values[high]), unit)} ({words[high]}).",
        )


def default_quantity(sweep: Sweep) -> str:
    """What a model file's sweep shows by default: the largest excursion of the joint that moves most in the first
    configuration that ran (a gripper's box, a pendulum's hinge), else the final energy."""
    for row in sweep.rows:
        if not row.diverged:
            excursions = {k: v for k, v in row.quantities.items() if "_max_excursion_" in k}
            if excursions:
                return max(excursions, key=lambda k: abs(excursions[k]))
            break
    return "energy_final_J"
