"""What `springlab fit` can identify in a scene, from which signal, and what it refuses: the machinery behind
each kind of fit a scene declares (`Scene.fit`, springlab.scenes.capabilities).

`model_of(scene)` reads the declaration and gives its `FitModel`: the names a fit may free (with
units), the default free set, the identifiability rules, how fitted values become the scene's
parameters and initial state, a start from the data by linear algebra (no optimizer), and the closed
form the MuJoCo fit is cross-checked against. The study never names a scene: two kinds of declaration,
two models.

An `OscillatorFit` observes one coordinate x of a mode m x'' + d x' + k (x - x_eq) = F: m, k, d are
the scene's parameters the declaration names (or m is the mode's mass its `mode_mass` hook derives,
then fixed), x_eq its `rest` parameter (or 0), F a step force of the scenarios it lists (or 0).

A free decay depends on k/m and d/m only, so of mass, stiffness and damping at
most two can be fitted, and then only while the third is not zero; omega_n and
zeta are the same information in modal form. The initial state at the record's
start (x0 [m], v0 [m/s]) and a constant sensor offset are nuisance parameters;
a sensor delay (or the moment of a release from rest) is identifiable only
when the initial velocity is known, because shifting a free response in time is
the same as changing its initial state.

A `PolynomialFit` observes x(t) = x0 + v0 t + a0 t^2 / 2 + jerk t^3 / 6 (its coefficients c_n, the
n-th derivatives at t = 0, up to the degree it declares): velocity data cannot give x0,
acceleration data neither x0 nor v0.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from springlab import scenes
from springlab.errors import BadInputError, UnknownNameError
from springlab.exact import analytic
from springlab.scenes.base import Case, Scene
from springlab.scenes.capabilities.fit import OscillatorFit, PolynomialFit

from . import reductions
from .data import Record

#: modal names of an oscillator and their units
MODAL = {"omega_n": "rad/s", "zeta": "-"}
NUISANCE = {"x0": "m", "v0": "m/s", "offset": "(signal)", "delay": "s"}
#: accepted spellings of the modal names
ALIASES = {"damping_ratio": "zeta", "omega": "omega_n"}
#: units of an oscillator's derived quantities
DERIVED_UNITS = {
    "omega_n_rad_s": "rad/s",
    "damping_ratio": "-",
    "natural_frequency_hz": "Hz",
    "damped_frequency_rad_s": "rad/s",
    "damped_period_s": "s",
}
#: a polynomial's coefficient c_n of t^n / n!: its unit, and the name and unit of t^n's coefficient c_n / n!
POWER_UNITS = ("m", "m/s", "m/s^2", "m/s^3")
POWER_TERMS = ("constant_m", "linear_coefficient_m_s", "quadratic_coefficient_m_s2", "cubic_coefficient_m_s3")
#: signal -> how many of a polynomial's lowest coefficients differentiation loses
LOST = {"vel": 1, "acc": 2}


def fittable() -> list[str]:
    """The scenes that declare a fit (`Scene.fit`), in catalogue order."""
    return [name for name, scene in scenes.SCENES.items() if scene.fit is not None]


def model_of(scene: Scene) -> FitModel:
    """The fit machinery for what `scene` declares (BadInputError naming the fittable scenes if nothing)."""
    declared = scene.fit
    if isinstance(declared, OscillatorFit):
        return OscillatorModel(scene, declared)
    if isinstance(declared, PolynomialFit):
        return PolynomialModel(scene, declared)
    raise not_fittable(scene.name)


def not_fittable(name: str) -> BadInputError:
    """The error for a scene `name` that declares no fit (or does not exist): the fittable ones and the others."""
    others = [other for other, scene in scenes.SCENES.items() if scene.fit is None]
    why = f" ({', '.join(others)} {'has' if len(others) == 1 else 'have'} no identification yet)" if others else ""
    return BadInputError(f"scene {name!r} cannot be fitted; valid: {', '.join(fittable())}{why}")


class FitModel:
    """A scene's fit (see the module docstring): the common face of the two kinds.

    Attributes
    ----------
    scene
        The scene (springlab.scenes.base.Scene).
    name
        Its name.
    kind
        'oscillator' or 'polynomial', the kind of its declaration.
    joint
        The measured joint.
    scenarios
        Scenarios a record can be fitted with; the first is the default.
    default_free
        Free names when the user names none (before the signal drops any).
    signals
        Signal kinds it fits.
    """

    kind = ""

    def __init__(self, scene: Scene, joint: str, scenarios: tuple[str, ...], default_free: tuple[str, ...]):
        self.scene, self.name = scene, scene.name
        self.joint, self.scenarios, self.default_free = joint, scenarios, default_free
        self.signals: tuple[str, ...] = ("pos", "vel", "acc")

    # -- names and rules (override) ---------------------------------------------

    def units(self) -> dict[str, str]:
        """Every name a fit may free -> its unit."""
        raise NotImplementedError

    def check_free(
        self, free: list[str], fixed: dict[str, float], params: dict[str, float], forced: bool, signal: str
    ) -> None:
        """Raise BadInputError for an unknown or unidentifiable free set."""
        raise NotImplementedError

    def modal(self, free: list[str]) -> bool:
        """Whether fitted values are read in modal form (omega_n, zeta with the mass given)."""
        return False

    def free_by_default(self, signal: str) -> list[str]:
        """The free names when the user names none, for a record of `signal`."""
        return list(self.default_free)

    def free_of_degree(self, degree: int, signal: str) -> list[str]:
        """The free names of `--degree` (BadInputError where the fit has no degree)."""
        polynomial = [name for name, s in scenes.SCENES.items() if isinstance(s.fit, PolynomialFit)]
        raise BadInputError(
            f"--degree applies to {' and '.join(polynomial)} only"
            f" ({'its polynomial' if len(polynomial) == 1 else 'their polynomials'}); other scenes take --free"
        )

    def step_force(self, scenario: str) -> str | None:
        """The scene parameter holding the constant force [N] `scenario` applies from t = 0, or None (free motion)."""
        return None

    # -- values <-> scene ---------------------------------------------------------

    def equilibrium(self, params: Mapping[str, float]) -> float:
        """Rest position x_eq [m] of the observed coordinate (unforced)."""
        return 0.0

    def values_from_params(self, params: dict[str, float]) -> dict[str, float]:
        """All fit names' values implied by scene parameters."""
        raise NotImplementedError

    def scene_params(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        """Scene parameters for fit values."""
        raise NotImplementedError

    def initial(self, case: Case, x0: float, v0: float) -> tuple[np.ndarray, np.ndarray]:
        """(qpos, qvel) of the candidate `case` with the observed coordinate at x0 [m], v0 [m/s] (the rest of the
        scene at rest)."""
        model = case.model
        qpos, qvel = model.qpos0.copy(), np.zeros(model.nv)
        qpos[model.joint(self.joint).qposadr[0]] = x0
        qvel[model.joint(self.joint).dofadr[0]] = v0
        return qpos, qvel

    def run_parameters(
        self, params: dict[str, float], values: dict[str, float], moving: bool
    ) -> tuple[dict[str, Any], str]:
        """(the identified scene's run parameters, a note on what its run leaves out, or '')."""
        return {k: v for k, v in params.items() if k in self.scene.parameters}, ""

    # -- the closed form, a start, bounds (override) -----------------------------------

    def closed_form(
        self, t: np.ndarray, params: dict[str, float], values: dict[str, float], signal: str, force: float = 0.0
    ) -> np.ndarray:
        """The exact signal at times since the origin t [s]."""
        raise NotImplementedError

    def start(
        self, record: Record, params: dict[str, float], fixed: dict[str, float], free: list[str], force: float = 0.0
    ) -> dict[str, float]:
        """Start values of every fit name, by linear algebra on the data (no optimizer involved)."""
        raise NotImplementedError

    def bounds(self, name: str, start: float, record: Record) -> tuple[float, float]:
        """Box bounds of a free name around its start value (wide: they only keep the model physical)."""
        raise NotImplementedError

    def fastest_rate(self, values: dict[str, float], base: dict[str, float], modal: bool) -> float:
        """Fastest pole |s| [1/s] of the motion at these values (0: none, a polynomial)."""
        return 0.0

    def system(
        self, values: dict[str, float], base: dict[str, float], modal: bool, force: float = 0.0
    ) -> tuple[np.ndarray, float] | None:
        """(A [1/s], x_rest [m]): the motion as z' = A z with z = (x - x_rest, v); None where it has no mode
        (a polynomial, which RK4 integrates exactly)."""
        return None

    def derived(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        """Named results computed from the fitted values (SI)."""
        raise NotImplementedError

    def derived_units(self) -> dict[str, str]:
        """Unit of each name `derived` returns."""
        raise NotImplementedError

    def amplitude(self, fitted: np.ndarray, level: float) -> float:
        """The motion's size in the fitted signal [signal unit], about `level` (the rest level) where it has one."""
        return max(float(np.max(np.abs(fitted[a:b] - level))) for a, b in reductions.blocks(fitted.size))


class OscillatorModel(FitModel):
    """An `OscillatorFit`: one mode m x'' + d x' + k (x - x_eq) = F (see the module docstring).

    Attributes
    ----------
    mass, stiffness, damping
        The scene's parameter names of m, k, d (mass None: derived by the declaration's `mode_mass`, fixed).
    """

    kind = "oscillator"

    def __init__(self, scene: Scene, declared: OscillatorFit):
        super().__init__(scene, declared.joint, declared.scenarios, declared.default_free)
        self.declared = declared
        self.signals = declared.signals
        self.mass, self.stiffness, self.damping = declared.mass, declared.stiffness, declared.damping

    # -- names and rules -------------------------------------------------------

    def physical(self) -> tuple[str, ...]:
        """The scene's parameter names of m, k, d that may be freed."""
        return tuple(n for n in (self.mass, self.stiffness, self.damping) if n)

    def units(self) -> dict[str, str]:
        """Every name a fit may free -> its unit."""
        named = ((self.mass, "kg"), (self.stiffness, "N/m"), (self.damping, "N s/m"))
        units = {name: unit for name, unit in named if name is not None}
        return {**MODAL, **units, **NUISANCE}

    def check_free(
        self, free: list[str], fixed: dict[str, float], params: dict[str, float], forced: bool, signal: str
    ) -> None:
        """Raise BadInputError for an unknown or unidentifiable free set."""
        valid = self.units()
        for name in free:
            if name not in valid:
                if name in params:
                    raise BadInputError(
                        f"{name} cannot be fitted in {self.name}: a ring-down depends on the mode's k/m and d/m"
                        f" only; give it with --set {name}=VALUE and free one of {', '.join(valid)}"
                    )
                raise UnknownNameError(f"fit parameter of {self.name}", name, valid)
        modal = [n for n in free if n in MODAL]
        physical = [n for n in free if n in self.physical()]
        if modal and physical:
            raise BadInputError(
                f"free either the modal form (omega_n, zeta) or the physical one ({', '.join(self.physical())}),"
                f" not both: {', '.join(modal + physical)} describe the same two numbers"
            )
        if len(physical) == 3 and (not forced or "offset" in free):
            why = (
                "a free decay depends on k/m and d/m only"
                if not forced
                else "a free offset hides the static deflection F/k"
            )
            raise BadInputError(
                f"{', '.join(physical)} cannot all be fitted: {why}; fix one with --set (e.g. --set {self.mass}=...)"
            )
        rest = set(self.physical()) - set(physical)
        if len(physical) == 2 and not forced and rest:
            (fixed_name,) = rest
            if params[fixed_name] == 0:
                raise BadInputError(
                    f"{' and '.join(physical)} cannot be told apart with {fixed_name} = 0: a free decay fixes only"
                    f" their ratio; give {fixed_name} a non-zero value with --set"
                )
        if "delay" in free and "v0" in free and not forced:
            raise BadInputError(
                "delay and v0 cannot both be fitted: shifting a free response in time is the same as changing its"
                " initial state; fix v0 (e.g. --set v0=0 for a release from rest)"
            )

    def modal(self, free: list[str]) -> bool:
        """Whether fitted values are read in modal form: omega_n or zeta is free."""
        return bool(set(free) & set(MODAL))

    def step_force(self, scenario: str) -> str | None:
        """The scene parameter holding the constant force [N] `scenario` applies from t = 0, or None (a free decay)."""
        return self.declared.step_forces.get(scenario)

    # -- values <-> scene ------------------------------------------------------

    def mode_mass(self, params: Mapping[str, float]) -> float:
        """The mode's mass m [kg] in these scene parameters."""
        if self.declared.mode_mass is not None:
            return self.declared.mode_mass(params)
        assert self.mass is not None, "OscillatorFit requires a mass parameter or a mode_mass hook"
        return params[self.mass]

    def equilibrium(self, params: Mapping[str, float]) -> float:
        """Rest position x_eq [m] of the observed coordinate (unforced): the declared `rest` parameter, or 0."""
        return params.get(self.declared.rest, 0.0) if self.declared.rest is not None else 0.0

    def values_from_params(self, params: dict[str, float]) -> dict[str, float]:
        """All fit names' values implied by scene parameters (x0, v0 from the scene where it has them)."""
        m, k, d = self.mode_mass(params), params[self.stiffness], params[self.damping]
        values = {name: params[name] for name in self.physical()}
        values["omega_n"] = math.sqrt(k / m)
        values["zeta"] = d / (2.0 * math.sqrt(k * m)) if k > 0 else math.inf
        values.update(x0=params.get("x0", self.equilibrium(params)), v0=params.get("v0", 0.0), offset=0.0, delay=0.0)
        return values

    def scene_params(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        """Scene parameters for fit values: modal (omega_n, zeta with the mass given) or physical."""
        params = dict(base)
        if modal:
            m = self.mode_mass(params)
            params[self.stiffness] = m * values["omega_n"] ** 2
            params[self.damping] = 2.0 * values["zeta"] * m * values["omega_n"]
        else:
            for name in self.physical():
                params[name] = values[name]
        for name in ("x0", "v0"):
            if name in params:
                params[name] = values[name]
        return params

    def initial(self, case: Case, x0: float, v0: float) -> tuple[np.ndarray, np.ndarray]:
        """(qpos, qvel) with the observed coordinate at x0 [m], v0 [m/s]: the declaration's hook, or the joint set."""
        if self.declared.initial_state is not None:
            return self.declared.initial_state(case, x0, v0)
        return super().initial(case, x0, v0)

    def run_parameters(
        self, params: dict[str, float], values: dict[str, float], moving: bool
    ) -> tuple[dict[str, Any], str]:
        """(the identified scene's run parameters, a note on what its run leaves out, or '').

        A scene whose runs start at rest (the declaration's `release` hook) starts at the fitted x0; a fitted
        v0 that is not plausibly 0 (`moving`) is not in its run, and the note says so.
        """
        overrides, note = super().run_parameters(params, values, moving)
        if self.declared.release is not None:
            overrides = self.declared.release(overrides, values["x0"])
            if moving:
                note = f"the {self.name} scene starts at rest; the fitted v0 = {values['v0']:.3g} m/s is not in its run"
        return overrides, note

    # -- the closed form ---------------------------------------------------------

    def closed_form(
        self, t: np.ndarray, params: dict[str, float], values: dict[str, float], signal: str, force: float = 0.0
    ) -> np.ndarray:
        """The exact signal at times since the origin t [s] (analytic.free/step_response), offset and delay applied."""
        m, k, d = self.mode_mass(params), params[self.stiffness], params[self.damping]
        eq = self.equilibrium(params)
        s = np.asarray(t, float) - values["delay"]
        after = np.maximum(s, 0.0)
        x, v = analytic.step_response(after, m, k, d, force, values["x0"] - eq, values["v0"])
        a = (force - k * x - d * v) / m
        # before the release (s < 0) the coordinate is held at x0
        held = s < 0
        x, v, a = np.where(held, values["x0"] - eq, x), np.where(held, 0.0, v), np.where(held, 0.0, a)
        y = {"pos": x + eq, "vel": v, "acc": a}[signal]
        return y + values["offset"]

    # -- a start from the data ---------------------------------------------------

    def start(
        self, record: Record, params: dict[str, float], fixed: dict[str, float], free: list[str], force: float = 0.0
    ) -> dict[str, float]:
        """Start values of every fit name: modal from a linear prediction of the data, then x0, v0, offset by
        linear least squares on the closed form (no optimizer involved)."""
        values = self.values_from_params(params)
        values.update({k: v for k, v in fixed.items() if k in values})
        omega, zeta = modal_estimate(record.model_time, record.values)
        if "omega_n" not in fixed and ("omega_n" in free or set(free) & set(self.physical())):
            values["omega_n"] = omega
        if "zeta" not in fixed and ("zeta" in free or set(free) & set(self.physical())):
            values["zeta"] = zeta
        self._physical_from_modal(values, free, params)
        physical = self.scene_params(values, params, modal=True)
        m, k, d = self.mode_mass(physical), physical[self.stiffness], physical[self.damping]
        eq = self.equilibrium(physical)
        names = [name for name in ("x0", "v0", "offset") if name in free]
        if names:
            known = dict(values, offset=values["offset"] if "offset" not in free else 0.0)
            for name in names:
                if name in ("x0", "v0"):
                    known[name] = eq if name == "x0" else 0.0

            def rows(start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
                """The linear names' columns and the data less the rest, for samples start..stop-1."""
                t = record.time[start:stop] - record.origin
                columns = []
                for name, (x0, v0) in (("x0", (1.0, 0.0)), ("v0", (0.0, 1.0))):
                    if name in free:
                        x, v = analytic.free_response(t, m, k, d, x0, v0)
                        columns.append({"pos": x, "vel": v, "acc": -(k * x + d * v) / m}[record.signal])
                if "offset" in free:
                    columns.append(np.ones_like(t))
                base = self.closed_form(t, physical, dict(known, delay=0.0), record.signal, force)
                return np.column_stack(columns), record.values[start:stop] - base

            # over blocks of samples for a long record (springlab.studies.fit.reductions: the same solution)
            solution = reductions.lstsq(record.time.size, rows)
            for name, value in zip(names, solution):
                values[name] = float(value) + (eq if name == "x0" else 0.0)
        return values

    def _physical_from_modal(self, values: dict[str, float], free: list[str], params: dict[str, float]) -> None:
        """Physical free names from the modal guess and the fixed ones (in place)."""
        omega, zeta = values["omega_n"], values["zeta"]
        free_physical = [n for n in free if n in self.physical()]
        if not free_physical:
            return
        m = values.get(self.mass) if self.mass else None
        k, d = values[self.stiffness], values[self.damping]
        if self.mass in free_physical:
            if self.stiffness not in free_physical:
                m = k / omega**2
            else:  # stiffness and mass free, damping given: d / m = 2 zeta omega
                m = d / (2.0 * max(zeta, 1e-3) * omega)
            values[self.mass] = m
        if self.mass is None:
            m = self.mode_mass(params)
        if self.stiffness in free_physical:
            assert m is not None, "a free stiffness needs the mass: given, freed or the mode's"
            values[self.stiffness] = m * omega**2
        if self.damping in free_physical:
            assert m is not None, "a free damping needs the mass: given, freed or the mode's"
            values[self.damping] = 2.0 * zeta * m * omega

    def bounds(self, name: str, start: float, record: Record) -> tuple[float, float]:
        """Box bounds of a free name around its start value (wide: they only keep the model physical)."""
        scale = float(np.ptp(record.values)) + abs(float(np.mean(record.values))) + 1e-12
        span = float(record.time[-1] - record.origin)
        if name == "omega_n":
            return start / 10.0, start * 10.0
        if name == "zeta":
            return 0.0, max(3.0, 5.0 * start)
        if name == self.damping:
            return 0.0, max(100.0 * start, 1e-6)
        if name in (self.mass, self.stiffness):
            return start / 100.0, start * 100.0
        if name == "delay":
            return -0.1 * span, 0.5 * span
        if name == "v0":
            return start - 1e3 * scale, start + 1e3 * scale
        return start - 1e3 * scale, start + 1e3 * scale

    # -- what the fit reports ------------------------------------------------------

    def fastest_rate(self, values: dict[str, float], base: dict[str, float], modal: bool) -> float:
        """Fastest pole |s| [1/s] of the mode at these values."""
        params = self.scene_params(values, base, modal)
        m = self.mode_mass(params)
        k, d = params[self.stiffness], params[self.damping]
        omega, zeta = math.sqrt(k / m), d / (2 * math.sqrt(k * m))
        return omega * (zeta + math.sqrt(max(zeta * zeta - 1.0, 0.0))) if zeta > 1 else omega

    def system(
        self, values: dict[str, float], base: dict[str, float], modal: bool, force: float = 0.0
    ) -> tuple[np.ndarray, float] | None:
        """(A [1/s], x_rest [m]) of m x'' + d x' + k (x - x_eq) = F: z = (x - x_rest, v), x_rest = x_eq + F / k."""
        params = self.scene_params(values, base, modal)
        m, k, d = self.mode_mass(params), params[self.stiffness], params[self.damping]
        rest = self.equilibrium(params) + (force / k if k > 0 else 0.0)
        return np.array([[0.0, 1.0], [-k / m, -d / m]]), rest

    def derived(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        """omega_n, zeta, the natural frequency, m, k, d and, underdamped, the damped frequency and period (SI)."""
        params = self.scene_params(values, base, modal)
        m, k, d = self.mode_mass(params), params[self.stiffness], params[self.damping]
        out = {
            "omega_n_rad_s": math.sqrt(k / m),
            "damping_ratio": d / (2 * math.sqrt(k * m)),
            "natural_frequency_hz": math.sqrt(k / m) / (2 * math.pi),
            self.stiffness: k,
            self.damping: d,
        }
        if self.mass:
            out[self.mass] = m
        if out["damping_ratio"] < 1:
            omega_d = out["omega_n_rad_s"] * math.sqrt(1 - out["damping_ratio"] ** 2)
            out["damped_frequency_rad_s"] = omega_d
            out["damped_period_s"] = 2 * math.pi / omega_d
        return out

    def derived_units(self) -> dict[str, str]:
        """Unit of each name `derived` returns."""
        named = ((self.mass, "kg"), (self.stiffness, "N/m"), (self.damping, "N s/m"))
        return {**DERIVED_UNITS, **{name: unit for name, unit in named if name is not None}}


class PolynomialModel(FitModel):
    """A `PolynomialFit`: x(t) = sum_n c_n t^n / n! with the scene's coefficients c_n (see the module docstring).

    Attributes
    ----------
    coefficients
        The scene's parameter names of c_0, c_1, ... (x0, v0, ...), ascending power.
    """

    kind = "polynomial"

    def __init__(self, scene: Scene, declared: PolynomialFit):
        super().__init__(scene, declared.joint, declared.scenarios, declared.coefficients)
        self.declared = declared
        self.signals = declared.signals
        self.coefficients = declared.coefficients

    def units(self) -> dict[str, str]:
        """Every name a fit may free -> its unit (c_n [m/s^n])."""
        return dict(zip(self.coefficients, POWER_UNITS))

    def check_free(
        self, free: list[str], fixed: dict[str, float], params: dict[str, float], forced: bool, signal: str
    ) -> None:
        """Raise BadInputError for an unknown name, an offset or delay, or a coefficient the signal lost."""
        valid = self.units()
        for name in free:
            if name in ("offset", "delay"):
                raise BadInputError(
                    f"{name} cannot be fitted with a polynomial: it is indistinguishable from"
                    f" {self.coefficients[0] if name == 'offset' else 'the coefficients'};"
                    f" free {', '.join(self.coefficients)}"
                )
            if name not in valid:
                raise UnknownNameError(f"fit parameter of {self.name}", name, valid)
        lost = self.coefficients[: LOST.get(signal, 0)]
        for name in free:
            if name in lost:
                raise BadInputError(
                    f"{name} cannot be fitted from {signal} data: differentiation loses it; give it with --set"
                    f" {name}=VALUE and free only {', '.join(n for n in valid if n not in lost)}"
                )

    def modal(self, free: list[str]) -> bool:
        """True: a polynomial has no modal form to choose (the flag is unused)."""
        return True

    def free_by_default(self, signal: str) -> list[str]:
        """Every coefficient the signal keeps."""
        return list(self.coefficients)[LOST.get(signal, 0) :]

    def free_of_degree(self, degree: int, signal: str) -> list[str]:
        """The coefficients of a polynomial of `degree` the signal keeps (BadInputError outside 0 to the highest)."""
        highest = len(self.coefficients) - 1
        if not isinstance(degree, int) or not 0 <= degree <= highest:
            choices = [str(n) for n in range(highest + 1)]
            raise BadInputError(
                f"--degree must be {', '.join(choices[:-1])} or {choices[-1]} (the scene drives up to a constant"
                f" {self.coefficients[-1]}), got {degree!r}"
            )
        names = list(self.coefficients)[: degree + 1]
        lost = LOST.get(signal, 0)
        return names[lost:] if len(names) > lost else names

    def values_from_params(self, params: dict[str, float]) -> dict[str, float]:
        """The coefficients' values in the scene parameters, no offset, no delay."""
        return {n: params[n] for n in self.coefficients} | {"offset": 0.0, "delay": 0.0}

    def scene_params(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        """Scene parameters with the fitted coefficients."""
        return dict(base) | {n: values[n] for n in self.coefficients}

    def closed_form(
        self, t: np.ndarray, params: dict[str, float], values: dict[str, float], signal: str, force: float = 0.0
    ) -> np.ndarray:
        """The polynomial (pos), or its first or second derivative (vel, acc), at times t [s]."""
        t = np.asarray(t, float)
        c = [values[n] for n in self.coefficients] + [0.0] * (4 - len(self.coefficients))
        x0, v0, a0, j = c
        return {
            "pos": x0 + v0 * t + a0 * t**2 / 2 + j * t**3 / 6,
            "vel": v0 + a0 * t + j * t**2 / 2,
            "acc": a0 + j * t + 0.0 * t,
        }[signal]

    def start(
        self, record: Record, params: dict[str, float], fixed: dict[str, float], free: list[str], force: float = 0.0
    ) -> dict[str, float]:
        """Linear least squares on the monomials: exact for a polynomial (the MuJoCo fit then confirms it)."""
        values = self.values_from_params(params) | {n: 0.0 for n in self.coefficients}
        values.update({k: v for k, v in fixed.items() if k in values})
        names = [n for n in self.coefficients if n in free]

        def rows(start: int, stop: int) -> tuple[np.ndarray, np.ndarray]:
            """The free coefficients' monomials and the data less the rest, for samples start..stop-1."""
            t = record.time[start:stop] - record.origin
            monomials = (
                {"pos": np.ones_like(t)},
                {"pos": t, "vel": np.ones_like(t)},
                {"pos": t**2 / 2, "vel": t, "acc": np.ones_like(t)},
                {"pos": t**3 / 6, "vel": t**2 / 2, "acc": t},
            )
            basis = dict(zip(self.coefficients, monomials))
            known = self.closed_form(t, params, {**values, **{n: 0.0 for n in names}}, record.signal)
            return np.column_stack([basis[n][record.signal] for n in names]), record.values[start:stop] - known

        if names:  # over blocks of samples for a long record (springlab.studies.fit.reductions: the same solution)
            solution = reductions.lstsq(record.time.size, rows)
            values.update({n: float(v) for n, v in zip(names, solution)})
        return values

    def bounds(self, name: str, start: float, record: Record) -> tuple[float, float]:
        """Box bounds of a coefficient: wide (a polynomial is linear in them)."""
        scale = float(np.max(np.abs(record.values))) + 1.0
        width = 1e3 * scale * (1.0 + float(record.time[-1] - record.origin)) ** 3
        return start - width, start + width

    def derived(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        """The coefficient of each power t^n, c_n / n!, highest power first (SI)."""
        return {
            POWER_TERMS[n]: values[name] / math.factorial(n) if n > 1 else values[name]
            for n, name in reversed(list(enumerate(self.coefficients)))
        }

    def derived_units(self) -> dict[str, str]:
        """Unit of each name `derived` returns."""
        return dict(zip(POWER_TERMS, POWER_UNITS))

    def amplitude(self, fitted: np.ndarray, level: float) -> float:
        """The range of the fitted signal (a polynomial has no rest level)."""
        return float(np.ptp(fitted))


def modal_estimate(t: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(omega_n [rad/s], zeta [-]) of the record's dominant mode by linear prediction, for a start.

    The signal is resampled evenly (np.interp) and y(t + 2h) = a y(t + h) + b y(t) + c
    solved by linear least squares (c absorbs an offset); the roots z of z^2 - a z - b
    give s = ln(z) / h. The lag h is an eighth of the period at the spectrum's peak
    (a tenth of the record when there is no peak: overdamped motion).
    """
    n = max(256, min(t.size, 1 << 15))
    grid = np.linspace(t[0], t[-1], n)
    even = np.interp(grid, t, y)
    step = grid[1] - grid[0]
    spectrum = np.abs(np.fft.rfft((even - even.mean()) * np.hanning(n), 8 * n))
    frequencies = np.fft.rfftfreq(8 * n, step) * 2 * np.pi
    peak = int(np.argmax(spectrum[1:])) + 1
    omega_peak = frequencies[peak]
    span = t[-1] - t[0]
    lag_time = (2 * np.pi / omega_peak) / 8 if omega_peak * span > 2 * 2 * np.pi else span / 10
    lag = max(1, int(round(lag_time / step)))
    h = lag * step
    rows = n - 2 * lag
    if rows < 4:
        return max(omega_peak, 1e-3), 0.05
    matrix = np.column_stack([even[lag : lag + rows], even[:rows], np.ones(rows)])
    (a, b, _), *_ = np.linalg.lstsq(matrix, even[2 * lag : 2 * lag + rows], rcond=None)
    roots = np.roots([1.0, -a, -b]).astype(complex)
    with np.errstate(all="ignore"):
        s = np.log(roots) / h
    if not np.all(np.isfinite(s)) or np.any(s.real > 0):
        return max(omega_peak, 1e-3), 0.05
    if abs(s[0].imag) > 1e-12:
        omega = float(abs(s[0]))
        zeta = float(-s[0].real / omega)
    else:
        omega = float(math.sqrt(abs(s[0].real * s[1].real)))
        zeta = float(-(s[0].real + s[1].real) / (2 * omega))
    if not (math.isfinite(omega) and omega > 0 and math.isfinite(zeta)):
        return max(omega_peak, 1e-3), 0.05
    return omega, max(zeta, 1e-3)
