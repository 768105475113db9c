"""One call shape for every study (issue 32): `springlab.STUDY(model, [scenario,] *, options..., **parameters)`.

The first argument is `model`; the options are keyword-only and typed (the command line's strings are refused
with BadInputError, only `springlab.cli` parses them); a scene's parameters are keyword arguments, and no
scene parameter is named like an option (`springlab.scenes.declarations.STUDY_OPTIONS`): a new scene
parameter named like one, or a new option missing from that set, fails here by name.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
import inspect
import pathlib
import subprocess
import sys
import typing

import numpy as np
import pytest

import springlab
from helpers import source
from springlab import scenes
from springlab.errors import BadInputError
from springlab.scenes.declarations import STUDY_OPTIONS

#: the positional arguments a study may take after `model`: what it asks (a scenario, a question, cases, data)
SECOND_ARGUMENTS = {"scenario", "question", "scenarios", "data"}
#: studies without a model, and why
WITHOUT_MODEL = {"stability": "it measures the integrators themselves, on the textbook oscillator"}
#: studies whose model may be any MJCF: no scene parameters where the model is a file (audit takes none)
WITHOUT_SCENE_PARAMETERS = {"validate": "it runs each scene's own scenarios", "audit": "any MJCF, no scene"}


def _study(name: str) -> typing.Callable[..., object]:
    return getattr(springlab, name)


def _options(name: str) -> list[inspect.Parameter]:
    return [p for p in inspect.signature(_study(name)).parameters.values() if p.kind is not p.VAR_KEYWORD]


def test_every_study_is_exported_and_public():
    assert set(springlab.STUDIES) <= set(springlab.__all__)
    for name in springlab.STUDIES:
        assert inspect.isfunction(_study(name)), name
        assert _study(name).__doc__, name


@pytest.mark.parametrize("name", springlab.STUDIES)
def test_the_first_argument_is_model_and_the_options_are_keyword_only(name):
    parameters = _options(name)
    if name in WITHOUT_MODEL:
        assert all(p.kind is p.KEYWORD_ONLY for p in parameters)
        return
    first, *rest = parameters
    assert first.name == "model" and first.kind is first.POSITIONAL_OR_KEYWORD
    positional = [p.name for p in rest if p.kind is not p.KEYWORD_ONLY]
    # fit(model, data, scenario): its data and then, as DESIGN.md documents, the scenario
    assert set(positional) <= SECOND_ARGUMENTS and len(positional) <= (2 if name == "fit" else 1), positional


@pytest.mark.parametrize("name", springlab.STUDIES)
def test_scene_parameters_arrive_as_keywords_of_numbers(name):
    variadic = [
        p for p in inspect.signature(_study(name), eval_str=True).parameters.values() if p.kind is p.VAR_KEYWORD
    ]
    if name in WITHOUT_MODEL or name in WITHOUT_SCENE_PARAMETERS:
        assert not variadic
        return
    assert [p.name for p in variadic] == ["parameters"] and variadic[0].annotation is float


@pytest.mark.parametrize("name", springlab.STUDIES)
def test_every_option_is_in_the_reserved_names(name):
    """A study's new option joins STUDY_OPTIONS, so no scene can declare a parameter of its name."""
    missing = sorted({p.name for p in _options(name)} - STUDY_OPTIONS)
    assert not missing, f"add {missing} to springlab.scenes.declarations.STUDY_OPTIONS"


@pytest.mark.parametrize("scene", list(scenes.SCENES))
def test_no_scene_parameter_is_named_like_a_study_option(scene):
    """Scene parameters reach every study as keywords beside its options: one named like an option (`dt`,
    `tol`, `band`, `samples` ...) would be taken for the option."""
    clashes = sorted(STUDY_OPTIONS & set(scenes.SCENES[scene].parameters))
    assert not clashes, f"{scene} declares parameters named like a study's option: {clashes}"


