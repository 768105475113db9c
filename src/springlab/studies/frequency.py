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
from springlab.exact.harmonic_balance import Duffing, cubic_oscillator
from springlab.exact.linearize import (
    FD_STEP,
    Linearization,
    OperatingPoint,
    input_column,
    linearize,
    one_step_map,
    operating_point,
    sensor_rows,
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
#: sinestream.csv's columns (FrequencyResponse.sweep_rows)
SINESTREAM_COLUMNS = (
    "amplitude",
    "sweep",
    "frequency_hz",
    "magnitude",
    "phase_deg",
    "response_amplitude",
    "harmonic_balance_amplitude",
    "bound",
)
#: sweep frequencies when `sweep` is given without `sines`
DEFAULT_SWEEP_POINTS = 40


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
    sinestreams: tuple[Sinestream, ...] = ()
    sweeps: tuple[SweepBranch, ...] = ()
    duffing: Duffing | None = None

    answers: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    answer_lines: tuple[str, ...] = ()

    @property
    def amplitude_spread(self) -> np.ndarray | None:
        """(m,) max over the sinestreams' amplitudes of |H_A / H_A0 - 1| per sine [-], A0 the first amplitude
        (None: fewer than two amplitudes): 0 up to the demodulation's accuracy for a linear model."""
        if len(self.sinestreams) < 2:
            return None
        first = self.sinestreams[0].estimate
        return np.max([np.abs(s.estimate / first - 1.0) for s in self.sinestreams[1:]], axis=0)

    @property
    def sweeps_agree(self) -> bool:
        """Every sweep point within its harmonic-balance bound (True without sweeps or a prediction)."""
        return all(branch.agrees for branch in self.sweeps)

    def sweep_rows(self) -> dict[str, np.ndarray]:
        """The columns of sinestream.csv, one row per simulated sine: `amplitude` [input unit], `sweep`
        (0: the sinestream, 1: a sweep up, -1: down), `frequency_hz`, `magnitude`, `phase_deg`,
        `response_amplitude` [response unit], `harmonic_balance_amplitude` and `bound` (nan: none)."""
        parts = []
        for stream in self.sinestreams:
            m = len(stream.frequencies_hz)
            nan = np.full(m, np.nan)
            parts.append((stream.amplitude, 0.0, stream.frequencies_hz, stream.estimate, nan, nan))
        for branch in self.sweeps:
            m = len(branch.frequencies_hz)
            nan = np.full(m, np.nan)
            sign = 1.0 if branch.direction == "up" else -1.0
            predicted = nan if branch.predicted is None else branch.predicted
            bound = nan if branch.bound is None else branch.bound
            parts.append((branch.amplitude, sign, branch.frequencies_hz, branch.estimate, predicted, bound))
        columns: dict[str, list[np.ndarray]] = {k: [] for k in SINESTREAM_COLUMNS}
        for amplitude, sign, f, estimate, predicted, bound in parts:
            columns["amplitude"].append(np.full(len(f), amplitude))
            columns["sweep"].append(np.full(len(f), sign))
            columns["frequency_hz"].append(np.asarray(f, float))
            columns["magnitude"].append(np.abs(estimate))
            columns["phase_deg"].append(np.degrees(np.angle(estimate)))
            columns["response_amplitude"].append(np.abs(estimate) * amplitude)
            columns["harmonic_balance_amplitude"].append(np.asarray(predicted, float))
            columns["bound"].append(np.asarray(bound, float))
        return {k: np.concatenate(v) if v else np.zeros(0) for k, v in columns.items()}

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
        if len(self.sinestreams) > 1:
            lines.extend(self._amplitude_lines())
        elif self.sinestream is not None:
            stream = self.sinestream
            worst = float(np.max(stream.error_vs_discrete / stream.bound))
            word = "match" if stream.agrees else "DO NOT match"
            lines.append(
                f"sinestream: {len(stream.frequencies_hz)} sines simulated in MuJoCo ({stream.steps} steps) {word} the"
                f" discrete response within the stated accuracy (worst: {worst:.2g} of it)"
            )
        lines.extend(self._sweep_lines())
        return lines

    def _amplitude_lines(self) -> list[str]:
        unit = self.units["input"]
        amplitudes = ", ".join(f"{s.amplitude:g}" for s in self.sinestreams)
        spread = self.amplitude_spread
        assert spread is not None
        worst = int(np.argmax(spread))
        accuracy = float(max(np.max(s.accuracy) for s in self.sinestreams))
        f = self.sinestreams[0].frequencies_hz[worst]
        if float(spread[worst]) <= 2 * accuracy:
            verdict = f"coincide to {spread[worst]:.2g} (within twice the demodulation's accuracy {accuracy:.2g})"
        else:
            verdict = f"part by up to {spread[worst]:.3g} (at {f:.4g} Hz): the response depends on the amplitude"
        lines = [f"sinestream at amplitudes {amplitudes} {unit}: the estimates {verdict}"]
        for stream in self.sinestreams:
            word = "matches" if stream.agrees else "departs from"
            departs = float(np.max(stream.error_vs_discrete))
            lines.append(
                f"  at {stream.amplitude:g} {unit}: {word} the linear discrete response (largest |H/H_d - 1| {departs:.2g})"
            )
        return lines

    def _sweep_lines(self) -> list[str]:
        unit = self.units["input"]
        lines = []
        for branch in self.sweeps:
            m = len(branch.frequencies_hz)
            head = (
                f"sweep {branch.direction} at {branch.amplitude:g} {unit} ({m} frequencies, each from the last's state)"
            )
            if branch.jump_hz is not None:
                lo, hi = branch.jump_hz
                head += f": jumps between {lo:.4g} and {hi:.4g} Hz"
            else:
                head += ": no jump"
            if branch.fold_hz is not None:
                f, low, high = branch.fold_hz
                head += f"; harmonic balance predicts the jump at {f:.4g} Hz ({low:.4g}-{high:.4g})"
            elif branch.predicted is not None:
                head += "; harmonic balance's branch does not end in the band"
            lines.append(head)
        if self.duffing is not None and self.sweeps:
            d = self.duffing
            inside = [b.within_bound for b in self.sweeps if b.within_bound is not None]
            count = sum(int(np.sum(x)) for x in inside)
            total = sum(len(x) for x in inside)
            worst = max(
                float(np.max(np.abs(b.response_amplitude - b.predicted) / b.bound))
                for b in self.sweeps
                if b.predicted is not None and b.bound is not None
            )
            lines.append(
                f"harmonic balance (m = {d.m:.4g}, c = {d.c:.4g}, k = {d.k:.4g}, k3 = {d.k3:.4g}, read from the model):"
                f" first-harmonic amplitude within its derived bound at {count} of {total} points (worst {worst:.2g}"
                " of it)"
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
            "sinestreams": [s.to_dict() for s in self.sinestreams],
            "sweeps": [b.to_dict() for b in self.sweeps],
            "harmonic_balance": None if self.duffing is None else self.duffing.to_dict(),
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
    getter = {"actuator": model.actuator, "joint": model.joint, "sensor": model.sensor}[kind]
    return [getter(i).name for i in range(count) if getter(i).name]


def _actuator_unit(model: mujoco.MjModel, actuator: int) -> str:
    """'N' or 'N m' for a motor (fixed gain 1, no bias) with gear 1 on a slide or hinge joint: its control is the
    joint's force; else 'actuator unit'."""
    motor = (
        int(model.actuator_trntype[actuator]) == int(mujoco.mjtTrn.mjTRN_JOINT)
        and int(model.actuator_gaintype[actuator]) == int(mujoco.mjtGain.mjGAIN_FIXED)
        and int(model.actuator_biastype[actuator]) == int(mujoco.mjtBias.mjBIAS_NONE)
        and float(model.actuator_gainprm[actuator, 0]) == 1.0
        and float(model.actuator_gear[actuator, 0]) == 1.0
    )
    if not motor:
        return "actuator unit"
    joint_type = int(model.jnt_type[int(model.actuator_trnid[actuator, 0])])
    if joint_type == int(mujoco.mjtJoint.mjJNT_SLIDE):
        return "N"
    return "N m" if joint_type == int(mujoco.mjtJoint.mjJNT_HINGE) else "actuator unit"


def resolve_input(model: mujoco.MjModel, name: str) -> tuple[str, int, str]:
    """(kind, index, unit) of the input called `name`: an actuator's control ('ctrl', its id), else a force
    on a joint's first degree of freedom ('force', its dof address): 'JOINT' or 'JOINT:force'.

    Raises
    ------
    UnknownNameError
        no actuator or joint of that name (the message lists the valid ones).
    """
    actuators = _names(model, "actuator", model.nu)
    if name in actuators:
        actuator = int(model.actuator(name).id)
        return "ctrl", actuator, _actuator_unit(model, actuator)
    joints = _names(model, "joint", model.njnt)
    joint_name = name[: -len(":force")] if name.endswith(":force") else name
    if joint_name in joints:
        joint = model.joint(joint_name)
        unit = "N m" if int(joint.type[0]) == int(mujoco.mjtJoint.mjJNT_HINGE) else "N"
        return "force", int(joint.dofadr[0]), unit
    raise UnknownNameError("input (ACTUATOR or JOINT:force)", name, actuators + [f"{j}:force" for j in joints])


#: a sensor's unit by its type (others: 'sensor unit')
_SENSOR_UNITS = {
    int(mujoco.mjtSensor.mjSENS_ACCELEROMETER): "m/s^2",
    int(mujoco.mjtSensor.mjSENS_VELOCIMETER): "m/s",
    int(mujoco.mjtSensor.mjSENS_GYRO): "rad/s",
    int(mujoco.mjtSensor.mjSENS_FORCE): "N",
    int(mujoco.mjtSensor.mjSENS_TORQUE): "N m",
    int(mujoco.mjtSensor.mjSENS_FRAMEPOS): "m",
    int(mujoco.mjtSensor.mjSENS_FRAMELINVEL): "m/s",
    int(mujoco.mjtSensor.mjSENS_FRAMEANGVEL): "rad/s",
    int(mujoco.mjtSensor.mjSENS_FRAMELINACC): "m/s^2",
    int(mujoco.mjtSensor.mjSENS_FRAMEANGACC): "rad/s^2",
    int(mujoco.mjtSensor.mjSENS_ACTUATORFRC): "N",
}


def _sensor_unit(model: mujoco.MjModel, sensor: int) -> str:
    kind = int(model.sensor_type[sensor])
    if kind in (int(mujoco.mjtSensor.mjSENS_JOINTPOS), int(mujoco.mjtSensor.mjSENS_JOINTVEL)):
        joint = int(model.sensor_objid[sensor])
        base = "rad" if int(model.jnt_type[joint]) == int(mujoco.mjtJoint.mjJNT_HINGE) else "m"
        return base if kind == int(mujoco.mjtSensor.mjSENS_JOINTPOS) else f"{base}/s"
    return _SENSOR_UNITS.get(kind, "sensor unit")


def resolve_response(model: mujoco.MjModel, name: str) -> tuple[int, str, str]:
    """(index, kind, unit) of the response called `name`: 'JOINT' (kind 'pos'), 'JOINT:vel', 'JOINT:acc' (index:
    the joint's dof, a row of the state x = (dq, dv)), or a sensor 'SENSOR' (one-dimensional) or 'SENSOR[i]'
    (component i; kind 'sensor', index: its sensordata address). A joint's name wins over a sensor's.

    Raises
    ------
    UnknownNameError
        no joint or sensor of that name, an unknown kind, or a component out of range.
    """
    joint_name, _, kind = name.partition(":")
    kind = kind or "pos"
    joints = _names(model, "joint", model.njnt)
    if joint_name in joints and kind in RESPONSE_KINDS:
        joint = model.joint(joint_name)
        dof = int(joint.dofadr[0])
        hinge = int(joint.type[0]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        base = "rad" if hinge else "m"
        unit = {"pos": base, "vel": f"{base}/s", "acc": f"{base}/s^2"}[kind]
        return dof, kind, unit
    sensors = {}
    for sensor in range(model.nsensor):
        sensor_name = model.sensor(sensor).name
        if not sensor_name:
            continue
        dim, adr = int(model.sensor_dim[sensor]), int(model.sensor_adr[sensor])
        if dim == 1:
            sensors[sensor_name] = (adr, sensor)
        for i in range(dim):
            sensors[f"{sensor_name}[{i}]"] = (adr + i, sensor)
    if name in sensors:
        adr, sensor = sensors[name]
        return adr, "sensor", _sensor_unit(model, sensor)
    valid = [f"{j}{suffix}" for j in joints for suffix in ("", ":vel", ":acc")] + list(sensors)
    raise UnknownNameError("response (JOINT, JOINT:vel, JOINT:acc, SENSOR or SENSOR[i])", name, valid)


def _output(linear: Linearization, b: np.ndarray, dof: int, kind: str) -> tuple[np.ndarray, float]:
    """(c, d) of a joint response: a row of the state, or of dx/dt = A x + b u for an acceleration."""
    nv = linear.M.shape[0]
    n = linear.A.shape[0]
    if kind == "acc":
        return linear.A[nv + dof].copy(), float(b[nv + dof])
    c = np.zeros(n)
    c[dof if kind == "pos" else nv + dof] = 1.0
    return c, 0.0


@dataclasses.dataclass(frozen=True)
class _Probe:
    """Where the sines go in and what is measured: the input (kind 'ctrl'|'force', index) and the response
    (kind 'pos'|'vel'|'acc'|'sensor', index: a dof or a sensordata address)."""

    input_kind: str
    input_index: int
    response_kind: str
    response_index: int

    def rows(
        self, model: mujoco.MjModel, point: OperatingPoint, integrator: str | None = None, dt: float | None = None
    ) -> tuple[np.ndarray, float]:
        """(c, d) of a sensor response: the continuous forward pass's (integrator None) or one step's."""
        rows, feedthrough = sensor_rows(model, self.input_kind, self.input_index, point, integrator=integrator, dt=dt)
        return rows[self.response_index].copy(), float(feedthrough[self.response_index])


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

    def __init__(
        self,
        model: mujoco.MjModel,
        point: OperatingPoint,
        kind: str,
        index: int,
        c: np.ndarray,
        d: float,
        probe: _Probe | None = None,
    ):
        self.model, self.point, self.kind, self.index, self.c, self.d = model, point, kind, index, c, d
        self.probe = probe  # a sensor response: its rows come from the step of each integrator at its dt

    def response(self, integrator: str, dt: float, f: np.ndarray, step: float = FD_STEP) -> np.ndarray | None:
        """H_d at f [Hz], or None where the one-step map is unstable (no steady state); `step`: the maps'
        finite-difference step."""
        phi = one_step_map(self.model, integrator, dt, self.point, step=step)
        if spectral_radius(phi) > STABLE_RADIUS:
            return None
        gamma = step_input_column(self.model, integrator, self.kind, self.index, dt, self.point, step=step)
        c, d = self.c, self.d
        if self.probe is not None and self.probe.response_kind == "sensor" and integrator != "rk4":
            c, d = self.probe.rows(self.model, self.point, integrator, dt)
        return _discrete(phi, gamma, c, d, dt, f)


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
    amplitudes: Any = None,
    sweep: str | None = None,
) -> FrequencyResponse:
    """The frequency response of a model's linearization, and how well an integrator at dt reproduces it.

    Parameters
    ----------
    scene_or_model
        a scene name (its declared scenario, input and response), a path to an MJCF file, or an MjModel.
    scenario
        a scene's scenario (None: the one its `frequency` capability declares, else its default).
    input
        an actuator (its control), or 'JOINT:force' (or 'JOINT': a generalized force on its first degree of
        freedom, `qfrc_applied`) (None: the scene's default).
    response
        'JOINT' (position [m or rad]), 'JOINT:vel', 'JOINT:acc', or a sensor 'SENSOR' / 'SENSOR[i]' (its
        component i) (None: the scene's default).
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
    amplitudes
        the sinestream's input amplitudes [input unit] (None: one, 1 or half an actuator's control room): one
        sinestream each, so a non-linear model's amplitude dependence shows.
    sweep
        'up', 'down' or 'both': instead of independent sines, sweep `sines` (default DEFAULT_SWEEP_POINTS)
        linearly spaced frequencies over the band, each continuing from the last one's state (a non-linear
        model's branches and jumps), at each amplitude; a cubic oscillator's sweep is compared with the
        first-order harmonic balance (springlab.exact.harmonic_balance).

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
        raise BadInputError(
            "name the input (--input ACTUATOR|JOINT:force) and the response (--response JOINT[:vel|:acc]|SENSOR[i])"
        )
    kind, index, input_unit = resolve_input(model, input_name)
    if input_name == source.input and source.input_unit:
        input_unit = source.input_unit  # the scene knows what its actuator's control is
    dof, out_kind, response_unit = resolve_response(model, response_name)
    probe = _Probe(kind, index, out_kind, dof)
    if sweep is not None and sweep not in SWEEP_DIRECTIONS:
        raise BadInputError(f"sweep must be one of {', '.join(SWEEP_DIRECTIONS)}, got {sweep!r}")
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
    amplitude_values = (
        (default_amplitude(model, point, kind, index),)
        if amplitudes is None
        else _check_amplitudes(model, point, kind, index, amplitudes)
    )
    c, d = probe.rows(model, point) if out_kind == "sensor" else _output(linear, b, dof, out_kind)
    exact_of = _continuous(linear.A, b, c, d)
    grid = np.geomspace(band[0], band[1], int(points))
    exact = exact_of(grid)
    discretizer = _Discretizer(model, point, kind, index, c, d, probe)
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
    streams: list[Sinestream] = []
    branches: list[SweepBranch] = []
    duffing = None
    if sines and sweep is None:
        top = min(2.0 * band[1], 0.45 / dt)  # an octave above the band, below Nyquist
        sine_grid = np.geomspace(band[0], top, int(sines))
        sine_discrete = discretizer.response(integrator, dt, sine_grid)
        coarse = discretizer.response(integrator, dt, sine_grid, step=2 * FD_STEP)
        if sine_discrete is None or coarse is None:
            raise BadInputError(f"{integrator} at dt = {dt:g} s is unstable on this model: no steady state to estimate")
        for amplitude in amplitude_values:
            streams.append(
                sinestream(
                    model,
                    point,
                    linear,
                    b,
                    probe,
                    integrator,
                    dt,
                    sine_grid,
                    sine_discrete,
                    exact_of,
                    np.abs(coarse / sine_discrete - 1.0),
                    amplitude,
                    executor,
                )
            )
    if sweep is not None:
        sweep_grid = np.linspace(band[0], band[1], int(sines) if sines else DEFAULT_SWEEP_POINTS)
        if discretizer.response(integrator, dt, sweep_grid[:1]) is None:
            raise BadInputError(f"{integrator} at dt = {dt:g} s is unstable on this model: no steady state to sweep")
        directions = ("up", "down") if sweep == "both" else (sweep,)
        branches = _jumps(
            _run_sweeps(model, point, linear, b, probe, integrator, dt, sweep_grid, amplitude_values, directions)
        )
        if out_kind == "pos":
            reach = 1.2 * max(float(np.max(br.response_amplitude)) for br in branches)
            duffing = cubic_oscillator(model, point, kind, index, reach)
        if duffing is not None:

            def linear_error(f: np.ndarray) -> np.ndarray:
                # the integrator's own share (the hold's sinc is in the harmonic balance's force already)
                h_d = discretizer.response(integrator, dt, f)
                held = _hold(linear.A, b, c, d, dt, f)
                return np.zeros(len(f)) if h_d is None else np.abs(h_d / held - 1.0)

            branches = _harmonic_balance(branches, duffing, dt, (float(band[0]), float(band[1])), linear_error)
        for branch in branches:
            for array in (branch.frequencies_hz, branch.estimate, branch.response_amplitude, branch.residue):
                array.setflags(write=False)
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
        sinestream=streams[0] if streams else None,
        sinestreams=tuple(streams),
        sweeps=tuple(branches),
        duffing=duffing,
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
#: harmonics demodulated beside the fundamental (those below the Nyquist frequency of dt): a non-linear
#: response's harmonics are fitted, not aliased into the fundamental
HARMONICS = 5
#: the inputs a sine drives: every control and every generalized force, set before each step
_CONTROL_SPEC = int(mujoco.mjtState.mjSTATE_CTRL | mujoco.mjtState.mjSTATE_QFRC_APPLIED)
_STATE_SPEC = int(
    mujoco.mjtState.mjSTATE_TIME
    | mujoco.mjtState.mjSTATE_QPOS
    | mujoco.mjtState.mjSTATE_QVEL
    | mujoco.mjtState.mjSTATE_ACT
)


def _drive(common: dict[str, Any], omega: float, phase: float, amplitude: float, first: int, count: int) -> np.ndarray:
    """(count, nu + nv) rows of (ctrl, qfrc_applied) for steps first .. first + count - 1: the operating point's
    controls with amplitude sin(phase + omega (k + 1/2) dt) added to the input, held over step k."""
    model = common["model"]
    rows = np.zeros((count, model.nu + model.nv))
    rows[:, : model.nu] = common["ctrl"]
    column = common["input_index"] if common["input_kind"] == "ctrl" else model.nu + common["input_index"]
    k = np.arange(first, first + count)
    rows[:, column] += amplitude * np.sin(phase + omega * (k + 0.5) * common["dt"])
    return rows


def _measure(common: dict[str, Any], out: dict[Any, np.ndarray], row: int) -> np.ndarray:
    """The response samples of one simulation of a batched rollout: a joint's after each step, a sensor's at
    each step's start (MuJoCo computes sensors in the step's forward pass)."""
    nq, nv = common["model"].nq, common["model"].nv
    kind, index = common["response_kind"], common["response_index"]
    if kind == "sensor":
        values = out["sensordata"][row][:, index]
    elif kind == "pos":
        values = out[_STATE_SPEC][row][:, 1 + common["qposadr"]]
    else:
        values = out[_STATE_SPEC][row][:, 1 + nq + index]
    del nv
    return np.asarray(values, float) - common["offset"]


def _record(common: dict[str, Any]) -> list[Any]:
    return ["sensordata"] if common["response_kind"] == "sensor" else [_STATE_SPEC]


def _batch(common: dict[str, Any], starts: list[tuple[np.ndarray, np.ndarray, np.ndarray]], nthread: int):
    """A mujoco.batch.Batch of the configured model with one simulation per start (qpos, qvel, act)."""
    from mujoco import batch as mjbatch

    from springlab.sim.simulate import configured

    model = configured(common["model"], common["integrator"], common["dt"])
    batch = mjbatch.Batch(model, nsim=len(starts), nthread=nthread)
    for i, (qpos, qvel, act) in enumerate(starts):
        batch.time[i] = 0.0
        batch.qpos[i] = qpos
        batch.qvel[i] = qvel
        if model.na:
            batch.act[i] = act
    batch.warning[:] = 0
    return batch


def _check_finite(batch, values: list[np.ndarray], what: str) -> None:
    from springlab.errors import DivergedError
    from springlab.sim.simulate import BAD_WARNINGS

    warnings = np.array(batch.warning)
    if any(warnings[:, w, 1].any() for w in BAD_WARNINGS) or not all(np.isfinite(v).all() for v in values):
        raise DivergedError(f"{what} blew up in MuJoCo (non-finite state or MuJoCo's bad-state warnings)")


def _sine_chunk(payload: dict[str, Any], nthread: int = 0) -> list[np.ndarray]:
    """Run one chunk of sines (one batched MuJoCo rollout, segment by segment as the shorter runs end) and
    return each run's response samples (a module-level function: it runs on dask workers too)."""
    common = payload["common"]
    runs = payload["runs"]  # (qpos, qvel, act, omega, amplitude, steps)
    batch = _batch(common, [(r[0], r[1], r[2]) for r in runs], nthread)
    steps = np.array([r[5] for r in runs])
    records: list[list[np.ndarray]] = [[] for _ in runs]
    done = 0
    with quiet_mujoco():
        for end in np.unique(steps):
            ids = np.flatnonzero(steps >= end).astype(np.int32)
            count = int(end - done)
            control = np.stack([_drive(common, runs[i][3], 0.0, runs[i][4], done, count) for i in ids])
            out = batch.rollout(count, control=control, control_spec=_CONTROL_SPEC, record=_record(common), ids=ids)
            for row, i in enumerate(ids):
                records[i].append(_measure(common, out, row))
            done = int(end)
    values = [np.concatenate(r) for r in records]
    _check_finite(batch, values, "a sine")
    return values


def _demodulate(y: np.ndarray, t: np.ndarray, omega: float, dt: float | None = None) -> np.ndarray:
    """(Y_1, ..., Y_H): y(t) = a + b t + sum_h Re(Y_h exp(j h omega t)) by least squares (numpy.linalg.lstsq);
    the harmonics h = 2 .. HARMONICS below the Nyquist frequency of dt (None: the fundamental only)."""
    top = 1 if dt is None else max(1, min(HARMONICS, int(math.ceil(math.pi / (omega * dt))) - 1))
    t0 = t - t[0]
    columns = [np.ones_like(t), t0]
    for h in range(1, top + 1):
        columns += [np.cos(h * omega * t), np.sin(h * omega * t)]
    coef, *_ = np.linalg.lstsq(np.column_stack(columns), y, rcond=None)
    return np.array([complex(coef[2 + 2 * h], -coef[3 + 2 * h]) for h in range(top)])


def _common(model: mujoco.MjModel, point: OperatingPoint, probe: _Probe, integrator: str, dt: float) -> dict[str, Any]:
    """What every chunk needs: the model, the setting, the input and the response, and the response at the point."""
    qposadr = 0
    if probe.response_kind == "sensor":
        data = mujoco.MjData(model)
        with quiet_mujoco():
            point.load(model, data)
            mujoco.mj_forward(model, data)
        offset = float(data.sensordata[probe.response_index])
    else:
        qposadr = int(model.jnt_qposadr[int(model.dof_jntid[probe.response_index])])
        if probe.response_kind == "pos":
            offset = float(point.qpos[qposadr])
        else:
            offset = float(point.qvel[probe.response_index])
    return {
        "model": model,
        "integrator": integrator,
        "dt": dt,
        "ctrl": np.array(point.ctrl, float),
        "input_kind": probe.input_kind,
        "input_index": probe.input_index,
        "response_kind": probe.response_kind,
        "response_index": probe.response_index,
        "qposadr": qposadr,
        "offset": offset,
    }


def default_amplitude(model: mujoco.MjModel, point: OperatingPoint, kind: str, index: int) -> float:
    """The sinestream's input amplitude when none is given: 1 input unit, or half the room an actuator's
    control range leaves at the operating point [input unit].

    Raises
    ------
    BadInputError
        the operating point's control sits on its limit.
    """
    if kind != "ctrl":
        return 1.0
    low, high = model.actuator_ctrlrange[index]
    limited = bool(model.actuator_ctrllimited[index]) and high > low
    base = float(point.ctrl[index])
    amplitude = min(1.0, 0.5 * min(high - base, base - low)) if limited else 1.0
    if amplitude <= 0:
        raise BadInputError("the operating point's control sits on its limit: no room for a sine")
    return float(amplitude)


def _check_amplitudes(
    model: mujoco.MjModel, point: OperatingPoint, kind: str, index: int, amplitudes: Any
) -> tuple[float, ...]:
    """The amplitudes as floats > 0, each inside an actuator's control range around the operating point."""
    try:
        values = tuple(float(a) for a in amplitudes)
    except (TypeError, ValueError):
        raise BadInputError(f"amplitudes must be numbers > 0 in input units, got {amplitudes!r}") from None
    if not values or not all(math.isfinite(a) and a > 0 for a in values):
        raise BadInputError(f"amplitudes must be finite numbers > 0 in input units, got {amplitudes!r}")
    if kind == "ctrl" and bool(model.actuator_ctrllimited[index]):
        low, high = model.actuator_ctrlrange[index]
        room = min(high - point.ctrl[index], point.ctrl[index] - low)
        if max(values) > room:
            raise BadInputError(
                f"amplitude {max(values):g} leaves the actuator's control range {low:g}..{high:g} around"
                f" {point.ctrl[index]:g}; give amplitudes <= {room:g}"
            )
    return values


def _settle_rate(linear: Linearization) -> tuple[float, float]:
    """(sigma [1/s], cond(V)): the slowest decaying non-rigid mode's rate and the mode basis' condition number."""
    moving = [-lam.real for lam in linear.eigenvalues if abs(lam) > linear.growth_tolerance and lam.real < 0]
    sigma = min(moving) if moving else math.inf
    _, vectors = np.linalg.eig(linear.A)
    condition = float(np.linalg.cond(vectors)) if vectors.size else 1.0
    return sigma, condition


def _steady_start(
    model: mujoco.MjModel, point: OperatingPoint, linear: Linearization, b: np.ndarray, omega: float, amplitude: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(qpos, qvel, act) on the linearization's steady state at t = 0 of amplitude sin(omega t)."""
    nv = model.nv
    state = np.linalg.solve(1j * omega * np.eye(linear.A.shape[0]) - linear.A, b * (-1j * amplitude))
    start = state.real
    qpos = point.qpos.copy()
    mujoco.mj_integratePos(model, qpos, start[:nv], 1.0)
    return qpos, point.qvel + start[nv : 2 * nv], point.act + start[2 * nv :]


def sinestream(
    model: mujoco.MjModel,
    point: OperatingPoint,
    linear: Linearization,
    b: np.ndarray,
    probe: _Probe,
    integrator: str,
    dt: float,
    frequencies_hz: np.ndarray,
    discrete: np.ndarray,
    exact_of: Callable[[np.ndarray], np.ndarray],
    uncertainty: np.ndarray,
    amplitude: float,
    executor: Any = None,
) -> Sinestream:
    """Simulate MuJoCo at each frequency and demodulate (`Sinestream`; the module docstring says how).

    Each sine u_k = U sin(omega (k + 1/2) dt), held over step k on the input (an actuator's control or a
    joint's `qfrc_applied`), starts on the exact linearization's steady state (so only the small
    discrete-minus-exact difference is left to decay), runs `settle` (the slowest non-rigid mode's envelope
    exp(-sigma t) times the mode basis' condition number down to SINESTREAM_ACCURACY), then ESTIMATE_PERIODS
    whole periods (at least ESTIMATE_SAMPLES samples) of the response (a joint's position or velocity, or a
    sensor) are demodulated by least squares on (1, t, cos h omega t, sin h omega t) with the harmonics h
    below Nyquist. `uncertainty` (m,) is the discrete response's own relative finite-difference error (its maps
    at the steps h and 2 h compared). The stated accuracy is the linear model's: for a non-linear one the
    estimate is the first harmonic per input amplitude (its describing function) and may part from it.

    Raises
    ------
    BadInputError
        the response is a joint's acceleration (the run records positions and velocities; a sensor can
        measure one).
    """
    from springlab.studies.executor import chunked, resolve

    if probe.response_kind == "acc":
        raise BadInputError(
            "the sinestream measures a joint's position or velocity, or a sensor; not a joint's acceleration"
            " (add an accelerometer sensor)"
        )
    started = _time.perf_counter()
    sigma, condition = _settle_rate(linear)
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
        qpos, qvel, act = _steady_start(model, point, linear, b, omega, amplitude)
        runs.append((qpos, qvel, act, omega, amplitude, steps))
        left = condition * math.exp(-sigma * settle_steps * dt) if math.isfinite(sigma) else 0.0
        rounding = 1e3 * _EPS * math.sqrt(steps)
        meta.append((omega, settle_steps, estimate_steps, periods, min(left, 1.0) + rounding))
    common = _common(model, point, probe, integrator, dt)
    shift = 0 if probe.response_kind == "sensor" else 1  # a joint's sample k is after step k
    chunks = chunked(len(runs), SINES_PER_CHUNK)
    payloads = [{"common": common, "runs": [runs[i] for i in chunk]} for chunk in chunks]
    results = [y for part in resolve(executor).map(_sine_chunk, payloads, description="sines") for y in part]
    estimates = []
    for y, (omega, _, estimate_steps, _, _) in zip(results, meta):
        t = (np.arange(len(y)) + shift) * dt
        window = slice(len(y) - estimate_steps - shift, len(y))
        estimates.append(_demodulate(y[window], t[window], omega, dt)[0] / (-1j * amplitude))
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
        steps=int(sum(r[5] for r in runs)),
        wall_time_s=_time.perf_counter() - started,
    )


# -- the sweep: up and down in frequency, each sine continuing from the last (a non-linear model's branches) -----

#: each sweep frequency settles until the slowest mode's envelope falls to this, from where the last one ended
SWEEP_ACCURACY = 1e-4
#: the sweep's branches differ (hysteresis) where their first harmonics part by more than this many times
#: SWEEP_ACCURACY
HYSTERESIS_FACTOR = 100.0
SWEEP_DIRECTIONS = ("up", "down", "both")


@dataclasses.dataclass(frozen=True)
class SweepBranch:
    """One sweep in frequency at one input amplitude, each sine starting from the previous one's final state
    (continuation: a non-linear model stays on the branch it is on until that branch ends).

    Attributes
    ----------
    direction
        'up' or 'down'.
    amplitude
        the input amplitude [input unit].
    frequencies_hz
        (m,) in the order swept [Hz].
    estimate
        (m,) complex: the response's first harmonic per input amplitude (the describing function).
    response_amplitude
        (m,) |first harmonic| [response unit].
    third_harmonic
        (m,) |third harmonic| / |first harmonic| [-] (nan where 3 f is above Nyquist).
    residue
        (m,) |Y(second half of the window) - Y(first half)| / |Y| [-]: what the transient left (settling check).
    jump_hz
        (f_before, f_after) [Hz] between which the branch jumps (the end of the band where the up and down
        branches differ, in this sweep's direction), or None (no hysteresis, or only one direction swept).
    predicted
        (m,) the harmonic-balance amplitude nearest the measured one [response unit] (None: the model is no
        cubic oscillator or the response is not its position).
    bound
        (m,) the derived bound on |measured - predicted| [response unit] (springlab.exact.harmonic_balance:
        twice the first-order shift by the neglected third harmonic, plus twice the residue and the
        integrator's relative error on the linearization beyond the held input's (|H_d / H_zoh - 1|), times
        the measured amplitude).
    fold_hz
        (f, low, high) [Hz]: the harmonic-balance fold where the branch this sweep starts on ends (followed
        root to root from the first point's root), with the bracket first-order balance promises, or None.
    steps
        MuJoCo steps of the sweep.
    """

    direction: str
    amplitude: float
    frequencies_hz: np.ndarray
    estimate: np.ndarray
    response_amplitude: np.ndarray
    third_harmonic: np.ndarray
    residue: np.ndarray
    jump_hz: tuple[float, float] | None = None
    predicted: np.ndarray | None = None
    bound: np.ndarray | None = None
    fold_hz: tuple[float, float, float] | None = None
    steps: int = 0

    @property
    def within_bound(self) -> np.ndarray | None:
        """(m,) bool: |measured - predicted| <= bound (None without a prediction)."""
        if self.predicted is None or self.bound is None:
            return None
        return np.abs(self.response_amplitude - self.predicted) <= self.bound

    @property
    def agrees(self) -> bool:
        """Every point within its harmonic-balance bound (True without a prediction)."""
        inside = self.within_bound
        return True if inside is None else bool(np.all(inside))

    def to_dict(self) -> dict[str, Any]:
        """One entry of frequency.json's "sweeps"."""
        inside = self.within_bound
        return {
            "direction": self.direction,
            "amplitude": self.amplitude,
            "frequencies_hz": self.frequencies_hz.tolist(),
            "magnitude": np.abs(self.estimate).tolist(),
            "phase_deg": np.degrees(np.angle(self.estimate)).tolist(),
            "response_amplitude": self.response_amplitude.tolist(),
            "third_harmonic": [None if not math.isfinite(v) else float(v) for v in self.third_harmonic],
            "residue": self.residue.tolist(),
            "jump_hz": None if self.jump_hz is None else list(self.jump_hz),
            "harmonic_balance_amplitude": None if self.predicted is None else self.predicted.tolist(),
            "bound": None if self.bound is None else self.bound.tolist(),
            "within_bound": None if inside is None else inside.tolist(),
            "agrees": self.agrees,
            "fold_hz": None if self.fold_hz is None else list(self.fold_hz),
            "steps": self.steps,
        }


def _run_sweeps(
    model: mujoco.MjModel,
    point: OperatingPoint,
    linear: Linearization,
    b: np.ndarray,
    probe: _Probe,
    integrator: str,
    dt: float,
    grid: np.ndarray,
    amplitudes: tuple[float, ...],
    directions: tuple[str, ...],
) -> list[SweepBranch]:
    """Continuation sweeps, one chain per (amplitude, direction), all chains in one mujoco.batch.Batch.

    At each frequency the input u_k = U sin(phi + omega (k + 1/2) dt) continues the last frequency's phase phi
    (no jump in the drive), runs ln(1 / SWEEP_ACCURACY) / sigma (sigma: the slowest decaying mode of the
    linearization; for a one-degree-of-freedom oscillator the mean decay of any periodic orbit's neighbours is
    c / (2 m) too, by Liouville) and then 2 ESTIMATE_PERIODS whole periods, demodulated with their harmonics
    (`_demodulate`); the halves of that window demodulated alone give the residue. The first frequency of each
    chain starts on the linearization's steady state.
    """
    if probe.response_kind == "acc":
        raise BadInputError(
            "the sweep measures a joint's position or velocity, or a sensor; not a joint's acceleration"
        )
    sigma, _ = _settle_rate(linear)
    if not math.isfinite(sigma):
        raise BadInputError("the model has no damped mode: a sweep has no steady state to continue along")
    settle = math.log(1.0 / SWEEP_ACCURACY) / sigma
    chains = [(a, d) for a in amplitudes for d in directions]
    orders = [grid if d == "up" else grid[::-1] for _, d in chains]
    first = [2 * math.pi * float(order[0]) for order in orders]
    starts = [_steady_start(model, point, linear, b, w, a) for w, (a, _) in zip(first, chains)]
    common = _common(model, point, probe, integrator, dt)
    shift = 0 if probe.response_kind == "sensor" else 1
    # every chain advances together, one batched rollout per frequency index (threads across chains): the same
    # settling for all, and each chain's own whole-period window at the end of it
    batch = _batch(common, starts, min(len(chains), os.cpu_count() or 1))
    phases = [0.0] * len(chains)
    found: list[list[np.ndarray]] = [[] for _ in chains]
    ids = np.arange(len(chains), dtype=np.int32)
    total = 0
    settle_steps = int(math.ceil(settle / dt))
    with quiet_mujoco():
        for i in range(len(grid)):
            freqs = [float(order[i]) for order in orders]
            windows = []
            for f in freqs:
                periods = max(2 * ESTIMATE_PERIODS, 2 * math.ceil(0.5 * ESTIMATE_SAMPLES * dt * f))
                windows.append(int(round(periods / f / dt)))
            steps = settle_steps + max(windows)
            control = np.stack(
                [_drive(common, 2 * math.pi * f, phases[j], chains[j][0], 0, steps) for j, f in enumerate(freqs)]
            )
            out = batch.rollout(steps, control=control, control_spec=_CONTROL_SPEC, record=_record(common), ids=ids)
            ys = [_measure(common, out, j) for j in range(len(chains))]
            _check_finite(batch, ys, "a sweep")
            t = (np.arange(steps) + shift) * dt
            for j, (amplitude, _) in enumerate(chains):
                f, y, window = freqs[j], ys[j], windows[j]
                omega = 2 * math.pi * f
                tail, half = slice(steps - window, steps), slice(steps - window // 2, steps)
                early = slice(steps - window, steps - window // 2)
                whole = _demodulate(y[tail], t[tail], omega, dt)
                late = _demodulate(y[half], t[half], omega, dt)[0]
                before = _demodulate(y[early], t[early], omega, dt)[0]
                phasor = -1j * amplitude * np.exp(1j * phases[j])
                third = abs(whole[2]) / abs(whole[0]) if len(whole) >= 3 and abs(whole[0]) > 0 else math.nan
                residue = abs(late - before) / max(abs(whole[0]), 1e-300)
                found[j].append(np.array([f, whole[0] / phasor, abs(whole[0]), third, residue], complex))
                phases[j] = math.fmod(phases[j] + omega * steps * dt, 2 * math.pi)
            total += steps * len(chains)
    branches = []
    for j, (amplitude, direction) in enumerate(chains):
        rows = np.array(found[j])
        branches.append(
            SweepBranch(
                direction=direction,
                amplitude=float(amplitude),
                frequencies_hz=rows[:, 0].real.copy(),
                estimate=rows[:, 1].copy(),
                response_amplitude=rows[:, 2].real.copy(),
                third_harmonic=rows[:, 3].real.copy(),
                residue=rows[:, 4].real.copy(),
                steps=total // len(chains),
            )
        )
    return branches


def _jumps(branches: list[SweepBranch]) -> list[SweepBranch]:
    """Each branch with its jump: where the up and down sweeps at its amplitude stop differing, in its direction."""
    out = []
    for branch in branches:
        other = next((o for o in branches if o.amplitude == branch.amplitude and o.direction != branch.direction), None)
        if other is None:
            out.append(branch)
            continue
        mine = dict(zip(branch.frequencies_hz, branch.estimate))
        theirs = dict(zip(other.frequencies_hz, other.estimate))
        grid = np.sort(branch.frequencies_hz)
        differ = [
            abs(mine[f] - theirs[f]) / max(abs(mine[f]), abs(theirs[f])) > HYSTERESIS_FACTOR * SWEEP_ACCURACY
            for f in grid
        ]
        inside = np.nonzero(differ)[0]
        jump = None
        if inside.size:
            if branch.direction == "up" and inside[-1] + 1 < len(grid):
                jump = (float(grid[inside[-1]]), float(grid[inside[-1] + 1]))
            if branch.direction == "down" and inside[0] > 0:
                jump = (float(grid[inside[0] - 1]), float(grid[inside[0]]))
        out.append(dataclasses.replace(branch, jump_hz=jump))
    return out


def _harmonic_balance(
    branches: list[SweepBranch],
    duffing: Any,
    dt: float,
    band: tuple[float, float],
    linear_error: Callable[[np.ndarray], np.ndarray],
) -> list[SweepBranch]:
    """Each branch with the harmonic-balance amplitude nearest each measured one, its derived bound, and the fold
    where its direction's branch ends (springlab.exact.harmonic_balance)."""
    from springlab.exact import harmonic_balance as hb

    out = []
    for branch in branches:
        omegas = 2 * math.pi * branch.frequencies_hz
        hold = np.sinc(omegas * dt / (2 * math.pi))  # a held sine's first harmonic: sinc(omega dt / 2)
        forces = duffing.gain * branch.amplitude * hold
        predicted, bound = [], []
        integrator = linear_error(branch.frequencies_hz)
        for omega, force, measured, residue, err in zip(
            omegas, forces, branch.response_amplitude, branch.residue, integrator
        ):
            roots = hb.amplitudes(duffing, float(force), float(omega))
            root = float(roots[np.argmin(np.abs(np.log(roots / measured)))])
            predicted.append(root)
            bound.append(hb.amplitude_bound(duffing, float(force), root, float(omega)) + (2 * residue + err) * measured)
        # the fold where the branch the sweep starts on ends (harmonic balance followed from the first point)
        force_mid = duffing.gain * branch.amplitude * float(np.sinc(math.sqrt(band[0] * band[1]) * dt))
        first, last = float(branch.frequencies_hz[0]), float(branch.frequencies_hz[-1])
        fold = hb.fold_bracket(duffing, force_mid, first, last, float(branch.response_amplitude[0]))
        out.append(dataclasses.replace(branch, predicted=np.array(predicted), bound=np.array(bound), fold_hz=fold))
    return out
