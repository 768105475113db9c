"""`springlab frequency MODEL|SCENE`: the frequency response of any model's linearization, and the band an
integrator at a timestep reproduces it in.

1. Exact: the linearization at the operating point (springlab.exact.linearize: A from MuJoCo's
   `mjd_inverseFD`, the input column b and the response row c by centred differences of `mj_forward`) as a
   `scipy.signal.StateSpace`; magnitude and phase over the band (`scipy.signal.freqresp`), resonances
   (local maxima of |H|, the peak refined by `scipy.optimize.minimize_scalar`, the damping ratio from the
   half-power width, zeta = (f2 - f1) / (2 f_peak), the textbook estimate, good to O(zeta^2)) and
   anti-resonances (local minima).
2. Discrete: MuJoCo's own one-step map of the chosen integrator at dt (Phi from `one_step_map`, gamma from
   `step_input_column`: the input held over the step, as MuJoCo applies a control) as a `scipy.signal.dlti`;
   its response (`scipy.signal.dfreqresp`) to a sine sampled at mid-step and held, against the exact one:
   relative magnitude and phase errors, the band from FMIN within tol, and for each of MuJoCo's integrators
   the largest dt whose band covers the whole requested band (bisection in log dt below Nyquist, every
   returned dt checked).

The hold itself costs accuracy: a sine held over each step reaches the model as sinc(omega dt / 2) times
the sine, a relative error (omega dt)^2 / 24 even for an exact integrator. `hold_error` is that floor (the
exact zero-order-hold discretization, `scipy.signal.cont2discrete`, compared the same way), so a user sees
which part of the error is the integrator's.

`frequency(scene_or_model, ...)` returns a `FrequencyResponse` (immutable): `to_dict()` is frequency.json,
`to_pandas()` its rows (frequency.csv).
"""

from __future__ import annotations

import dataclasses
import math
import os
import pathlib
import time as _time
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from springlab import display, scenes, tables
from springlab.errors import BadInputError, UnknownNameError
from springlab.exact.linearize import (
    FD_STEP,
    Linearization,
    OperatingPoint,
    input_column,
    linearize,
    one_step_map,
    operating_point,
    spectral_radius,
    step_input_column,
)
from springlab.runs.run import prepare
from springlab.sim.simulate import INTEGRATORS, integrator_id, quiet_mujoco

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure

#: defaults of the command line and the API
DEFAULT_TOL = 1e-3
DEFAULT_POINTS = 200
#: the resonance search evaluates |H| on at least this many log-spaced points of the band
SEARCH_POINTS = 2000
#: a one-step map whose spectral radius exceeds 1 by more than this is unstable: no steady state to compare
STABLE_RADIUS = 1.0 + 1e-6
#: the smallest timestep the per-integrator search tries [s]
MIN_DT = 1e-7
#: function evaluations per step, for the cost of a setting (rk4: four forward passes)
EVALUATIONS = {"euler": 1, "implicit": 1, "implicitfast": 1, "rk4": 4, "discrete": 1}
#: a zero within this relative distance of a pole cancels it (finite differences leave ~1e-8 of a mode the
#: input does not reach)
CANCEL = 1e-5
_EPS = float(np.finfo(float).eps)
#: response kinds: 'JOINT' (position), 'JOINT:vel', 'JOINT:acc'
RESPONSE_KINDS = ("pos", "vel", "acc")