@pytest.mark.parametrize(
    "call, typed",
    [
        (lambda: springlab.run("slider", dt="1e-3"), "dt must be a finite number"),
        (lambda: springlab.run("slider", mass="2"), "mass must be a number"),
        (lambda: springlab.sweep("slider", vary=["damping=1:2:2"]), "vary takes a mapping"),
        (lambda: springlab.sweep("slider", vary={"damping": "1:2:2"}), "vary['damping'] takes (low, high, n)"),
        (lambda: springlab.sweep("slider", vary={"damping": ("1", "2", 2)}), "takes numbers"),
        (lambda: springlab.tradeoff("slider", tol="1e-6"), "tol must be a finite number"),
        (lambda: springlab.fit("slider", "x.csv", map=["t=time"]), "map takes a mapping"),
        (lambda: springlab.fit("slider", "x.csv", free="omega_n,zeta"), "free takes a sequence of names"),
        (lambda: springlab.refine("drill_string", sizes="4,8"), "sizes takes a sequence of whole numbers"),
        (lambda: springlab.refine("drill_string", integrators="rk4,euler"), "integrators takes a sequence"),
        (lambda: springlab.friction_settings("friction", dts="0.002,0.001"), "dts takes a sequence of timesteps"),
        (lambda: springlab.friction_settings("friction", dts=["0.002", "0.001"]), "dts takes a sequence"),
        (lambda: springlab.friction_settings("friction", integrators="rk4"), "integrators takes a sequence"),
        (lambda: springlab.friction_settings("friction", "incline_hold"), "scenarios takes a sequence"),
        (lambda: springlab.rms("stay_cable", seeds="8"), "seeds takes a count or a sequence"),
        (lambda: springlab.rms("stay_cable", level="0.9"), "level must"),
        (lambda: springlab.rms("stay_cable", record="60"), "got '60'"),
        (lambda: springlab.rms_settings("stay_cable", tol="0.1"), "tol must be a finite number"),
        (lambda: springlab.rms_settings("stay_cable", tol=0.1, integrators="rk4"), "integrators takes a sequence"),
        (lambda: springlab.design("printer_head", levels="3"), "levels must"),
        (lambda: springlab.frequency("slider", band="0.1:10"), "band=(0.1, 10.0)"),
        (lambda: springlab.audit("slider", dts="0.001,0.002"), "dts"),
        (lambda: springlab.audit("slider", integrators="rk4"), "integrators"),
    ],
)
def test_the_library_refuses_the_command_lines_strings(call, typed):
    with pytest.raises(BadInputError) as raised:
        call()
    assert typed in str(raised.value)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: springlab.run("slider", parameters={"mass": 2.0}), "keyword arguments (mass=2.0"),
        (lambda: springlab.frequency("nonlinear", parameters={"k3": 1e4}), "not parameters={...}"),
        (lambda: springlab.design("printer_head", overrides={"kp": 1.0}), "not overrides={...}"),
        (lambda: springlab.sweep("slider", vary={"mass": (1, 2, 2)}, seed=3), "sample_seed= where it took seed="),
        (lambda: springlab.run("slider", samples=3), "unexpected keyword argument 'samples'"),
        (lambda: springlab.tradeoff("slider", "free", scene="car"), "first argument is `model`"),
        (lambda: springlab.validate(scene_names=["slider"]), "scene_names"),
        (lambda: springlab.sweep(scene="slider", vary={"mass": (1, 2, 2)}), "model"),
    ],
)
def test_an_old_spelling_is_a_clear_type_error(call, message):
    with pytest.raises(TypeError) as raised:
        call()
    assert message in str(raised.value)


def test_seed_is_the_scenes_parameter_where_it_declares_one_and_warns():
    """The printer head's `seed` (its accelerometer noise) is a parameter; sweep's old `seed=` meant the
    sampling seed, so that spelling warns instead of changing meaning silently."""
    from springlab.scenes.declarations import keyword_parameters

    with pytest.warns(DeprecationWarning, match="sample_seed="):
        given = keyword_parameters(
            "sweep", {"seed": 7.0}, declared=scenes.SCENES["printer_head"].parameters, renamed={"seed": "sample_seed"}
        )
    assert given == {"seed": 7.0}


def test_the_scene_registry_is_read_only():
    with pytest.raises(TypeError):
        springlab.SCENES["mine"] = springlab.SCENES["slider"]  # type: ignore[index]
    with pytest.raises(AttributeError):
        springlab.SCENES.pop("slider")  # type: ignore[attr-defined]
    assert list(springlab.SCENES)[:2] == ["slider", "car"] and "slider" in springlab.SCENES


