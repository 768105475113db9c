"""The orchestrator of `springlab frequency`: check the options, load the model, compute the exact and the
discrete responses, the band and every integrator's largest dt, run the sinestream or the sweep, and
assemble the `FrequencyResponse`."""

from __future__ import annotations

import dataclasses
import math
import os
import time as _time
from collections.abc import Callable, Sequence
from typing import Any

import mujoco
import numpy as np

from springlab.errors import BadInputError
from springlab.exact.harmonic_balance import Duffing, cubic_oscillator
from springlab.exact.linearize import FD_STEP, Linearization
from springlab.exact.model_at_point import ModelAtPoint
from springlab.scenes.declarations import keyword_parameters
from springlab.sim.simulate import INTEGRATORS, integrator_id
from springlab.studies.executor import Executor

from .caveats import point_warnings
from .inputs import (
    Probe,
    Source,
    load_source,
    output_row,
    resolve_input,
    resolve_response,
    valid_inputs,
    valid_responses,
)
from .linear import (
    EVALUATIONS,
    Discretizer,
    band_within,
    continuous_response,
    find_anti_resonances,
    find_resonances,
    held_response,
    max_dt,
    relative_error,
)
from .results import FrequencyResponse, IntegratorBand, Resonance, Sinestream, SweepBranch
from .sinestream import check_amplitudes, default_amplitude, sinestream
from .sweep import SWEEP_DIRECTIONS, compare_with_harmonic_balance, mark_jumps, run_sweeps

#: defaults of the command line and the API
DEFAULT_TOL = 1e-3
DEFAULT_POINTS = 200
#: sweep frequencies when `sweep` is given without `sines`
DEFAULT_SWEEP_POINTS = 40


def _refuse_command_line_strings(**values: object) -> None:
    """The library takes typed values; the command line's strings ('0.1:10', '0.5,2', 'rk4,euler') are parsed
    by `springlab frequency` alone."""
    typed = {
        "band": "a (fmin, fmax) tuple in Hz, e.g. band=(0.1, 10.0)",
        "amplitudes": "a sequence of numbers in input units, e.g. amplitudes=(0.5, 2.0)",
        "integrators": "a sequence of names, e.g. integrators=['rk4', 'euler']",
    }
    for name, value in values.items():
        if isinstance(value, str):
            raise BadInputError(f"{name} takes {typed[name]}, not the command line's string {value!r}")


def _check_counts(points: int, sines: int, integrators: Sequence[str] | None, sweep: str | None) -> tuple[str, ...]:
    """Check the grid's and the sinestream's counts and the sweep's direction; the integrators to search."""
    if isinstance(points, bool) or not isinstance(points, (int, np.integer)) or points < 2:
        raise BadInputError(f"points must be an integer >= 2, got {points!r}")
    if isinstance(sines, bool) or not isinstance(sines, (int, np.integer)) or sines < 0 or sines == 1:
        raise BadInputError(f"sines must be 0 (none) or an integer >= 2, got {sines!r}")
    swept = tuple(INTEGRATORS) if integrators is None else tuple(integrators)
    for name in swept:
        integrator_id(name)
    if sweep is not None and sweep not in SWEEP_DIRECTIONS:
        raise BadInputError(f"sweep must be one of {', '.join(SWEEP_DIRECTIONS)}, got {sweep!r}")
    return swept


