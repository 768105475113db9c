"""springlab frequency (issue 23): the exact response against closed forms, MuJoCo's discrete-time response
against independent derivations of its integrators' one-step maps, and bad input at the command line.

Tolerances: the linearization's entries come from centred differences of a linear model, good to a few eps
relative (a centred difference of a linear function only rounds), and a relative perturbation delta of A
moves H(j omega) by at most kappa delta, kappa = ||A|| ||(j omega I - A)^-1|| (the same with Phi and
z I - Phi for the discrete response). Each test bounds its error by ROUNDING x eps x kappa with
ROUNDING = 1e3 for the tens of floating-point operations in every evaluated entry. The quarter car carries
its weight on its springs: a centred difference there rounds relative to the preload (6e4 N of tire bias
against 0.2 N of increment), so its tests take CONTRIBUTING's sqrt(eps) for finite differences instead.
"""

from __future__ import annotations

import json
import math
import re

import mujoco
import numpy as np
import pytest

import springlab
from springlab.cli.main import main
from springlab.errors import BadInputError
from springlab.scenes import get as get_scene

EPS = float(np.finfo(float).eps)
ROUNDING = 1e3


def _kappa(a: np.ndarray, points: np.ndarray) -> float:
    """max over the points of ||A|| ||(x I - A)^-1||_2."""
    n = a.shape[0]
    norm = np.linalg.norm(a, 2)
    return max(norm * np.linalg.norm(np.linalg.inv(x * np.eye(n) - a), 2) for x in points)


def _slider(zeta: float, **extra):
    m, k = 2.0, 800.0
    d = 2.0 * zeta * math.sqrt(k * m)
    result = springlab.frequency(
        "slider",
        mass=m,
        stiffness=k,
        damping=d,
        band=(0.1, 40.0),
        points=120,
        integrators=(),
        **extra,
    )
    return result, m, d, k


@pytest.mark.parametrize("zeta", [0.05, 1.0, 3.0], ids=["underdamped", "critical", "overdamped"])
def test_slider_exact_response_is_one_over_m_s2_plus_d_s_plus_k(zeta):
    result, m, d, k = _slider(zeta)
    s = 2j * np.pi * result.frequencies_hz
    closed = 1.0 / (m * s**2 + d * s + k)
    a = np.array([[0.0, 1.0], [-k / m, -d / m]])
    tol = ROUNDING * EPS * _kappa(a, s)
    assert tol < 1e-9  # the 1e-9 holds with room
    assert np.max(np.abs(result.exact / closed - 1.0)) <= tol
    phase = np.unwrap(np.angle(result.exact)) - np.unwrap(np.angle(closed))
    assert np.max(np.abs(phase)) <= tol


def test_slider_resonance_peak_and_half_power_damping_match_the_closed_form():
    zeta = 0.05
    result, m, d, k = _slider(zeta)
    (peak,) = result.resonances
    wn = math.sqrt(k / m)
    f_peak = wn * math.sqrt(1 - 2 * zeta**2) / (2 * math.pi)
    # |H| is flat at its peak: the located frequency is good to sqrt(eps) relative, the magnitude to eps
    assert peak.frequency_hz == pytest.approx(f_peak, rel=1e-6)
    assert peak.magnitude == pytest.approx(1.0 / (2 * zeta * k * math.sqrt(1 - zeta**2)), rel=1e-9)
    # half-power points from the closed form: (k - m w^2)^2 + (d w)^2 = 2 / |H|max^2, a quadratic in w^2
    target = 2.0 / peak.magnitude**2
    roots = np.roots([m**2, d**2 - 2 * k * m, k**2 - target])
    w1, w2 = np.sqrt(np.sort(roots.real))
    assert peak.damping_ratio == pytest.approx((w2 - w1) / (2 * wn * math.sqrt(1 - 2 * zeta**2)), rel=1e-6)
    assert abs(peak.damping_ratio - zeta) <= zeta**2  # the half-power estimate itself is good to O(zeta^2)
    assert result.anti_resonances == ()