@dataclasses.dataclass(frozen=True)
class Resonance:
    """A resonance (local maximum of |H|) or an anti-resonance (a lightly damped zero) of the exact response.

    Attributes
    ----------
    frequency_hz
        where |H| peaks (or dips) [Hz].
    magnitude
        |H| there [response unit per input unit].
    damping_ratio
        a resonance's from the half-power width, (f2 - f1) / (2 f) [-] (None: a half-power point outside
        the band or not below the neighbouring valley); an anti-resonance's, its zero's -Re(z) / |z|.
    natural_frequency_hz, pole_damping_ratio
        a resonance's mode: the linearization's oscillatory pole p it peaks near, |p| / 2 pi [Hz] and
        -Re(p) / |p| [-] (exact, where the peak's frequency and half-power width are estimates); None for an
        anti-resonance.
    """

    frequency_hz: float
    magnitude: float
    damping_ratio: float | None = None
    natural_frequency_hz: float | None = None
    pole_damping_ratio: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """{"frequency_hz", "magnitude", "damping_ratio", "natural_frequency_hz", "pole_damping_ratio"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class IntegratorBand:
    """One of MuJoCo's integrators against the requested band.

    Attributes
    ----------
    integrator
        its name.
    max_dt_s
        the largest timestep [s] whose discrete response stays within tol of the exact one over the whole
        band (None: none down to MIN_DT).
    evaluations_per_s
        forward-pass evaluations per simulated second at max_dt_s (EVALUATIONS / dt) [1/s] (None: no dt).
    """

    integrator: str
    max_dt_s: float | None
    evaluations_per_s: float | None

    def to_dict(self) -> dict[str, Any]:
        """{"integrator", "max_dt_s", "evaluations_per_s"}."""
        return dataclasses.asdict(self)


@dataclasses.dataclass(frozen=True)
class Sinestream:
    """The response estimated by simulating MuJoCo (the nonlinear model, the chosen integrator and dt): one held
    sine after another, each started on the exact steady state, settled, then demodulated.

    Attributes
    ----------
    frequencies_hz
        (m,) the sines [Hz], log-spaced over the band and one octave above it.
    estimate
        (m,) complex: the demodulated response (least squares of the window on 1, t, cos, sin: an offset and a
        drift, a free body's, are fitted away).
    discrete
        (m,) the integrator's discrete-time response at the same frequencies (what the estimate must match).
    exact
        (m,) the exact response there.
    accuracy
        (m,) the demodulation's stated relative accuracy: the slowest decaying mode's envelope left after the
        settling time, times the mode basis' condition number, plus round-off over the run's steps.
    amplitude
        the input amplitude [input unit].
    settle_s, estimate_periods
        (m,) the settling time [s] and the whole periods demodulated.
    uncertainty
        (m,) the discrete response's own relative error from its finite differences (maps at steps h and 2 h).
    steps
        total MuJoCo steps of all sines.
    wall_time_s
        how long the simulation took [s].
    """

    frequencies_hz: np.ndarray
    estimate: np.ndarray
    discrete: np.ndarray
    exact: np.ndarray
    accuracy: np.ndarray
    amplitude: float
    settle_s: np.ndarray
    estimate_periods: np.ndarray
    uncertainty: np.ndarray
    steps: int
    wall_time_s: float

    @property
    def error_vs_discrete(self) -> np.ndarray:
        """|H_est / H_d - 1| [-]: within `bound` when MuJoCo's run is the measured one-step map's."""
        return np.abs(self.estimate / self.discrete - 1.0)

    @property
    def bound(self) -> np.ndarray:
        """accuracy + uncertainty [-]: what `error_vs_discrete` must stay within."""
        return self.accuracy + self.uncertainty

    @property
    def agrees(self) -> bool:
        """Whether every sine's estimate is within `bound` of the discrete response."""
        return bool(np.all(self.error_vs_discrete <= self.bound))

    def to_dict(self) -> dict[str, Any]:
        """frequency.json's "sinestream"."""
        return {
            "frequencies_hz": self.frequencies_hz.tolist(),
            "magnitude": np.abs(self.estimate).tolist(),
            "phase_deg": np.degrees(np.angle(self.estimate)).tolist(),
            "error_vs_discrete": self.error_vs_discrete.tolist(),
            "error_vs_exact": np.abs(self.estimate / self.exact - 1.0).tolist(),
            "accuracy": self.accuracy.tolist(),
            "uncertainty": self.uncertainty.tolist(),
            "agrees": self.agrees,
            "amplitude": self.amplitude,
            "settle_s": self.settle_s.tolist(),
            "estimate_periods": self.estimate_periods.tolist(),
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
        }


@dataclasses.dataclass(frozen=True, repr=False)
class FrequencyResponse(display.Shown):
    """The exact and the integrator's frequency response of one input to one response.

    Attributes
    ----------
    source
        what was analysed, e.g. "scene 'car' (scenario 'road_bump')" or a file name.
    input, response
        their names ('JOINT:vel' for a velocity); `units` gives theirs.
    units
        {"input": ..., "response": ...}.
    point
        the operating point's label.
    integrator, dt, tol
        the setting checked [s] and the tolerance [-] on the relative complex error.
    band_hz
        (fmin, fmax) requested [Hz].
    frequencies_hz
        (points,) log-spaced over the band [Hz].
    exact, discrete, hold
        (points,) complex responses: the linearization's H(j omega), the integrator's (input sampled at
        mid-step and held), the exact zero-order-hold discretization's (the floor any integrator shares).
    resonances, anti_resonances
        of the exact response inside the band.
    within_tol_hz
        (fmin, f) the band from fmin over which the integrator stays within tol (f refined between grid
        points); None: not even at fmin.
    covers_band
        whether that reaches fmax.
    integrators
        every integrator's largest dt covering the band.
    description
        the question in words (a scene's declaration; else input -> response).
    wall_time_s
        how long the analysis took [s].
    sinestream
        the simulated verification (None: not asked for).
    answers, answer_lines
        what the response means for the scene's question (`FrequencySpec.interpret`: named values, SI, and
        their verdict lines), e.g. the single-mass car's isolation frequency; empty for a model file.
    """

    source: str
    input: str
    response: str
    units: dict[str, str]
    point: str
    integrator: str
    dt: float
    tol: float
    band_hz: tuple[float, float]
    frequencies_hz: np.ndarray
    exact: np.ndarray
    discrete: np.ndarray
    hold: np.ndarray
    resonances: tuple[Resonance, ...]
    anti_resonances: tuple[Resonance, ...]
    within_tol_hz: tuple[float, float] | None
    covers_band: bool
    integrators: tuple[IntegratorBand, ...]
    description: str
    wall_time_s: float
    sinestream: Sinestream | None = None
    answers: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    answer_lines: tuple[str, ...] = ()

    @property
    def relative_error(self) -> np.ndarray:
        """|H_d / H - 1| per frequency [-]."""
        return np.abs(self.discrete / self.exact - 1.0)

    @property
    def magnitude_error(self) -> np.ndarray:
        """|H_d| / |H| - 1 per frequency [-]."""
        return np.abs(self.discrete) / np.abs(self.exact) - 1.0

    @property
    def phase_error_rad(self) -> np.ndarray:
        """arg(H_d / H) per frequency [rad]."""
        return np.angle(self.discrete / self.exact)

    @property
    def hold_error(self) -> np.ndarray:
        """|H_zoh / H - 1| per frequency [-]: the held input's own share of the error."""
        return np.abs(self.hold / self.exact - 1.0)

    @property
    def cheapest(self) -> IntegratorBand | None:
        """The integrator that covers the band with the fewest evaluations per simulated second."""
        found = [b for b in self.integrators if b.evaluations_per_s is not None]
        return min(found, key=lambda b: b.evaluations_per_s or math.inf) if found else None

    def rows(self) -> dict[str, np.ndarray]:
        """The columns of frequency.csv (SI, phases in degrees, unwrapped)."""
        return {
            "frequency_hz": self.frequencies_hz,
            "exact_magnitude": np.abs(self.exact),
            "exact_phase_deg": np.degrees(np.unwrap(np.angle(self.exact))),
            "discrete_magnitude": np.abs(self.discrete),
            "discrete_phase_deg": np.degrees(np.unwrap(np.angle(self.discrete))),
            "relative_error": self.relative_error,
            "magnitude_error": self.magnitude_error,
            "phase_error_rad": self.phase_error_rad,
            "hold_error": self.hold_error,
        }

    def verdict(self) -> list[str]:
        """A few lines for the terminal: the band the setting reproduces and the cheapest setting for the band."""
        lo, hi = self.band_hz
        setting = f"{self.integrator} at dt = {self.dt:.3g} s"
        if self.within_tol_hz is None:
            lines = [f"{setting} misses the tolerance {self.tol:g} already at {lo:.4g} Hz"]
        else:
            top = self.within_tol_hz[1]
            word = "covers" if self.covers_band else "does not cover"
            lines = [
                f"{setting} reproduces {lo:.4g}-{top:.4g} Hz to {self.tol:g} ({word} the band {lo:.4g}-{hi:.4g} Hz)"
            ]
        for r in self.resonances:
            zeta = "" if r.damping_ratio is None else f", zeta = {r.damping_ratio:.3g}"
            lines.append(f"resonance at {r.frequency_hz:.4g} Hz (|H| = {r.magnitude:.4g}{zeta})")
        for r in self.anti_resonances:
            lines.append(f"anti-resonance at {r.frequency_hz:.4g} Hz (|H| = {r.magnitude:.4g})")
        dts = ", ".join(
            f"{b.integrator} <= {b.max_dt_s:.3g} s" if b.max_dt_s is not None else f"{b.integrator}: none"
            for b in self.integrators
        )
        if dts:  # none when no integrator was searched
            lines.append(f"the band within {self.tol:g} needs dt: {dts}")
        if self.cheapest is not None:
            best = self.cheapest
            lines.append(f"cheapest: {best.integrator} at dt = {best.max_dt_s:.3g} s")
        lines.extend(self.answer_lines)
        if self.sinestream is not None:
            stream = self.sinestream
            worst = float(np.max(stream.error_vs_discrete / stream.bound))
            word = "match" if stream.agrees else "DO NOT match"
            lines.append(
                f"sinestream: {len(stream.frequencies_hz)} sines simulated in MuJoCo ({stream.steps} steps) {word} the"
                f" discrete response within the stated accuracy (worst: {worst:.2g} of it)"
            )
        return lines

    def _shown(self) -> display.Summary:
        """The response as a notebook shows it: whether the setting covers the band, then the resonances."""
        lines = self.verdict()
        facts = [
            display.Fact("setting", f"{self.integrator} at dt = {self.dt:g} s"),
            display.Fact("band", self.band_hz, "Hz"),
            display.Fact("within tol", self.within_tol_hz, "Hz"),
            display.Fact("tol", self.tol),
        ]
        facts += [display.Fact(f"largest dt, {b.integrator}", b.max_dt_s, "s") for b in self.integrators]
        return display.Summary(
            "FrequencyResponse",
            f"{self.source}: {self.input} -> {self.response}",
            "covers the band" if self.covers_band else "does not cover the band",
            self.covers_band,
            lines[0],
            tuple(facts),
            display.table(
                ("kind", "frequency [Hz]", "|H|", "damping ratio [-]"),
                [("resonance", r.frequency_hz, r.magnitude, r.damping_ratio) for r in self.resonances]
                + [("anti-resonance", r.frequency_hz, r.magnitude, r.damping_ratio) for r in self.anti_resonances],
            ),
            note="; ".join(lines[1:]),
        )

    def plot(self) -> Figure:
        """Exact and discrete magnitude and phase, and their relative error against tol (`springlab.plots.frequency.bode_figure`).

        Returns
        -------
        matplotlib.figure.Figure
            a bare Figure (no pyplot): Jupyter shows it inline; `.savefig(path)` writes it.
        """
        return display.plot(self)

    def to_dict(self) -> dict[str, Any]:
        """frequency.json (docs/json.md lists the keys)."""
        rows = {name: column.tolist() for name, column in self.rows().items()}
        return {
            "source": self.source,
            "description": self.description,
            "input": self.input,
            "response": self.response,
            "units": dict(self.units),
            "operating_point": self.point,
            "integrator": self.integrator,
            "dt": self.dt,
            "tol": self.tol,
            "band_hz": list(self.band_hz),
            "frequencies_hz": rows["frequency_hz"],
            "exact": {"magnitude": rows["exact_magnitude"], "phase_deg": rows["exact_phase_deg"]},
            "discrete": {"magnitude": rows["discrete_magnitude"], "phase_deg": rows["discrete_phase_deg"]},
            "error": {
                "relative": rows["relative_error"],
                "magnitude": rows["magnitude_error"],
                "phase_rad": rows["phase_error_rad"],
                "hold": rows["hold_error"],
            },
            "resonances": [r.to_dict() for r in self.resonances],
            "anti_resonances": [r.to_dict() for r in self.anti_resonances],
            "within_tol_hz": None if self.within_tol_hz is None else list(self.within_tol_hz),
            "covers_band": self.covers_band,
            "integrators": [b.to_dict() for b in self.integrators],
            "cheapest": None if self.cheapest is None else self.cheapest.to_dict(),
            "sinestream": None if self.sinestream is None else self.sinestream.to_dict(),
            "answers": dict(self.answers),
            "wall_time_s": self.wall_time_s,
        }

    def to_pandas(self) -> pandas.DataFrame:
        """The rows of frequency.csv as a DataFrame (needs pandas)."""
        return tables.to_pandas({k: np.asarray(v) for k, v in self.rows().items()})


# -- the model, its input and its response ------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class _Source:
    label: str
    model: mujoco.MjModel
    integrator: str
    dt: float
    input: str | None
    response: str | None
    description: str
    parameters: Mapping[str, float] = dataclasses.field(default_factory=dict)
    interpret: Any = None
    input_unit: str = ""


def _spec_for(declared: Any, scenario: str | None) -> Any:
    """The scene's FrequencySpec for `scenario` (None: its default, the first declared), or None."""
    specs = () if declared is None else (declared,) if not isinstance(declared, tuple) else declared
    if scenario is None:
        return specs[0] if specs else None
    return next((spec for spec in specs if spec.scenario == scenario), None)


def declared_scenarios(scene_name: str) -> tuple[str, ...]:
    """The scenarios of a scene that declare a frequency question (`Scene.frequency`), the default first.

    Parameters
    ----------
    scene_name
        a registered scene's name.

    Returns
    -------
    tuple[str, ...]
        the scenario names; () when the scene declares none.
    """
    declared = scenes.get(scene_name).frequency
    specs = () if declared is None else (declared,) if not isinstance(declared, tuple) else declared
    return tuple(spec.scenario for spec in specs)


def _load(scene_or_model: Any, scenario: str | None, parameters: Mapping[str, Any]) -> _Source:
    """The model to analyse: an MjModel, an MJCF path, or a scene (its declared scenario and edit)."""
    if isinstance(scene_or_model, mujoco.MjModel):
        model = scene_or_model
        return _Source("<MjModel>", model, _integrator_name(model), model.opt.timestep, None, None, "")
    if not isinstance(scene_or_model, (str, os.PathLike)):
        raise BadInputError(f"model must be an MjModel, a path to an MJCF file or a scene name, got {scene_or_model!r}")
    text = os.fspath(scene_or_model)
    path = pathlib.Path(text)
    if not path.exists() and text in scenes.SCENES:
        scene = scenes.get(text)
        spec = _spec_for(scene.frequency, scenario)
        scene, chosen, params = prepare(scene, scenario or (spec.scenario if spec else None), dict(parameters))
        model_spec = scene.model_spec()
        scene.edit(model_spec, params, chosen)
        if spec is not None and chosen.name != spec.scenario:
            spec = None  # another scenario: its own model, the user names the input and response
        if spec is not None and spec.edit is not None:
            spec.edit(model_spec, params)
        with quiet_mujoco():
            model = model_spec.compile()
        label = f"scene {text!r} (scenario {chosen.name!r})"
        dt = chosen.dt if chosen.dt is not None else scene.dt
        return _Source(
            label,
            model,
            scene.integrator,
            float(dt),
            spec.input if spec else None,
            spec.response if spec else None,
            spec.description if spec else "",
            dict(params),
            spec.interpret if spec else None,
            spec.input_unit if spec else "",
        )
    if scenario is not None or parameters:
        raise BadInputError("a scenario and parameters go with a scene name, not with a model file")
    if not path.is_file():
        raise BadInputError(f"no such model file or scene {text!r}; scenes: {', '.join(sorted(scenes.SCENES))}")
    try:
        with quiet_mujoco():
            model = mujoco.MjModel.from_xml_path(str(path))
    except Exception as error:  # MuJoCo raises ValueError with its compiler's message
        message = " ".join(str(error).split())
        raise BadInputError(f"cannot load {text!r}: {message}") from None
    return _Source(text, model, _integrator_name(model), model.opt.timestep, None, None, "")


def _integrator_name(model: mujoco.MjModel) -> str:
    return next(name for name, value in INTEGRATORS.items() if value == int(model.opt.integrator))


def _names(model: mujoco.MjModel, kind: str, count: int) -> list[str]:
    getter = model.actuator if kind == "actuator" else model.joint
    return [getter(i).name for i in range(count) if getter(i).name]


def resolve_input(model: mujoco.MjModel, name: str) -> tuple[str, int, str]:
    """(kind, index, unit) of the input called `name`: an actuator's control ('ctrl', its id), else a force
    on a joint's first degree of freedom ('force', its dof address).

    Raises
    ------
    UnknownNameError
        no actuator or joint of that name (the message lists the valid ones).
    """
    actuators = _names(model, "actuator", model.nu)
    if name in actuators:
        return "ctrl", int(model.actuator(name).id), "actuator unit"
    joints = _names(model, "joint", model.njnt)
    if name in joints:
        joint = model.joint(name)
        unit = "N m" if int(joint.type[0]) == int(mujoco.mjtJoint.mjJNT_HINGE) else "N"
        return "force", int(joint.dofadr[0]), unit
    raise UnknownNameError("input (an actuator or a joint)", name, actuators + joints)


def resolve_response(model: mujoco.MjModel, name: str) -> tuple[int, str, str]:
    """(row of the state x = (dq, dv), kind 'pos'|'vel'|'acc', unit) of the response called `name`:
    'JOINT', 'JOINT:vel' or 'JOINT:acc'.

    Raises
    ------
    UnknownNameError
        no joint of that name, or an unknown kind.
    """
    joint_name, _, kind = name.partition(":")
    kind = kind or "pos"
    joints = _names(model, "joint", model.njnt)
    valid = [f"{j}{suffix}" for j in joints for suffix in ("", ":vel", ":acc")]
    if joint_name not in joints or kind not in RESPONSE_KINDS:
        raise UnknownNameError("response (JOINT, JOINT:vel or JOINT:acc)", name, valid)
    joint = model.joint(joint_name)
    dof = int(joint.dofadr[0])
    hinge = int(joint.type[0]) == int(mujoco.mjtJoint.mjJNT_HINGE)
    base = "rad" if hinge else "m"
    unit = {"pos": base, "vel": f"{base}/s", "acc": f"{base}/s^2"}[kind]
    return dof, kind, unit


def _output(linear: Linearization, b: np.ndarray, dof: int, kind: str) -> tuple[np.ndarray, float]:
    """(c, d) of the response: a row of the state, or of dx/dt = A x + b u for an acceleration."""
    nv = linear.M.shape[0]
    n = linear.A.shape[0]
    if kind == "acc":
        return linear.A[nv + dof].copy(), float(b[nv + dof])
    c = np.zeros(n)
    c[dof if kind == "pos" else nv + dof] = 1.0
    return c, 0.0


# -- the responses --------------------------------------------------------------------------------------------


def _system(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, dt: float | None = None):
    """A SISO python-control state-space system (continuous, or discrete with step dt [s])."""
    import control  # a dependency (pyproject: its state-space evaluation); imported here to keep import time low

    args = (a, b[:, None], c[None, :], np.array([[d]]))
    return control.ss(*args) if dt is None else control.ss(*args, dt)


def _evaluate(system, x: np.ndarray) -> np.ndarray:
    """H at complex s (or z) points: python-control's state-space evaluation, c (x I - A)^-1 b + d, solved
    per point (no polynomial of the system is ever formed, so clustered poles near z = 1 at a small dt keep
    their accuracy)."""
    return np.asarray(system.horner(np.atleast_1d(x), warn_infinite=False))[0, 0]


def _continuous(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float) -> Callable[[np.ndarray], np.ndarray]:
    """H(f) of the continuous system, f [Hz] -> complex."""
    system = _system(a, b, c, d)

    def response(f: np.ndarray) -> np.ndarray:
        return _evaluate(system, 2j * np.pi * np.atleast_1d(np.asarray(f, float)))

    return response


def _discrete(phi: np.ndarray, gamma: np.ndarray, c: np.ndarray, d: float, dt: float, f: np.ndarray) -> np.ndarray:
    """H_d of x_{k+1} = Phi x_k + gamma u_k, y_k = c x_k + d u_k at f [Hz], for an input sampled at mid-step
    (k + 1/2) dt and held: H_d(exp(j omega dt)) exp(j omega dt / 2)."""
    omega_dt = 2 * np.pi * np.asarray(f, float) * dt
    return _evaluate(_system(phi, gamma, c, d, dt), np.exp(1j * omega_dt)) * np.exp(0.5j * omega_dt)


def _hold(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, dt: float, f: np.ndarray) -> np.ndarray:
    """The exact zero-order-hold discretization's response (scipy.signal.cont2discrete), sampled as `_discrete`."""
    from scipy import signal  # scipy is a dependency; imported here to keep import time low

    phi, gamma, *_ = signal.cont2discrete((a, b[:, None], c[None, :], np.array([[d]])), dt, method="zoh")
    return _discrete(phi, gamma[:, 0], c, d, dt, f)


def _anti_resonances(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, d: float, band: tuple[float, float]
) -> tuple[Resonance, ...]:
    """The anti-resonances inside the band: complex zeros with damping below 1 / sqrt(2) (so |H| dips), not
    cancelled by a pole (a mode the input does not reach or the response does not see)."""
    system = _system(a, b, c, d)
    zeros = np.asarray(system.zeros(), complex)
    poles = np.asarray(system.poles(), complex)
    found = []
    for z in zeros[zeros.imag > 0]:
        size = abs(z)
        if poles.size and np.min(np.abs(poles - z)) <= CANCEL * size:
            continue
        zeta = -z.real / size
        f = size / (2 * np.pi)
        if zeta < 1 / math.sqrt(2) and band[0] <= f <= band[1]:
            found.append(Resonance(float(f), float(abs(_evaluate(system, np.array([1j * size]))[0])), float(zeta)))
    return tuple(sorted(found, key=lambda r: r.frequency_hz))


def _resonances(
    response: Callable[[np.ndarray], np.ndarray], band: tuple[float, float], points: int, poles: np.ndarray
) -> tuple[Resonance, ...]:
    """The resonances inside the band: local maxima of |H| on a log grid, refined, with the half-power width.

    A maximum counts only near an oscillatory pole p (| 2 pi f - |p| | <= 2 |Re p| plus two grid steps): far
    above the modes |H| falls by orders of magnitude and round-off makes local maxima of no physics."""
    from scipy.optimize import brentq, minimize_scalar

    grid = np.geomspace(band[0], band[1], max(points, SEARCH_POINTS))
    mag = np.abs(response(grid))

    def size(f: float) -> float:
        return float(np.abs(response(np.array([f])))[0])

    peaks = []
    for i in range(1, len(grid) - 1):
        if not (mag[i] > mag[i - 1] and mag[i] >= mag[i + 1]):
            continue
        found = minimize_scalar(
            lambda f: -size(f), bounds=(grid[i - 1], grid[i + 1]), method="bounded", options={"xatol": 1e-12 * grid[i]}
        )
        f0, m0 = float(found.x), size(float(found.x))
        step = 2.0 * (grid[i + 1] / grid[i] - 1.0) * 2 * math.pi * f0
        near = [p for p in poles if p.imag > 0 and abs(2 * math.pi * f0 - abs(p)) <= 2 * abs(p.real) + step]
        if not near:
            continue
        pole = min(near, key=lambda p: abs(2 * math.pi * f0 - abs(p)))
        half = m0 / math.sqrt(2.0)
        below = mag < half
        left = np.nonzero(below[:i])[0]
        right = np.nonzero(below[i + 1 :])[0]
        zeta = None
        if left.size and right.size:
            lo_i, hi_i = int(left[-1]), i + 1 + int(right[0])
            f1 = brentq(lambda f, h=half: size(f) - h, grid[lo_i], f0)
            f2 = brentq(lambda f, h=half: size(f) - h, f0, grid[hi_i])
            zeta = (f2 - f1) / (2.0 * f0)
        peaks.append(Resonance(f0, m0, zeta, float(abs(pole) / (2 * math.pi)), float(-pole.real / abs(pole))))
    return tuple(peaks)


class _Discretizer:
    """MuJoCo's one-step map of an integrator at dt, with the input column, as a frequency response."""

    def __init__(self, model: mujoco.MjModel, point: OperatingPoint, kind: str, index: int, c: np.ndarray, d: float):
        self.model, self.point, self.kind, self.index, self.c, self.d = model, point, kind, index, c, d

    def response(self, integrator: str, dt: float, f: np.ndarray, step: float = FD_STEP) -> np.ndarray | None:
        """H_d at f [Hz], or None where the one-step map is unstable (no steady state); `step`: the maps'
        finite-difference step."""
        phi = one_step_map(self.model, integrator, dt, self.point, step=step)
        if spectral_radius(phi) > STABLE_RADIUS:
            return None
        gamma = step_input_column(self.model, integrator, self.kind, self.index, dt, self.point, step=step)
        return _discrete(phi, gamma, self.c, self.d, dt, f)


def _error(discrete: np.ndarray | None, exact: np.ndarray) -> np.ndarray:
    if discrete is None:
        return np.full(exact.shape, np.inf)
    return np.abs(discrete / exact - 1.0)


def _within(
    discretizer: _Discretizer, integrator: str, dt: float, exact_of, grid: np.ndarray, errors: np.ndarray, tol: float
) -> tuple[float, float] | None:
    """The band (fmin, f) within tol, f refined by bisection in log f between the last good and first bad point."""
    bad = np.nonzero(~(errors <= tol))[0]
    if bad.size == 0:
        return (float(grid[0]), float(grid[-1]))
    first = int(bad[0])
    if first == 0:
        return None
    lo, hi = float(grid[first - 1]), float(grid[first])
    for _ in range(30):
        mid = math.sqrt(lo * hi)
        probe = np.array([mid])
        err = _error(discretizer.response(integrator, dt, probe), exact_of(probe))[0]
        lo, hi = (mid, hi) if err <= tol else (lo, mid)
        if hi / lo - 1.0 < 1e-6:
            break
    return (float(grid[0]), lo)


def _max_dt(
    discretizer: _Discretizer, integrator: str, grid: np.ndarray, exact: np.ndarray, tol: float
) -> float | None:
    """The largest dt [s] below Nyquist of the band's top whose response is within tol over the grid."""

    def ok(dt: float) -> bool:
        return bool(np.all(_error(discretizer.response(integrator, dt, grid), exact) <= tol))

    top = 0.5 / grid[-1] * (1.0 - 1e-9)  # Nyquist of fmax
    if ok(top):
        return top
    hi = top
    lo = hi / 2.0
    while not ok(lo):
        hi, lo = lo, lo / 2.0
        if lo < MIN_DT:
            return None
    for _ in range(12):  # log bisection to 2^(1/4096): dt good to ~0.02 %
        mid = math.sqrt(lo * hi)
        lo, hi = (mid, hi) if ok(mid) else (lo, mid)
    return lo


# -- the study -----------------------------------------------------------------------------------------------


def parse_band(text: str) -> tuple[float, float]:
    """'FMIN:FMAX' [Hz] -> (fmin, fmax).

    Raises
    ------
    BadInputError
        not two numbers, an empty band, or fmin >= fmax or fmin <= 0.
    """
    parts = str(text).split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        fmin, fmax = float(parts[0]), float(parts[1])
    except ValueError:
        raise BadInputError(f"--band must be FMIN:FMAX in Hz (e.g. 0.1:100), got {text!r}") from None
    return _check_band((fmin, fmax))


def _check_band(band: Any) -> tuple[float, float]:
    try:
        fmin, fmax = (float(v) for v in band)
    except (TypeError, ValueError):
        raise BadInputError(f"band must be (fmin, fmax) in Hz, got {band!r}") from None
    if not (math.isfinite(fmin) and math.isfinite(fmax) and fmin > 0):
        raise BadInputError(f"band must be finite with fmin > 0 Hz (a log-spaced grid), got {fmin:g}:{fmax:g}")
    if fmin == fmax:
        raise BadInputError(f"band is empty ({fmin:g}:{fmax:g} Hz); give FMIN:FMAX with fmin < fmax")
    if fmin > fmax:
        raise BadInputError(f"band is inverted: fmin must be below fmax, got {fmin:g}:{fmax:g} Hz")
    return fmin, fmax


def _default_band(linear: Linearization, dt: float) -> tuple[float, float]:
    """A decade below the slowest mode to three times the fastest, capped at half the Nyquist frequency of dt."""
    moving = [m.frequency_hz for m in linear.modes if m.kind != "rigid" and m.frequency_hz > 0]
    slow, fast = (min(moving), max(moving)) if moving else (1.0, 1.0)
    fmax = min(3.0 * fast, 0.25 / dt)
    fmin = min(slow / 10.0, fmax / 100.0)
    return fmin, fmax


def _check_number(name: str, value: Any, low: float = 0.0, high: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (low < value < high):
        bound = f"in ({low:g}, {high:g})" if math.isfinite(high) else f"> {low:g}"
        raise BadInputError(f"{name} must be a finite number {bound}, got {value!r}")
    return float(value)


def frequency(
    scene_or_model: Any,
    scenario: str | None = None,
    *,
    input: str | None = None,  # noqa: A002 - the issue's and the command line's name
    response: str | None = None,
    band: tuple[float, float] | str | None = None,
    points: int = DEFAULT_POINTS,
    integrator: str | None = None,
    dt: float | None = None,
    tol: float = DEFAULT_TOL,
    integrators: tuple[str, ...] | None = None,
    parameters: Mapping[str, Any] | None = None,
    sines: int = 0,
    executor: Any = None,
) -> FrequencyResponse:
    """The frequency response of a model's linearization, and how well an integrator at dt reproduces it.

    Parameters
    ----------
    scene_or_model
        a scene name (its declared scenario, input and response), a path to an MJCF file, or an MjModel.
    scenario
        a scene's scenario (None: the one its `frequency` capability declares, else its default).
    input
        an actuator (its control) or a joint (a force on it) (None: the scene's default).
    response
        'JOINT' (position [m or rad]), 'JOINT:vel' or 'JOINT:acc' (None: the scene's default).
    band
        (fmin, fmax) or 'FMIN:FMAX' [Hz] (None: a decade below the slowest mode to three times the fastest,
        at most a quarter of 1 / dt).
    points
        log-spaced frequencies over the band (>= 2).
    integrator
        the integrator checked (None: the scene's or the model's own).
    dt
        its timestep [s] (None: the scene's or the model's own); the band must stay below 1 / (2 dt).
    tol
        tolerance on the relative complex error |H_d / H - 1| [-], in (0, 1).
    integrators
        those whose largest dt covering the band is searched (None: MuJoCo's five; (): none).
    parameters
        a scene's parameter overrides [SI] (as `springlab.run`'s keywords).
    sines
        verify by simulation: this many sines log-spaced over the band and an octave above it (0: none).
    executor
        where the sines run (a `springlab.studies.executor.Executor`; None: locally).

    Returns
    -------
    FrequencyResponse
        the exact and discrete responses, resonances, the band within tol and every integrator's largest dt.

    Raises
    ------
    BadInputError
        unknown names, an empty or inverted band, a band above Nyquist of dt, a bad number.
    """
    started = _time.perf_counter()
    source = _load(scene_or_model, scenario, parameters or {})
    model = source.model
    integrator = source.integrator if integrator is None else integrator
    integrator_id(integrator)
    dt = source.dt if dt is None else _check_number("dt", dt)
    tol = _check_number("tol", tol, 0.0, 1.0)
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 2:
        raise BadInputError(f"points must be an integer >= 2, got {points!r}")
    if isinstance(sines, bool) or not isinstance(sines, (int, np.integer)) or sines < 0 or sines == 1:
        raise BadInputError(f"sines must be 0 (none) or an integer >= 2, got {sines!r}")
    swept = tuple(INTEGRATORS) if integrators is None else tuple(integrators)
    for name in swept:
        integrator_id(name)
    input_name = input if input is not None else source.input
    response_name = response if response is not None else source.response
    if input_name is None or response_name is None:
        raise BadInputError("name the input (--input ACTUATOR|JOINT) and the response (--response JOINT[:vel|:acc])")
    kind, index, input_unit = resolve_input(model, input_name)
    if input_name == source.input and source.input_unit:
        input_unit = source.input_unit  # the scene knows what its actuator's control is
    dof, out_kind, response_unit = resolve_response(model, response_name)
    if band is not None:
        band = parse_band(band) if isinstance(band, str) else _check_band(band)
    point = operating_point(model)
    linear = linearize(model, point)
    band = _default_band(linear, dt) if band is None else band
    nyquist = 0.5 / dt
    if band[1] >= nyquist:
        raise BadInputError(
            f"band top {band[1]:g} Hz is at or above the Nyquist frequency 1 / (2 dt) = {nyquist:g} Hz of"
            f" dt = {dt:g} s; lower fmax or dt"
        )
    b = input_column(model, kind, index, point)
    c, d = _output(linear, b, dof, out_kind)
    exact_of = _continuous(linear.A, b, c, d)
    grid = np.geomspace(band[0], band[1], int(points))
    exact = exact_of(grid)
    discretizer = _Discretizer(model, point, kind, index, c, d)
    discrete = discretizer.response(integrator, dt, grid)
    if discrete is None:
        discrete = np.full(grid.shape, np.nan + 0j)
    errors = _error(None if np.isnan(discrete).any() else discrete, exact)
    within = _within(discretizer, integrator, dt, exact_of, grid, errors, tol)
    hold = _hold(linear.A, b, c, d, dt, grid)
    resonances = _resonances(exact_of, band, int(points), np.asarray(linear.eigenvalues, complex))
    anti = _anti_resonances(linear.A, b, c, d, band)
    bands = []
    for name in swept:
        top = _max_dt(discretizer, name, grid, exact, tol)
        bands.append(IntegratorBand(name, top, None if top is None else EVALUATIONS[name] / top))
    stream = None
    if sines:
        top = min(2.0 * band[1], 0.45 / dt)  # an octave above the band, below Nyquist
        sine_grid = np.geomspace(band[0], top, int(sines))
        sine_discrete = discretizer.response(integrator, dt, sine_grid)
        coarse = discretizer.response(integrator, dt, sine_grid, step=2 * FD_STEP)
        if sine_discrete is None or coarse is None:
            raise BadInputError(f"{integrator} at dt = {dt:g} s is unstable on this model: no steady state to estimate")
        stream = sinestream(
            model,
            point,
            linear,
            b,
            c,
            kind,
            index,
            dof,
            out_kind,
            integrator,
            dt,
            sine_grid,
            sine_discrete,
            exact_of,
            np.abs(coarse / sine_discrete - 1.0),
            executor,
        )
    for array in (grid, exact, discrete, hold):
        array.setflags(write=False)
    answers: dict[str, Any] = {}
    answer_lines: tuple[str, ...] = ()
    if source.interpret is not None and (input_name, response_name) == (source.input, source.response):
        # the scene's own question, asked of its declared input and response only
        answers, answer_lines = source.interpret(
            model, source.parameters, exact_of, tuple(r.to_dict() for r in resonances), band
        )
    return FrequencyResponse(
        source=source.label,
        input=input_name,
        response=response_name,
        units={"input": input_unit, "response": response_unit},
        point=point.label,
        integrator=integrator,
        dt=float(dt),
        tol=tol,
        band_hz=(float(band[0]), float(band[1])),
        frequencies_hz=grid,
        exact=exact,
        discrete=discrete,
        hold=hold,
        resonances=resonances,
        anti_resonances=anti,
        within_tol_hz=within,
        covers_band=within is not None and within[1] >= band[1],
        integrators=tuple(bands),
        description=source.description
        if (input_name, response_name) == (source.input, source.response) and source.description
        else f"{input_name} to {response_name}",
        wall_time_s=_time.perf_counter() - started,
        sinestream=stream,
        answers=answers,
        answer_lines=tuple(answer_lines),
    )


# -- the sinestream: the response estimated by simulating MuJoCo --------------------------------------------------

#: the demodulation's target relative accuracy: the settling time lets the slowest mode's transient decay to it
SINESTREAM_ACCURACY = 1e-7
#: whole periods demodulated per sine (at least), and samples in the window (at least)
ESTIMATE_PERIODS = 4
ESTIMATE_SAMPLES = 256
#: a sine's run is capped at this many steps (its stated accuracy then says what the shorter settling gives)
MAX_SINE_STEPS = 200_000
#: sines per executor chunk (one batched MuJoCo call each)
SINES_PER_CHUNK = 8


def _sine_chunk(payload: dict[str, Any], nthread: int = 0) -> list[np.ndarray]:
    """Run one chunk of sines (batched) and return each run's response samples (a module-level function: it
    runs on dask workers too)."""
    from springlab.sim.batch import Job, run_batched
    from springlab.sim.simulate import Setup

    model = payload["model"]
    jobs = [
        Job(model, payload["integrator"], payload["dt"], int(len(control)), Setup(qpos, qvel, act, control))
        for qpos, qvel, act, control in payload["runs"]
    ]
    out = []
    for outcome in run_batched(jobs, nthread=nthread):
        if isinstance(outcome, Exception):
            raise outcome
        column = outcome.qpos[:, payload["qposadr"]] if payload["kind"] == "pos" else outcome.qvel[:, payload["dof"]]
        out.append(np.asarray(column, float) - payload["offset"])
    return out


def _demodulate(y: np.ndarray, t: np.ndarray, omega: float) -> complex:
    """Y of y(t) = a + b t + Re(Y exp(j omega t)) by least squares (numpy.linalg.lstsq)."""
    t0 = t - t[0]
    basis = np.column_stack([np.ones_like(t), t0, np.cos(omega * t), np.sin(omega * t)])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return complex(coef[2], -coef[3])


def sinestream(
    model: mujoco.MjModel,
    point: OperatingPoint,
    linear: Linearization,
    b: np.ndarray,
    c: np.ndarray,
    kind: str,
    index: int,
    dof: int,
    out_kind: str,
    integrator: str,
    dt: float,
    frequencies_hz: np.ndarray,
    discrete: np.ndarray,
    exact_of: Callable[[np.ndarray], np.ndarray],
    uncertainty: np.ndarray,
    executor: Any = None,
) -> Sinestream:
    """Simulate MuJoCo at each frequency and demodulate (`Sinestream`; the module docstring says how).

    Each sine u_k = U sin(omega (k + 1/2) dt), held over step k, starts on the exact linearization's steady
    state (so only the small discrete-minus-exact difference is left to decay), runs `settle` (the slowest
    non-rigid mode's envelope exp(-sigma t) times the mode basis' condition number down to
    SINESTREAM_ACCURACY), then ESTIMATE_PERIODS whole periods (at least ESTIMATE_SAMPLES samples) are
    demodulated by least squares on (1, t, cos, sin). `uncertainty` (m,) is the discrete response's own
    relative finite-difference error (its maps at the steps h and 2 h compared).

    Raises
    ------
    BadInputError
        the input is not an actuator, or the response is an acceleration (the run records positions and
        velocities).
    """
    from springlab.studies.executor import chunked, resolve

    if kind != "ctrl":
        raise BadInputError("the sinestream drives an actuator's control; name an actuator as the input")
    if out_kind == "acc":
        raise BadInputError("the sinestream measures a position or a velocity response, not an acceleration")
    started = _time.perf_counter()
    nv = model.nv
    limited = (
        bool(model.actuator_ctrllimited[index])
        and model.actuator_ctrlrange[index, 1] > model.actuator_ctrlrange[index, 0]
    )
    low, high = model.actuator_ctrlrange[index]
    base = float(point.ctrl[index])
    amplitude = min(1.0, 0.5 * min(high - base, base - low)) if limited else 1.0
    if amplitude <= 0:
        raise BadInputError("the operating point's control sits on its limit: no room for a sine")
    moving = [-lam.real for lam in linear.eigenvalues if abs(lam) > linear.growth_tolerance and lam.real < 0]
    sigma = min(moving) if moving else math.inf
    _, vectors = np.linalg.eig(linear.A)
    condition = float(np.linalg.cond(vectors)) if vectors.size else 1.0
    exact = exact_of(frequencies_hz)
    runs, meta = [], []
    for f in frequencies_hz:
        omega = 2 * math.pi * float(f)
        period = 1.0 / float(f)
        settle = math.log(condition / SINESTREAM_ACCURACY) / sigma if math.isfinite(sigma) else 0.0
        periods = max(ESTIMATE_PERIODS, math.ceil(ESTIMATE_SAMPLES * dt / period))
        estimate_steps = int(round(periods * period / dt))
        settle_steps = min(int(math.ceil(settle / dt)), max(MAX_SINE_STEPS - estimate_steps, 0))
        steps = settle_steps + estimate_steps
        # the exact steady state at t = 0 of the input U sin(omega t) = Re(-j U exp(j omega t))
        state = np.linalg.solve(1j * omega * np.eye(linear.A.shape[0]) - linear.A, b * (-1j * amplitude))
        start = state.real
        qpos = point.qpos.copy()
        mujoco.mj_integratePos(model, qpos, start[:nv], 1.0)
        qvel = point.qvel + start[nv : 2 * nv]
        act = point.act + start[2 * nv :]
        control = np.tile(point.ctrl, (steps, 1))
        control[:, index] = base + amplitude * np.sin(omega * (np.arange(steps) + 0.5) * dt)
        runs.append((qpos, qvel, act, control))
        left = condition * math.exp(-sigma * settle_steps * dt) if math.isfinite(sigma) else 0.0
        rounding = 1e3 * _EPS * math.sqrt(steps)
        meta.append((omega, settle_steps, estimate_steps, periods, min(left, 1.0) + rounding))
    joint_qposadr = int(model.jnt_qposadr[int(model.dof_jntid[dof])])
    offset = float(point.qpos[joint_qposadr]) if out_kind == "pos" else float(point.qvel[dof])
    common = {
        "model": model,
        "integrator": integrator,
        "dt": dt,
        "kind": out_kind,
        "qposadr": joint_qposadr,
        "dof": dof,
        "offset": offset,
    }
    chunks = chunked(len(runs), SINES_PER_CHUNK)
    payloads = [{**common, "runs": [runs[i] for i in chunk]} for chunk in chunks]
    results = [y for part in resolve(executor).map(_sine_chunk, payloads, description="sines") for y in part]
    estimates = []
    for y, (omega, _, estimate_steps, _, _) in zip(results, meta):
        window = slice(len(y) - estimate_steps - 1, len(y))
        t = np.arange(len(y)) * dt
        estimates.append(_demodulate(y[window], t[window], omega) / (-1j * amplitude))
    arrays = [
        np.asarray(frequencies_hz, float),
        np.array(estimates),
        np.asarray(discrete),
        np.asarray(exact),
        np.array([m[4] for m in meta]),
        np.array([m[1] * dt for m in meta]),
        np.array([m[3] for m in meta]),
        np.asarray(uncertainty, float),
    ]
    for array in arrays:
        array.setflags(write=False)
    return Sinestream(
        frequencies_hz=arrays[0],
        estimate=arrays[1],
        discrete=arrays[2],
        exact=arrays[3],
        accuracy=arrays[4],
        amplitude=float(amplitude),
        settle_s=arrays[5],
        estimate_periods=arrays[6],
        uncertainty=arrays[7],
        steps=int(sum(len(r[3]) for r in runs)),
        wall_time_s=_time.perf_counter() - started,
    )