def _below_nyquist(band: tuple[float, float], dt: float) -> tuple[float, float]:
    """The band, refused when its top reaches the Nyquist frequency 1 / (2 dt) [Hz] of the timestep dt [s]."""
    nyquist = 0.5 / dt
    if band[1] >= nyquist:
        raise BadInputError(
            f"band top {band[1]:g} Hz is at or above the Nyquist frequency 1 / (2 dt) = {nyquist:g} Hz of"
            f" dt = {dt:g} s; lower fmax or dt"
        )
    return band


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
    model: str | os.PathLike[str] | mujoco.MjModel,
    scenario: str | None = None,
    *,
    input: str | None = None,  # noqa: A002 - the issue's and the command line's name
    response: str | None = None,
    band: tuple[float, float] | None = None,
    points: int = DEFAULT_POINTS,
    integrator: str | None = None,
    dt: float | None = None,
    tol: float = DEFAULT_TOL,
    integrators: Sequence[str] | None = None,
    sines: int = 0,
    executor: Executor | None = None,
    amplitudes: Sequence[float] | None = None,
    sweep: str | None = None,
    **parameters: float,
) -> FrequencyResponse:
    """The frequency response of a model's linearization, and how well an integrator at dt reproduces it.

    Parameters
    ----------
    model
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
        (fmin, fmax) [Hz] (None: a decade below the slowest mode to three times the fastest,
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
    **parameters
        a scene's parameter overrides [SI], as `springlab.run`'s keywords.

    Returns
    -------
    FrequencyResponse
        the exact and discrete responses, resonances, the band within tol and every integrator's largest dt.

    Raises
    ------
    BadInputError
        unknown names, an empty or inverted band, a band above Nyquist of dt, a bad number.
    TypeError
        an old keyword spelling (`parameters={...}`) or another study's option.
    """
    started = _time.perf_counter()
    parameters = keyword_parameters("frequency", parameters)
    _refuse_command_line_strings(band=band, amplitudes=amplitudes, integrators=integrators)
    source = load_source(model, scenario, parameters)
    integrator = source.integrator if integrator is None else integrator
    integrator_id(integrator)
    dt = source.dt if dt is None else _check_number("dt", dt)
    tol = _check_number("tol", tol, 0.0, 1.0)
    swept = _check_counts(points, sines, integrators, sweep)
    signal = _signal(source, input, response)
    checked_band = None if band is None else _check_band(band)
    at = ModelAtPoint.at(source.model)  # linearized once, its maps differenced once per setting
    band = _below_nyquist(_default_band(at.linear, dt) if checked_band is None else checked_band, dt)
    probe = signal.probe
    amplitude_values = (
        (default_amplitude(at.model, at.point, probe.input_kind, probe.input_index),)
        if amplitudes is None
        else check_amplitudes(at.model, at.point, probe.input_kind, probe.input_index, amplitudes)
    )
    responses = _responses(at, signal, integrator, dt, tol, band, int(points), swept)
    streams: list[Sinestream] = []
    branches: tuple[SweepBranch, ...] = ()
    duffing = None
    if sines and sweep is None:
        streams = _sinestreams(responses, integrator, dt, band, int(sines), amplitude_values, executor)
    if sweep is not None:
        branches, duffing = _sweeps(responses, integrator, dt, band, int(sines), amplitude_values, sweep)
    result = _result(
        source, signal, at.point.label, integrator, dt, tol, band, responses, streams, branches, duffing, started
    )
    return dataclasses.replace(result, warnings=point_warnings(at, band))


def _result(
    source: Source,
    signal: _Signal,
    point_label: str,
    integrator: str,
    dt: float,
    tol: float,
    band: tuple[float, float],
    responses: _Responses,
    streams: list[Sinestream],
    branches: tuple[SweepBranch, ...],
    duffing: Duffing | None,
    started: float,
) -> FrequencyResponse:
    """The `FrequencyResponse`, with the scene's own answers where its declared input and response were asked."""
    answers: dict[str, Any] = {}
    answer_lines: tuple[str, ...] = ()
    declared = (signal.input, signal.response) == (source.input, source.response)
    if source.interpret is not None and declared:
        # the scene's own question, asked of its declared input and response only
        answers, answer_lines = source.interpret(
            source.model, source.parameters, responses.exact_of, tuple(r.to_dict() for r in responses.resonances), band
        )
    return FrequencyResponse(
        source=source.label,
        input=signal.input,
        response=signal.response,
        units={"input": signal.input_unit, "response": signal.response_unit},
        point=point_label,
        integrator=integrator,
        dt=float(dt),
        tol=tol,
        band_hz=(float(band[0]), float(band[1])),
        frequencies_hz=responses.grid,
        exact=responses.exact,
        discrete=responses.discrete,
        hold=responses.hold,
        resonances=responses.resonances,
        anti_resonances=responses.anti_resonances,
        within_tol_hz=responses.within,
        covers_band=responses.within is not None and responses.within[1] >= band[1],
        integrators=responses.bands,
        description=source.description if declared and source.description else f"{signal.input} to {signal.response}",
        wall_time_s=_time.perf_counter() - started,
        sinestream=streams[0] if streams else None,
        sinestreams=tuple(streams),
        sweeps=branches,
        duffing=duffing,
        answers=answers,
        answer_lines=tuple(answer_lines),
    )