def test_car_transmissibility_is_the_quarter_car_closed_form():
    car = get_scene("car")
    params = car.resolve(car.scenario("road_bump"), {})
    ms, ks, cs = params["mass"] / 4, params["stiffness"] / 4, params["damping"] / 4
    mu, kt = params["unsprung_mass"], params["tire_stiffness"]
    result = springlab.frequency("car", points=150, integrators=())
    assert (result.input, result.response) == ("road", "heave")
    s = 2j * np.pi * result.frequencies_hz
    body = ms * s**2 + cs * s + ks
    wheel = mu * s**2 + cs * s + ks + kt
    closed = kt * (cs * s + ks) / (body * wheel - (cs * s + ks) ** 2)
    a = np.zeros((4, 4))
    a[0, 2] = a[1, 3] = 1.0
    a[2] = [-ks / ms, ks / ms, -cs / ms, cs / ms]
    a[3] = [ks / mu, -(ks + kt) / mu, cs / mu, -cs / mu]
    tol = math.sqrt(EPS) * _kappa(a, s)
    assert np.max(np.abs(result.exact / closed - 1.0)) <= tol
    assert len(result.resonances) == 2  # body bounce and wheel hop


def _held_sine_response(phi, gamma, c, dt, f):
    """c (z I - Phi)^-1 gamma z^(1/2): the response to a sine sampled at mid-step and held (numpy only)."""
    z = np.exp(2j * np.pi * f * dt)
    n = phi.shape[0]
    return np.array([c @ np.linalg.solve(zi * np.eye(n) - phi, gamma) * np.sqrt(zi) for zi in z])


def test_rk4_discrete_response_is_its_stability_polynomial_on_the_diagonalised_quarter_car():
    car = get_scene("car")
    params = car.resolve(car.scenario("road_bump"), {})
    ms, ks, cs = params["mass"] / 4, params["stiffness"] / 4, params["damping"] / 4
    mu, kt = params["unsprung_mass"], params["tire_stiffness"]
    dt = 2e-3
    result = springlab.frequency("car", integrator="rk4", dt=dt, band=(0.5, 100.0), points=80, integrators=())
    a = np.zeros((4, 4))
    a[0, 2] = a[1, 3] = 1.0
    a[2] = [-ks / ms, ks / ms, -cs / ms, cs / ms]
    a[3] = [ks / mu, -(ks + kt) / mu, cs / mu, -cs / mu]
    b = np.array([0.0, 0.0, 0.0, kt / mu])
    c = np.array([1.0, 0.0, 0.0, 0.0])
    lam, v = np.linalg.eig(a)
    w = np.linalg.inv(v)
    hl = dt * lam
    amplification = 1 + hl + hl**2 / 2 + hl**3 / 6 + hl**4 / 24  # RK4's stability polynomial R(h lambda)
    forcing = dt * (1 + hl / 2 + hl**2 / 6 + hl**3 / 24)  # what a held input adds over one step, per mode
    z = np.exp(2j * np.pi * result.frequencies_hz * dt)
    modal = (c @ v) * (w @ b) * forcing
    derived = np.array([np.sum(modal / (zi - amplification)) * np.sqrt(zi) for zi in z])
    phi = (v * amplification) @ w
    tol = math.sqrt(EPS) * _kappa(phi.real, z) * np.linalg.cond(v)
    assert np.max(np.abs(result.discrete / derived - 1.0)) <= tol
    # and the error against the exact response grows as the input's hold and RK4 predict: (omega dt)^2 / 24
    assert result.relative_error[0] <= (2 * np.pi * 0.5 * dt) ** 2


@pytest.mark.parametrize("zeta", [0.0, 0.05], ids=["undamped", "damped"])
def test_euler_discrete_response_is_mujocos_semi_implicit_euler(zeta):
    """MuJoCo's 'euler' is semi-implicit: v+ = (m v + h (u - k q)) / (m + h d) (joint damping implicit,
    its default eulerdamp), then q+ = q + h v+."""
    dt = 1e-3
    result, m, d, k = _slider(zeta, integrator="euler", dt=dt)
    h = dt
    phi = np.array([[1 - h * h * k / (m + h * d), h * m / (m + h * d)], [-h * k / (m + h * d), m / (m + h * d)]])
    gamma = np.array([h * h / (m + h * d), h / (m + h * d)])
    derived = _held_sine_response(phi, gamma, np.array([1.0, 0.0]), dt, result.frequencies_hz)
    z = np.exp(2j * np.pi * result.frequencies_hz * dt)
    tol = ROUNDING * EPS * _kappa(phi, z)
    assert np.max(np.abs(result.discrete / derived - 1.0)) <= tol
    # first order: the error at the band's top is O(omega dt), far above RK4's at the same setting
    rk4, *_ = _slider(zeta, integrator="rk4", dt=dt)
    assert result.relative_error[-1] > 10 * rk4.relative_error[-1]


