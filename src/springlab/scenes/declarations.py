"""The plain data of a scene: what it declares (its parameters and scenarios) and what it answers with (an
exact reference, scalar checks). springlab.scenes.base builds on these; they import nothing of the scenes.

Also the one set of names no scene parameter may take, `STUDY_OPTIONS`: every study takes a scene's
parameters as keyword arguments beside its own options (`springlab.sweep("slider", vary=..., mass=2.0)`), so
a parameter named like an option would be taken for the option. `keyword_parameters` is what each study
calls on its `**parameters`.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Collection, Mapping
from typing import Any

import numpy as np

from springlab.errors import BadInputError, ParameterError

#: Every name a public study (springlab.run, validate, sweep, tradeoff, design, fit, stability, refine,
#: friction_settings, rms, rms_settings, frequency, audit) takes besides a scene's parameters, and the names
#: their first argument and parameters had before issue 32. A scene parameter named like one would be taken
#: for the option (or refused), so no scene may declare one: tests/studies/test_api.py holds every scene and every
#: study's signature to this set, and a study's new option is added here.
STUDY_OPTIONS: frozenset[str] = frozenset(
    {
        # every study: the model, its scenario, where the chunks run
        "model",
        "scenario",
        "executor",
        "nthread",
        # the setting and its tolerance
        "integrator",
        "dt",
        "duration",
        "tol",
        "integrators",
        "dts",
        # sweep
        "vary",
        "samples",
        "sample_seed",
        "chunk_size",
        # design
        "levels",
        "plane_levels",
        "omega_dt",
        "sobol",
        "sobol_seed",
        # fit
        "data",
        "map",
        "free",
        "scale",
        "time_scale",
        "start",
        "degree",
        "run_scene",
        "starts",
        "workers",
        "scheduler",
        "show_progress",
        # stability
        "full",
        # refine, friction_settings
        "question",
        "sizes",
        "scenarios",
        "values",
        "bodies",
        "hold_s",
        # rms, rms_settings
        "seeds",
        "record",
        "level",
        "seed_counts",
        # frequency
        "input",
        "response",
        "band",
        "points",
        "sines",
        "amplitudes",
        "sweep",
        # audit, and a model file's run, sweep and friction settings
        "keyframe",
        "settle_s",
        "perturb",
        # names before issue 32: the first argument, the parameters as one mapping
        "scene",
        "scene_or_model",
        "model_or_path",
        "scene_names",
        "parameters",
        "overrides",
    }
)
#: the first argument's names before issue 32 (it is `model` in every study now)
_FIRST_ARGUMENT_BEFORE = ("scene", "scene_or_model", "model_or_path", "scene_names")


def keyword_parameters(
    study: str,
    parameters: Mapping[str, Any],
    *,
    declared: Collection[str] = (),
    renamed: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    """A study's `**parameters`, checked to be a scene's parameters and not an option spelled another way.

    Parameters
    ----------
    study
        the study's public name (for the message), e.g. 'sweep'.
    parameters
        the keyword arguments the study did not bind to an option.
    declared
        the scene's parameter names (empty: unknown here, e.g. a model file).
    renamed
        old option keyword -> its new name, for this study's options renamed in issue 32 (sweep's
        `seed` is `sample_seed`). Where the scene declares a parameter of the old name (the printer
        head's `seed`), the keyword is that parameter and a DeprecationWarning says so.

    Returns
    -------
    dict[str, Any]
        the scene parameter overrides, name -> value.

    Raises
    ------
    TypeError
        an old spelling (a renamed option, the first argument's old name, `parameters=` or `overrides=`
        as one mapping) or another study's option, as Python says of an unexpected keyword.
    """
    renamed = renamed or {}
    for name in parameters:
        if name in renamed and name in declared:
            warnings.warn(
                f"{study}(): {name}= sets the scene's parameter {name}; the study's option it named before issue 32"
                f" is {renamed[name]}=",
                DeprecationWarning,
                stacklevel=3,
            )
        elif name in renamed:
            raise TypeError(f"{study}() takes {renamed[name]}= where it took {name}= (renamed in issue 32)")
        elif name in _FIRST_ARGUMENT_BEFORE:
            raise TypeError(
                f"{study}()'s first argument is `model` (it was `{name}`): pass the scene name first, e.g."
                f" {study}('slider', ...)"
            )
        elif name in ("parameters", "overrides"):
            raise TypeError(
                f"{study}() takes a scene's parameters as keyword arguments (mass=2.0, damping=4.0), not {name}={{...}}:"
                f" unpack the mapping, {study}(model, **{name})"
            )
        elif name in STUDY_OPTIONS:
            raise TypeError(
                f"{study}() got an unexpected keyword argument {name!r} (an option of another study; no scene"
                " parameter is named like one)"
            )
    return dict(parameters)


def refuse_text(option: str, value: object, typed: str, *, numbers: bool = False) -> None:
    """Refuse the command line's string where a study takes a typed value (only `springlab.cli` parses text).

    Parameters
    ----------
    option
        the keyword, e.g. 'integrators'.
    value
        what was passed.
    typed
        the typed form, e.g. "a sequence of names, e.g. integrators=['rk4', 'euler']".
    numbers
        `value` is a sequence of numbers: a string among them is refused too.

    Raises
    ------
    BadInputError
        `value` is a string (or, with `numbers`, holds one).
    """
    if isinstance(value, (str, bytes)):
        raise BadInputError(f"{option} takes {typed}, not the command line's string {value!r}")
    if numbers and isinstance(value, (list, tuple)) and any(isinstance(v, (str, bytes)) for v in value):
        raise BadInputError(f"{option} takes {typed}, not strings: got {value!r}")


@dataclasses.dataclass(frozen=True)
class Parameter:
    """A scene parameter in SI units.

    Attributes
    ----------
    name
        as used by `--set NAME=VALUE` and keyword arguments.
    unit
        SI unit, e.g. 'kg', 'N/m', 'N s/m', 'm', 'm/s', 'Hz', '-' for none.
    description
        one line.
    minimum
        lowest valid value (None: unbounded).
    minimum_inclusive
        whether `minimum` itself is valid.
    maximum
        highest valid value (None: unbounded).
    default
        default value, or None when it is read back from the model.
    reason
        why the range is what it is (added to the error message), e.g. MIN_MASS_REASON.
    """

    name: str
    unit: str
    description: str
    minimum: float | None = None
    minimum_inclusive: bool = True
    maximum: float | None = None
    default: float | None = None
    reason: str = ""

    def valid_range(self) -> str:
        """Human-readable valid range, e.g. '> 0 kg'."""
        unit = "" if self.unit == "-" else f" {self.unit}"
        parts = []
        if self.minimum is not None:
            parts.append(f"{'>=' if self.minimum_inclusive else '>'} {self.minimum:g}")
        if self.maximum is not None:
            parts.append(f"<= {self.maximum:g}")
        return (" and ".join(parts) or "any finite value") + unit

    def check(self, value: Any) -> float:
        """Return `value` as a float, or raise ParameterError saying what is valid.

        A string is refused: the library takes numbers, and only the command line parses `--set`'s text.
        """
        if isinstance(value, (str, bytes)):
            raise ParameterError(f"{self.name} must be a number {self.valid_range()}, got {value!r}")
        try:
            number = float(value)
        except (TypeError, ValueError):
            raise ParameterError(f"{self.name} must be a number {self.valid_range()}, got {value!r}") from None
        low_ok = self.minimum is None or number > self.minimum or (self.minimum_inclusive and number == self.minimum)
        high_ok = self.maximum is None or number <= self.maximum
        if not math.isfinite(number) or not low_ok or not high_ok:
            why = f" ({self.reason})" if self.reason else ""
            raise ParameterError(f"{self.name} must be a finite number {self.valid_range()}{why}, got {value!r}")
        return number


@dataclasses.dataclass(frozen=True)
class Scenario:
    """A named question a scene answers.

    Attributes
    ----------
    name
        scenario name.
    description
        one line.
    duration
        default simulated time [s].
    presets
        parameter values this scenario sets (user overrides win).
    derive
        optional function(params, explicitly_set_names) -> extra values,
        for presets that depend on other parameters (e.g. damping from a ratio).
    exact
        whether an exact reference exists (validated by `validate`).
    dt
        the scenario's validated timestep [s] (None: the scene's `dt`).
    integrator
        the scenario's validated integrator (None: the scene's `integrator`), for a scenario whose model
        another integrator runs more cheaply (e.g. a stiff damper that only an implicit one steps at a
        useful dt).
    variant
        for a scene whose scenarios differ in their model (e.g. the car: 1 DOF,
        pitch/heave, quarter car), the object that carries what differs; the scene's
        hooks delegate to it instead of dispatching on scenario names (None: unused).
    """

    name: str
    description: str
    duration: float
    presets: Mapping[str, float] = dataclasses.field(default_factory=dict)
    derive: Callable[[dict[str, float], set[str]], dict[str, float]] | None = None
    exact: bool = True
    dt: float | None = None
    integrator: str | None = None
    variant: Any = None


@dataclasses.dataclass
class Reference:
    """The exact solution of a scenario at the trajectory's times.

    Attributes
    ----------
    pos, vel
        joint name -> exact position [m or rad] and velocity [m/s or rad/s].
    system
        for linear scenes, the matrix A [1/s] of the autonomous system
        z' = A z that generated the reference (forcing included as generator
        states); None otherwise. Used to derive the error bound.
    states
        (n, dim) exact z(t), or None.
    rows
        joint name -> (row of its position, row of its velocity) in z.
    tolerance
        for scenes without `system`, the relative tolerance [-] every
        compared column is held to, and `tolerance_basis` says why.
    tolerance_of
        instead of `tolerance`, where it depends on the run's integrator:
        integrator name -> that relative tolerance [-] (e.g. the printer
        head's closed loop, whose error the scene carries through its law).
        With a `system` beside it, that is only where the run must lie inside
        the range of a leading-order estimate (compare.estimate_range), not
        the tolerance's source.
    switches
        for a linear scene whose input is switched on a step boundary:
        [(time [s], A after it)], in time order; `system` holds before the first.
        The states z(t) stay continuous across a switch.
    input_error
        column -> exact max absolute difference [m or m/s] between the
        responses to the input the model realizes and the true input, added to
        that column's tolerance (`tolerance_basis` says where it comes from).
    roundoff
        column -> the absolute round-off [m or m/s] one step may add to it beyond the relative floor of 100 eps
        per step, added times the number of steps to that column's tolerance: where the column is a small
        difference of large terms (the velocity of a node of a stiff chain, whose spring forces nearly cancel).
    scales
        column -> the scale [m or m/s] its max_rel is relative to where the exact motion
        has none (max |ref| = 0: a block held at rest); otherwise max |ref| is.
    derived
        what the run layer derives from this reference alone (its tolerances per setting, its modes),
        kept so a reference kept by its case (`Case.reference`) is judged without recomputing them.
    """

    pos: dict[str, np.ndarray]
    vel: dict[str, np.ndarray]
    system: np.ndarray | None = None
    states: np.ndarray | None = None
    rows: dict[str, tuple[int, int]] = dataclasses.field(default_factory=dict)
    tolerance: float | None = None
    tolerance_basis: str = ""
    tolerance_of: Callable[[str], float] | None = None
    switches: list[tuple[float, np.ndarray]] = dataclasses.field(default_factory=list)
    input_error: dict[str, float] = dataclasses.field(default_factory=dict)
    roundoff: dict[str, float] = dataclasses.field(default_factory=dict)
    scales: dict[str, float] = dataclasses.field(default_factory=dict)
    derived: dict[Any, Any] = dataclasses.field(default_factory=dict, init=False, repr=False, compare=False)


@dataclasses.dataclass(frozen=True)
class Check:
    """A validated scalar claim of a scenario: a measured value against an independent reference.

    For scenes without an exact trajectory (non-linear ones), `validate` holds a
    scenario to its checks instead of (or besides) the compared columns.

    Attributes
    ----------
    name
        what is checked, ending in its unit like a quantity, e.g. 'period_s'.
    value
        measured from the simulation (in the name's unit).
    reference
        the independent expectation (closed form, quadrature, ...).
    tolerance
        bound on `error` [-]: relative, or absolute in the name's unit
        when the reference is 0.
    basis
        why the tolerance is what it is (one line).
    certifies_error
        whether `error` is an error of a physical result, which a PASS
        without a requested tolerance certifies only up to springlab.runs.compare.CERTIFIED_CAP
        (False for a diagnostic, e.g. an observed order of convergence against the
        integrator's).
    follows_tol
        a relative error [-] held to the run's own tolerance: the requested tolerance when
        there is one (`tolerance` then gives way to it), else `tolerance`.
    """

    name: str
    value: float
    reference: float
    tolerance: float
    basis: str
    certifies_error: bool = True
    follows_tol: bool = False

    @property
    def error(self) -> float:
        """|value - reference| / |reference|, or |value - reference| when the reference is 0."""
        difference = abs(float(self.value) - float(self.reference))
        return difference / abs(float(self.reference)) if self.reference != 0 else difference

    @property
    def passed(self) -> bool:
        """Whether the error is within the tolerance (False for a non-finite value)."""
        return bool(math.isfinite(self.error) and self.error <= self.tolerance)

    def to_dict(self) -> dict[str, Any]:
        """The summary.json form: name, value, reference, error, tolerance, basis, passed."""
        return {
            "name": self.name,
            "value": float(self.value),
            "reference": float(self.reference),
            "error": self.error,
            "tolerance": float(self.tolerance),
            "basis": self.basis,
            "passed": self.passed,
        }