@dataclasses.dataclass(frozen=True)
class _Signal:
    """The input and the response asked for, resolved on the model (names, units, where to read them)."""

    input: str
    response: str
    input_unit: str
    response_unit: str
    probe: Probe


def _signal(source: Source, input_name: str | None, response_name: str | None) -> _Signal:
    """The input and response named (None: the scene's declared ones), resolved on the source's model."""
    input_name = input_name if input_name is not None else source.input
    response_name = response_name if response_name is not None else source.response
    if input_name is None or response_name is None:
        # the names this model takes, so the first try is not a guess
        missing = [
            f"--input, one of: {', '.join(valid_inputs(source.model))}" if input_name is None else "",
            f"--response, one of: {', '.join(valid_responses(source.model))}" if response_name is None else "",
        ]
        raise BadInputError(f"{source.label} declares no default: name {'; and '.join(m for m in missing if m)}")
    kind, index, input_unit = resolve_input(source.model, input_name)
    if input_name == source.input and source.input_unit:
        input_unit = source.input_unit  # the scene knows what its actuator's control is
    dof, out_kind, response_unit = resolve_response(source.model, response_name)
    return _Signal(input_name, response_name, input_unit, response_unit, Probe(kind, index, out_kind, dof))


@dataclasses.dataclass(frozen=True)
class _Responses:
    """The exact and discrete responses over the grid, and what the sinestream and the sweep reuse."""

    at: ModelAtPoint
    probe: Probe
    b: np.ndarray
    c: np.ndarray
    d: float
    exact_of: Callable[[np.ndarray], np.ndarray]
    discretizer: Discretizer
    grid: np.ndarray
    exact: np.ndarray
    discrete: np.ndarray
    hold: np.ndarray
    within: tuple[float, float] | None
    resonances: tuple[Resonance, ...]
    anti_resonances: tuple[Resonance, ...]
    bands: tuple[IntegratorBand, ...]


def _responses(
    at: ModelAtPoint,
    signal: _Signal,
    integrator: str,
    dt: float,
    tol: float,
    band: tuple[float, float],
    points: int,
    swept: tuple[str, ...],
) -> _Responses:
    """The exact response, the integrator's at dt, the exact hold's, the band within tol, the resonances and
    every swept integrator's largest dt covering the band."""
    probe, linear = signal.probe, at.linear
    b = at.input_column(probe.input_kind, probe.input_index)
    if probe.response_kind == "sensor":
        c, d = probe.rows(at)
    else:
        c, d = output_row(linear, b, probe.response_index, probe.response_kind)
    exact_of = continuous_response(linear.A, b, c, d)
    grid = np.geomspace(band[0], band[1], points)
    exact = exact_of(grid)
    discretizer = Discretizer(at, probe, c, d)
    discrete = discretizer.response(integrator, dt, grid)
    if discrete is None:
        discrete = np.full(grid.shape, np.nan + 0j)
    errors = relative_error(None if np.isnan(discrete).any() else discrete, exact)
    within = band_within(discretizer, integrator, dt, exact_of, grid, errors, tol)
    hold = held_response(linear.A, b, c, d, dt, grid)
    bands = []
    for name in swept:
        top = max_dt(discretizer, name, grid, exact, tol)
        bands.append(IntegratorBand(name, top, None if top is None else EVALUATIONS[name] / top))
    for array in (grid, exact, discrete, hold):
        array.setflags(write=False)
    return _Responses(
        at=at,
        probe=probe,
        b=b,
        c=c,
        d=d,
        exact_of=exact_of,
        discretizer=discretizer,
        grid=grid,
        exact=exact,
        discrete=discrete,
        hold=hold,
        within=within,
        resonances=find_resonances(exact_of, band, points, np.asarray(linear.eigenvalues, complex)),
        anti_resonances=find_anti_resonances(linear.A, b, c, d, band),
        bands=tuple(bands),
    )


