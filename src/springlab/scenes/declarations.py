"""The plain data of a scene: what it declares (its parameters and scenarios) and what it answers with (an
exact reference, scalar checks). springlab.scenes.base builds on these; they import nothing of the scenes.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from springlab.errors import ParameterError


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
        """Return `value` as a float, or raise ParameterError saying what is valid."""
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