def test_band_within_tol_and_largest_dt_keep_their_promise():
    result = springlab.frequency("slider", band=(0.1, 10.0), points=60, integrators=("rk4",), dt=1e-3)
    lo, hi = result.within_tol_hz
    assert lo == pytest.approx(0.1) and result.covers_band == (hi >= 10.0)
    (rk4,) = result.integrators
    checked = springlab.frequency("slider", band=(0.1, 10.0), points=60, integrators=(), dt=rk4.max_dt_s)
    assert checked.covers_band and np.max(checked.relative_error) <= result.tol
    coarser = springlab.frequency("slider", band=(0.1, 10.0), points=60, integrators=(), dt=1.01 * rk4.max_dt_s)
    assert not coarser.covers_band


def test_result_serialises_and_tables():
    result, *_ = _slider(0.05)
    data = json.loads(json.dumps(result.to_dict()))
    assert len(data["frequencies_hz"]) == 120 and data["resonances"][0]["damping_ratio"] > 0
    frame = result.to_pandas()
    assert list(frame.columns)[:3] == ["frequency_hz", "exact_magnitude", "exact_phase_deg"]
    with pytest.raises(AttributeError):
        result.dt = 1.0


@pytest.mark.parametrize(
    "argv, words",
    [
        (["slider", "--input", "nope"], "unknown input"),
        (["slider", "--response", "nope"], "unknown response"),
        (["slider", "--band", "1:1"], "empty"),
        (["slider", "--band", "5:1"], "inverted"),
        (["slider", "--band", "1"], "FMIN:FMAX"),
        (["slider", "--band", "1:150"], "Nyquist"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(argv, words, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["frequency", *argv, "--output", str(out)]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and words in lines[0] and captured.out == ""
    assert not out.exists()


def test_command_writes_json_csv_and_bode(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["frequency", "slider", "--band", "0.1:10", "--points", "40", "--dt", "1e-3", "--output", str(out)])
    data = json.loads((out / "frequency.json").read_text())
    assert code == (0 if data["covers_band"] else 1)
    assert (out / "bode.png").stat().st_size > 0
    header = (out / "frequency.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "frequency_hz" and "relative_error" in header
    assert {b["integrator"] for b in data["integrators"]} == {"euler", "implicit", "implicitfast", "rk4", "discrete"}
    assert "reproduces" in capsys.readouterr().out


def test_an_unwritable_output_fails_before_any_computing(tmp_path, capsys, monkeypatch):
    def must_not_run(*args, **kwargs):
        raise AssertionError("computed before checking --output")

    monkeypatch.setattr("springlab.cli.commands.frequency.run_frequency", must_not_run)
    blocker = tmp_path / "file"
    blocker.write_text("a file, not a folder")
    assert main(["frequency", "slider", "--output", str(blocker / "sub")]) == 2
    assert "cannot write into output directory" in capsys.readouterr().err


def test_sinestream_in_mujoco_matches_the_discrete_response_within_its_stated_accuracy():
    """24 sines from the band's bottom to an octave above it: each MuJoCo estimate within the demodulation's
    stated accuracy (plus the discrete response's own finite-difference error) of the one-step map's response,
    and at the top, above the band, exact and discrete part by far more than that, and the estimate follows
    the discrete one."""
    result = springlab.frequency("printer_head", band=(20.0, 400.0), points=40, integrators=(), sines=24)
    stream = result.sinestream
    assert len(stream.frequencies_hz) == 24 and stream.frequencies_hz[-1] > result.band_hz[1]
    assert np.all(stream.error_vs_discrete <= stream.bound) and stream.agrees
    parted = np.abs(stream.discrete / stream.exact - 1.0)
    assert parted[-1] > 1e3 * stream.bound[-1]
    assert np.abs(stream.estimate[-1] / stream.exact[-1] - 1.0) == pytest.approx(parted[-1], rel=1e-3)
    assert json.loads(json.dumps(result.to_dict()))["sinestream"]["agrees"] is True


def test_sinestream_refuses_a_joint_acceleration_response():
    with pytest.raises(springlab.BadInputError, match="accelerometer"):
        springlab.frequency("slider", response="slider:acc", integrators=(), sines=4)


@pytest.mark.parametrize(
    "option, text, typed",
    [
        ("band", "0.1:10", "band=(0.1, 10.0)"),
        ("amplitudes", "0.5,2", "amplitudes=(0.5, 2.0)"),
        ("integrators", "rk4", "integrators=['rk4'"),
    ],
)
def test_the_library_refuses_the_command_lines_strings_and_names_the_typed_form(option, text, typed):
    with pytest.raises(BadInputError, match=re.escape(typed)):
        springlab.frequency("slider", **{option: text})


def test_one_linearization_and_one_map_per_setting_at_the_operating_point(monkeypatch):
    """The model is held at its operating point once (springlab.exact.model_at_point): one linearization, one
    eig(A), and each one-step map differenced once per (integrator, dt, step), though the band's bisection in
    frequency, the sinestream (two amplitudes, and its uncertainty at twice the step) ask for them again.
    Counted with cProfile, which sees every call whatever imported the function."""
    import cProfile
    import pstats

    from springlab.exact import linearize as linearize_module
    from springlab.exact import model_at_point

    asked = []
    differenced = model_at_point.map_on

    def map_on(work, kind, dt, point, **options):
        asked.append((kind, dt, options.get("step")))
        return differenced(work, kind, dt, point, **options)

    monkeypatch.setattr(model_at_point, "map_on", map_on)
    profile = cProfile.Profile()
    profile.enable()
    # euler at 0.5 ms misses tol inside the band: the band's edge is bisected in frequency at that one setting
    result = springlab.frequency(
        "slider", integrator="euler", dt=5e-4, band=(0.1, 3.0), points=20, integrators=(), sines=4, amplitudes=(0.5, 2)
    )
    profile.disable()
    assert result.within_tol_hz is not None and result.within_tol_hz[1] < 3.0  # the bisection ran
    calls: dict[str, int] = {}
    for (filename, _, name), (count, *_) in pstats.Stats(profile).stats.items():
        if filename == linearize_module.__file__ or ("numpy" in filename and "linalg" in filename and name == "eig"):
            calls[name] = calls.get(name, 0) + count
    assert calls["linearize"] == 1
    assert calls["eig"] == 1  # the settling time of both sinestreams reads the one eigenbasis
    assert calls["input_column"] == 1
    step = linearize_module.FD_STEP
    euler = int(mujoco.mjtIntegrator.mjINT_EULER)
    assert sorted(set(asked)) == sorted(asked) == [(euler, 5e-4, step), (euler, 5e-4, 2 * step)]
    assert calls["map_on"] == calls["step_input_column"] == len(asked)


_TWO_MASSES = """<mujoco>
  <worldbody>
    <body name="a"><joint name="near" type="slide" axis="1 0 0" stiffness="100"/>
      <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
      <body name="b"><joint name="far" type="slide" axis="1 0 0" stiffness="50"/>
        <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></body>
  </worldbody>
  <actuator><motor name="push" joint="near"/></actuator>
  <sensor><jointpos name="gauge" joint="far"/><framepos name="where" objtype="body" objname="b"/></sensor>
</mujoco>"""


@pytest.mark.parametrize(
    "names, missing, listed",
    [
        (
            [],
            "--input, one of: push, near:force, far:force; and --response, one of:",
            "far:acc, gauge, gauge[0], where[0]",
        ),
        (["--input", "push"], "--response, one of: near, near:vel, near:acc, far,", "where[2]"),
        (["--response", "far"], "--input, one of: push, near:force, far:force", ""),
    ],
)
def test_a_model_without_declared_names_lists_its_inputs_and_responses(names, missing, listed, tmp_path, capsys):
    """A model file declares no input or response: the one-line error lists the names the model takes (its
    actuators, each joint's force; each joint's position, velocity, acceleration and every sensor component)."""
    model = tmp_path / "two.xml"
    model.write_text(_TWO_MASSES)
    assert main(["frequency", str(model), *names]) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and captured.out == ""
    assert "declares no default" in lines[0] and missing in lines[0] and listed in lines[0]
    assert ("--input" in lines[0]) == ("--input" not in names) and ("--response" in lines[0]) == (
        "--response" not in names
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["two.xml"]