def _sinestreams(
    responses: _Responses,
    integrator: str,
    dt: float,
    band: tuple[float, float],
    sines: int,
    amplitudes: tuple[float, ...],
    executor: Executor | None,
) -> list[Sinestream]:
    """One sinestream per amplitude: `sines` sines log-spaced over the band and an octave above it."""
    top = min(2.0 * band[1], 0.45 / dt)  # an octave above the band, below Nyquist
    sine_grid = np.geomspace(band[0], top, sines)
    discretizer = responses.discretizer
    sine_discrete = discretizer.response(integrator, dt, sine_grid)
    coarse = discretizer.response(integrator, dt, sine_grid, step=2 * FD_STEP)
    if sine_discrete is None or coarse is None:
        raise BadInputError(f"{integrator} at dt = {dt:g} s is unstable on this model: no steady state to estimate")
    return [
        sinestream(
            responses.at,
            responses.b,
            responses.probe,
            integrator,
            dt,
            sine_grid,
            sine_discrete,
            responses.exact_of,
            np.abs(coarse / sine_discrete - 1.0),
            amplitude,
            executor,
        )
        for amplitude in amplitudes
    ]


def _sweeps(
    responses: _Responses,
    integrator: str,
    dt: float,
    band: tuple[float, float],
    sines: int,
    amplitudes: tuple[float, ...],
    sweep: str,
) -> tuple[tuple[SweepBranch, ...], Duffing | None]:
    """The up and/or down sweeps over the band at each amplitude, and a cubic oscillator's harmonic balance."""
    discretizer, at, probe = responses.discretizer, responses.at, responses.probe
    sweep_grid = np.linspace(band[0], band[1], sines if sines else DEFAULT_SWEEP_POINTS)
    if discretizer.response(integrator, dt, sweep_grid[:1]) is None:
        raise BadInputError(f"{integrator} at dt = {dt:g} s is unstable on this model: no steady state to sweep")
    directions = ("up", "down") if sweep == "both" else (sweep,)
    branches = mark_jumps(
        run_sweeps(
            at,
            responses.b,
            probe,
            integrator,
            dt,
            sweep_grid,
            amplitudes,
            directions,
        )
    )
    duffing = None
    if probe.response_kind == "pos":
        reach = 1.2 * max(float(np.max(br.response_amplitude)) for br in branches)
        duffing = cubic_oscillator(at.model, at.point, probe.input_kind, probe.input_index, reach)
    if duffing is not None:

        def linear_error(f: np.ndarray) -> np.ndarray:
            # the integrator's own share (the hold's sinc is in the harmonic balance's force already)
            h_d = discretizer.response(integrator, dt, f)
            held = held_response(at.linear.A, responses.b, responses.c, responses.d, dt, f)
            return np.zeros(len(f)) if h_d is None else np.abs(h_d / held - 1.0)

        branches = compare_with_harmonic_balance(branches, duffing, dt, linear_error)
    for branch in branches:
        for array in (branch.frequencies_hz, branch.estimate, branch.response_amplitude, branch.residue):
            array.setflags(write=False)
    return tuple(branches), duffing