def test_importing_springlab_imports_no_scene():
    """The registry is filled on its first lookup, not by `import springlab` (CONTRIBUTING: import has no
    side effects)."""
    code = (
        "import sys, springlab\n"
        "print(sorted(m for m in sys.modules if m.startswith('springlab.scenes.') and m.count('.') == 2"
        " and m.split('.')[2] not in ('base', 'capabilities', 'checks', 'declarations')))\n"
        "springlab.SCENES['slider']\n"
        "print('springlab.scenes.slider' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[:2] == ["[]", "True"]


def test_validate_takes_one_scene_name_or_several():
    one = [(row.scene, row.scenario) for row in springlab.validate("kinematics")]
    assert one and one == [(row.scene, row.scenario) for row in springlab.validate(["kinematics"])]


#: functions docs/api.md documents outside `springlab.__all__` (a model file's sweep and trade-off, the output
#: writer, the run at a named setting): their user inputs are held to the same rule
DOCUMENTED_ELSEWHERE = (
    "springlab.studies.model_sweep.model_sweep",
    "springlab.studies.model_tradeoff.model_tradeoff",
    "springlab.outputs.write",
    "springlab.runs.run.run_scenario",
)


def _type_checking_names() -> dict[str, object]:
    """What the package's annotations name but imports only for mypy (`if TYPE_CHECKING:` blocks: pandas,
    Figure, ...), and the modules its modules import (a type alias written as a string, such as fit's
    DataSource, is evaluated where it is used): the namespace `typing.get_type_hints` needs to resolve
    every annotation as mypy does."""
    names: dict[str, object] = {}
    for module in [m for name, m in sorted(sys.modules.items()) if name.startswith("springlab") and m is not None]:
        names.update({k: v for k, v in vars(module).items() if inspect.ismodule(v) and k not in names})
        path = getattr(module, "__file__", None) or ""
        # the module's syntax tree, parsed once per test process with the other readers' (helpers/source.py)
        body = source.tree(pathlib.Path(path)).body if path.endswith(".py") else []
        for node in body:
            if isinstance(node, ast.If) and ast.unparse(node.test) in ("TYPE_CHECKING", "typing.TYPE_CHECKING"):
                found: dict[str, object] = {"__name__": module.__name__, "__package__": module.__package__}
                exec(compile(ast.Module(body=node.body, type_ignores=[]), module.__name__, "exec"), found)
                names.update({k: v for k, v in found.items() if not k.startswith("__") and k not in names})
    return names


def _public_callables() -> list[tuple[str, typing.Callable[..., object]]]:
    """Every function in `springlab.__all__` (and in its exported modules), the public methods of its classes
    (a result's generated `__init__` is left out: the studies build results, a user reads them), and
    DOCUMENTED_ELSEWHERE."""
    found: list[tuple[str, typing.Callable[..., object]]] = []
    for name in springlab.__all__:
        exported = getattr(springlab, name)
        if inspect.isfunction(exported):
            found.append((f"springlab.{name}", exported))
        elif inspect.ismodule(exported):
            members = [getattr(exported, n) for n in getattr(exported, "__all__", dir(exported)) if n[0] != "_"]
            found += [
                (f"springlab.{name}.{f.__name__}", f)
                for f in members
                if inspect.isfunction(f) and f.__module__.startswith("springlab")
            ]
        elif inspect.isclass(exported):
            # its own and inherited methods (a result's base class, display.Shown), nearest definition first
            inherited: dict[str, object] = {}
            for base in [c for c in exported.__mro__ if c.__module__.startswith("springlab")]:
                inherited.update({k: v for k, v in vars(base).items() if k not in inherited})
            for attribute, member in inherited.items():
                method = member.__func__ if isinstance(member, (classmethod, staticmethod)) else member
                generated = attribute == "__init__" and dataclasses.is_dataclass(exported)
                if inspect.isfunction(method) and (attribute[0] != "_" or attribute == "__init__") and not generated:
                    found.append((f"springlab.{name}.{attribute}", method))
    for path in DOCUMENTED_ELSEWHERE:
        module, _, function = path.rpartition(".")
        found.append((path, getattr(importlib.import_module(module), function)))
    return found


def _holds_any(hint: object) -> bool:
    """`Any` itself or anywhere inside (Sequence[Any], Mapping[str, Any], a union, a Callable's arguments);
    numpy's own aliases (npt.ArrayLike holds dtype[Any]) are numpy's typed forms, not an untyped input."""
    if hint is typing.Any:
        return True
    origin = typing.get_origin(hint)
    if getattr(origin, "__module__", "").startswith("numpy") or getattr(hint, "__module__", "").startswith("numpy"):
        return False
    return any(_holds_any(a) for arg in typing.get_args(hint) for a in (arg if isinstance(arg, list) else [arg]))


def test_no_public_signature_takes_an_untyped_user_input():
    """Issue 32: mypy finds no `Any` in a public signature's user inputs (resolved as mypy does, through
    `typing.get_type_hints`), so the command line's strings cannot hide behind one."""
    namespace = _type_checking_names()
    untyped = []
    for where, function in _public_callables():
        hints = typing.get_type_hints(function, globalns={**namespace, **function.__globals__})
        hints.pop("return", None)
        untyped += [f"{where}({parameter}: {hint})" for parameter, hint in hints.items() if _holds_any(hint)]
    assert not untyped, "typed Any: " + "; ".join(untyped)


def test_the_walk_sees_the_studies_and_their_results_methods():
    """The check above is only as good as what it walks: the studies, an exported module's functions, a
    result's methods and the documented deep paths are all in it."""
    walked = {where for where, _ in _public_callables()}
    assert {f"springlab.{name}" for name in springlab.STUDIES} <= walked
    assert {"springlab.analytic.free_response", "springlab.Sweep.plot", *DOCUMENTED_ELSEWHERE} <= walked


@pytest.mark.parametrize(
    "vary, typed",
    [
        (["opt.impratio=1:10:2"], "vary takes a mapping, name -> (low, high, n)"),
        ({"opt.impratio": "1:10:2"}, "not the command line's string '1:10:2'"),
        ({"opt.impratio": ("1", "10", 2)}, "takes numbers"),
        ({"opt.integrator": "euler,rk4"}, "takes a sequence of names, e.g. ('euler', 'rk4')"),
    ],
)
def test_a_model_files_sweep_refuses_the_command_lines_strings(tmp_path, vary, typed):
    from springlab.studies.model_sweep import model_sweep

    path = tmp_path / "mass.xml"
    path.write_text(
        '<mujoco><worldbody><body><joint name="x" type="slide" stiffness="100"/>'
        '<geom type="sphere" size="0.1" mass="1"/></body></worldbody></mujoco>'
    )
    with pytest.raises(BadInputError) as raised:
        model_sweep(path, vary=vary, duration=0.01)
    assert typed in str(raised.value)


def test_a_model_files_sweep_samples_with_sample_seed_as_the_scene_sweep_does(tmp_path):
    """One name for one idea: both sweeps draw their random points with `sample_seed`; the old `seed=` is
    Python's own TypeError (no caller outside springlab.cli used it, and `vary` changed form at once)."""
    from springlab.studies.model_sweep import model_sweep

    path = tmp_path / "mass.xml"
    path.write_text(
        '<mujoco><worldbody><body><joint name="x" type="slide" stiffness="100"/>'
        '<geom type="sphere" size="0.1" mass="1"/></body></worldbody></mujoco>'
    )
    vary = {"joint.x.stiffness": (50.0, 200.0, None)}
    first, again = (model_sweep(path, vary=vary, samples=3, sample_seed=5, duration=0.01) for _ in range(2))
    unit = np.random.default_rng(5).random((3, 1))[:, 0]
    assert list(first.values["joint.x.stiffness"]) == list(again.values["joint.x.stiffness"])
    assert np.array_equal(first.values["joint.x.stiffness"], 50.0 + unit * 150.0)
    with pytest.raises(TypeError, match="seed"):
        model_sweep(path, vary=vary, samples=3, seed=5, duration=0.01)  # type: ignore[call-arg]
