"""What `springlab fit` can identify in each scene, from which signal, and what it refuses.

Each fittable scene has a `SceneFit`: the names a fit may free (with units),
the default free set, the identifiability rules, how fitted values become the
scene's parameters and initial state, a start from the data by linear algebra
(no optimizer), and the closed form the MuJoCo fit is cross-checked against.

Oscillators (slider, car push_release/damped_release, printer_head settle)
observe one coordinate x of a mode m x'' + d x' + k (x - x_eq) = F:

* slider: x = the spring's stretch, m, k, d = mass, stiffness, damping;
* car: x = the car bottom's height (x_eq = clearance), m, k, d = mass, stiffness, damping;
* printer_head: x = the carriage, ringing with the belt about the resting centre
  of mass (x_eq = 0): m = the belt mode's mass mu = m_c m_m / (m_c + m_m),
  k, d = belt_stiffness, belt_damping; the carriage moves as -(m_m / M) of the
  belt's stretch, so its ring-down is the mode's free response itself.

A free decay depends on k/m and d/m only, so of mass, stiffness and damping at
most two can be fitted, and then only while the third is not zero; omega_n and
zeta are the same information in modal form. The initial state at the record's
start (x0 [m], v0 [m/s]) and a constant sensor offset are nuisance parameters;
a sensor delay (or the moment of a release from rest) is identifiable only
when the initial velocity is known, because shifting a free response in time is
the same as changing its initial state.

kinematics observes x(t) = x0 + v0 t + a0 t^2 / 2 + jerk t^3 / 6 (section 5.2):
the polynomial of degree <= 3 the scene drives; velocity data cannot give x0,
acceleration data neither x0 nor v0.
"""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np

from springlab.errors import BadInputError, UnknownNameError
from springlab.exact import analytic

from .data import Record

#: modal names of an oscillator and their units
MODAL = {"omega_n": "rad/s", "zeta": "-"}
NUISANCE = {"x0": "m", "v0": "m/s", "offset": "(signal)", "delay": "s"}
#: accepted spellings of the modal names
ALIASES = {"damping_ratio": "zeta", "omega": "omega_n"}


