"""What `springlab frequency` returns: the response, its resonances, the integrators' bands, the
sinestream and the sweep branches (immutable; `to_dict()` is frequency.json)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab import display, tables
from springlab.answer import Answer
from springlab.exact.harmonic_balance import Duffing
from springlab.files import Output, csv_text
from springlab.studies import answers

if TYPE_CHECKING:
    import pandas
    from matplotlib.figure import Figure


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
    warnings
        what the linearization cannot say at this operating point (springlab.studies.frequency.caveats: not at
        rest, contacts, dry friction, constraints; valid only for small motions keeping the contact state).
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
    warnings: tuple[str, ...] = ()

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

    @property
    def question_answer(self) -> Answer:
        """The question and its answer: the band the setting reproduces, the resonances, the cheapest setting."""
        say = answers.Quoter()
        lo, hi = self.band_hz
        setting = f"{self.integrator} at dt = {answers.written(self.dt, '~s')}"
        question = (
            f"What is the frequency response of {self.description} ({self.input} -> {self.response}) from"
            f" {answers.written(lo, 'Hz', '.4g')} to {answers.written(hi, 'Hz', '.4g')}, and does {setting} reproduce"
            f" it within {self.tol:g}?"
        )
        low = say("band_low_hz", lo, "Hz", ".4g")
        setting = f"{self.integrator} at {say.dt('dt_s', self.dt)}"
        if self.within_tol_hz is None:
            head = f"{setting} misses {self.tol:g} already at {low}"
        else:
            word = "the whole band" if self.covers_band else "not the whole band"
            head = (
                f"{setting} reproduces it within {self.tol:g} from {low} to"
                f" {say('within_tol_high_hz', self.within_tol_hz[1], 'Hz', '.4g')} ({word})"
            )
        peaks = [
            say(f"resonance_{i}_hz", r.frequency_hz, "Hz", ".4g")
            + (
                ""
                if r.damping_ratio is None
                else f" (damping ratio {say(f'resonance_{i}_damping_ratio', r.damping_ratio)})"
            )
            for i, r in enumerate(self.resonances, start=1)
        ]
        found = f"; it resonates at {', '.join(peaks)}" if peaks else "; no resonance in the band"
        best = self.cheapest
        cheapest = (
            f" The cheapest setting covering the band: {best.integrator} at {say.dt('cheapest_dt_s', best.max_dt_s)}."
            if best is not None and best.max_dt_s is not None
            else ""
        )
        return say.answer(question, f"{head}{found}.{cheapest}")

    @property
    def question(self) -> str:
        """What the analysis asks, in words (`question_answer`)."""
        return self.question_answer.question

    @property
    def answer(self) -> str:
        """The answer in words with units (`question_answer`)."""
        return self.question_answer.answer

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
            **self.question_answer.to_dict(),
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
            "warnings": list(self.warnings),
            "wall_time_s": self.wall_time_s,
        }

    def outputs(self) -> tuple[Output, ...]:
        """The files `springlab frequency --output DIR` writes (springlab.outputs.write): frequency.json,
        frequency.csv (`rows()`), sinestream.csv (`sweep_rows()`, after a sinestream or a sweep) and bode.png."""
        written = [Output.json("frequency.json", self.to_dict()), Output("frequency.csv", csv_text(self.rows()))]
        if self.sinestreams or self.sweeps:
            written.append(Output("sinestream.csv", csv_text(self.sweep_rows())))
        return (*written, Output("bode.png"))

    def to_pandas(self) -> pandas.DataFrame:
        """The rows of frequency.csv as a DataFrame (needs pandas)."""
        return tables.to_pandas({k: np.asarray(v) for k, v in self.rows().items()})


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