@dataclasses.dataclass
class SceneFit:
    """A scene's fit description (see the module docstring). Oscillators use this class directly.

    Attributes
    ----------
    scene
        Scene name.
    joint
        The measured joint.
    scenarios
        Scenarios a record can be fitted with; the first is the default.
    mass, stiffness, damping
        The scene's parameter names of m, k, d (mass None: derived, fixed).
    default_free
        Free names when the user names none.
    signals
        Signal kinds it fits.
    """

    scene: str
    joint: str
    scenarios: tuple[str, ...]
    mass: str | None = "mass"
    stiffness: str = "stiffness"
    damping: str = "damping"
    default_free: tuple[str, ...] = ("omega_n", "zeta", "x0", "v0", "offset")
    signals: tuple[str, ...] = ("pos", "vel", "acc")

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
                        f"{name} cannot be fitted in {self.scene}: a ring-down depends on the mode's k/m and d/m"
                        f" only; give it with --set {name}=VALUE and free one of {', '.join(valid)}"
                    )
                raise UnknownNameError(f"fit parameter of {self.scene}", name, valid)
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

    # -- values <-> scene ------------------------------------------------------

    def mode_mass(self, params: dict[str, float]) -> float:
        """The mode's mass m [kg] in these scene parameters."""
        if self.mass is not None:
            return params[self.mass]
        m_c, m_m = params["carriage_mass"], params["motor_mass"]
        return m_c * m_m / (m_c + m_m)

    def equilibrium(self, params: dict[str, float]) -> float:
        """Rest position x_eq [m] of the observed coordinate (unforced)."""
        return params.get("clearance", 0.0) if self.scene == "car" else 0.0

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

    def initial(
        self, model: mujoco.MjModel, params: dict[str, float], x0: float, v0: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """(qpos, qvel) with the observed coordinate at x0 [m], v0 [m/s] (the rest of the scene at rest)."""
        qpos, qvel = model.qpos0.copy(), np.zeros(model.nv)
        if self.scene == "printer_head":
            # carriage at x0 about the centre of mass at rest at 0: motor at -(m_c / m_m) x0
            ratio = params["carriage_mass"] / params["motor_mass"]
            for joint, q, v in (("carriage", x0, v0), ("motor", -ratio * x0, -ratio * v0)):
                qpos[model.joint(joint).qposadr[0]], qvel[model.joint(joint).dofadr[0]] = q, v
            return qpos, qvel
        qpos[model.joint(self.joint).qposadr[0]] = x0
        qvel[model.joint(self.joint).dofadr[0]] = v0
        return qpos, qvel

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
        t = record.model_time
        columns, names = [], []
        for name, (x0, v0) in (("x0", (1.0, 0.0)), ("v0", (0.0, 1.0))):
            if name in free:
                x, v = analytic.free_response(t, m, k, d, x0, v0)
                columns.append({"pos": x, "vel": v, "acc": -(k * x + d * v) / m}[record.signal])
                names.append(name)
        if "offset" in free:
            columns.append(np.ones_like(t))
            names.append("offset")
        if columns:
            known = dict(values, offset=values["offset"] if "offset" not in free else 0.0)
            for name in names:
                if name in ("x0", "v0"):
                    known[name] = eq if name == "x0" else 0.0
            base = self.closed_form(t, physical, dict(known, delay=0.0), record.signal, force)
            solution = np.linalg.lstsq(np.column_stack(columns), record.values - base, rcond=None)[0]
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
        span = float(record.model_time[-1])
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


@dataclasses.dataclass
class KinematicsFit(SceneFit):
    """The vehicle's polynomial x0 + v0 t + a0 t^2/2 + jerk t^3/6 (scene kinematics)."""

    default_free: tuple[str, ...] = ("x0", "v0", "a0", "jerk")

    def units(self) -> dict[str, str]:
        return {"x0": "m", "v0": "m/s", "a0": "m/s^2", "jerk": "m/s^3"}

    def check_free(
        self, free: list[str], fixed: dict[str, float], params: dict[str, float], forced: bool, signal: str
    ) -> None:
        valid = self.units()
        for name in free:
            if name in ("offset", "delay"):
                raise BadInputError(
                    f"{name} cannot be fitted with a polynomial: it is indistinguishable from"
                    f" {'x0' if name == 'offset' else 'the coefficients'}; free x0, v0, a0, jerk"
                )
            if name not in valid:
                raise UnknownNameError("fit parameter of kinematics", name, valid)
        lost = {"vel": ("x0",), "acc": ("x0", "v0")}.get(signal, ())
        for name in free:
            if name in lost:
                raise BadInputError(
                    f"{name} cannot be fitted from {signal} data: differentiation loses it; give it with --set"
                    f" {name}=VALUE and free only {', '.join(n for n in valid if n not in lost)}"
                )

    def values_from_params(self, params: dict[str, float]) -> dict[str, float]:
        return {n: params[n] for n in ("x0", "v0", "a0", "jerk")} | {"offset": 0.0, "delay": 0.0}

    def scene_params(self, values: dict[str, float], base: dict[str, float], modal: bool) -> dict[str, float]:
        return dict(base) | {n: values[n] for n in ("x0", "v0", "a0", "jerk")}

    def initial(
        self, model: mujoco.MjModel, params: dict[str, float], x0: float, v0: float
    ) -> tuple[np.ndarray, np.ndarray]:
        qpos, qvel = model.qpos0.copy(), np.zeros(model.nv)
        qpos[model.joint(self.joint).qposadr[0]] = x0
        qvel[model.joint(self.joint).dofadr[0]] = v0
        return qpos, qvel

    def closed_form(
        self, t: np.ndarray, params: dict[str, float], values: dict[str, float], signal: str, force: float = 0.0
    ) -> np.ndarray:
        t = np.asarray(t, float)
        x0, v0, a0, j = (values[n] for n in ("x0", "v0", "a0", "jerk"))
        return {
            "pos": x0 + v0 * t + a0 * t**2 / 2 + j * t**3 / 6,
            "vel": v0 + a0 * t + j * t**2 / 2,
            "acc": a0 + j * t + 0.0 * t,
        }[signal]

    def start(
        self, record: Record, params: dict[str, float], fixed: dict[str, float], free: list[str], force: float = 0.0
    ) -> dict[str, float]:
        """Linear least squares on the monomials: exact for a polynomial (the MuJoCo fit then confirms it)."""
        values = self.values_from_params(params) | {n: 0.0 for n in ("x0", "v0", "a0", "jerk")}
        values.update({k: v for k, v in fixed.items() if k in values})
        t = record.model_time
        basis = {
            "x0": {"pos": np.ones_like(t)},
            "v0": {"pos": t, "vel": np.ones_like(t)},
            "a0": {"pos": t**2 / 2, "vel": t, "acc": np.ones_like(t)},
            "jerk": {"pos": t**3 / 6, "vel": t**2 / 2, "acc": t},
        }
        names = [n for n in ("x0", "v0", "a0", "jerk") if n in free]
        known = self.closed_form(t, params, {**values, **{n: 0.0 for n in names}}, record.signal)
        if names:
            matrix = np.column_stack([basis[n][record.signal] for n in names])
            solution = np.linalg.lstsq(matrix, record.values - known, rcond=None)[0]
            values.update({n: float(v) for n, v in zip(names, solution)})
        return values

    def bounds(self, name: str, start: float, record: Record) -> tuple[float, float]:
        scale = float(np.max(np.abs(record.values))) + 1.0
        width = 1e3 * scale * (1.0 + float(record.model_time[-1])) ** 3
        return start - width, start + width


#: scene name -> its fit description
FITS: dict[str, SceneFit] = {
    "slider": SceneFit(
        "slider", "slider", ("free", "underdamped", "undamped", "critical", "overdamped", "exercise", "step")
    ),
    "car": SceneFit(
        "car", "heave", ("damped_release", "push_release"), default_free=("stiffness", "damping", "x0", "v0", "offset")
    ),
    "printer_head": SceneFit(
        "printer_head",
        "carriage",
        ("settle",),
        mass=None,
        stiffness="belt_stiffness",
        damping="belt_damping",
        default_free=("belt_stiffness", "belt_damping", "x0", "v0", "offset"),
    ),
    "kinematics": KinematicsFit("kinematics", "vehicle", ("polynomial_position",), mass=None),
}


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
