"""springlab frequency on non-linear models and with more inputs and responses (issue 23 item 4 and the inputs and
responses of its Build line): amplitude dependence, the Duffing jump against first-order harmonic balance,
joint-force inputs and sensor responses.

References are independent of the code under test: the harmonic-balance relation
[(k - m w^2 + 3/4 k3 a^2)^2 + (c w)^2] a^2 = F^2 is solved here with numpy.roots from the parameters the test
sets (not read back from the model), and its folds are found here by counting its real roots on a grid. The
bound on harmonic balance is the one springlab.exact.harmonic_balance derives (the neglected third harmonic
r3 = (k3 a^2 / 4) / |k + 3/2 k3 a^2 - 9 m w^2 + 3 j c w| perturbs the cubic coefficient by the relative r3;
twice the amplitude's move under that perturbation), computed here by re-solving the perturbed relation rather
than by the module's implicit derivative.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

import springlab
from springlab.cli.main import main

M, C, K, K3 = 1.0, 1.0, 100.0, 1e4  # kg, N s/m, N/m, N/m^3: zeta = 0.05, hardening
FORCE = 2.0  # N: k3 a^2 / k reaches 1.7 on the upper branch, the three-root band is 1.99-2.42 Hz
DUFFING = {"k1": K, "k3": K3, "damping": C, "mass": M}
DT = 0.005  # s: RK4, omega dt <= 0.1 over the band; the integrator's own error is far below the bound
BAND = (1.5, 3.0)
SWEEP_POINTS = 16  # 0.1 Hz apart


def _roots(force: float, omega: float, k3: float = K3) -> np.ndarray:
    """Positive first-harmonic amplitudes a [m] of the relation, ascending (numpy.roots in A = a^2)."""
    k0 = K - M * omega**2
    kappa = 0.75 * k3
    roots = np.roots([kappa**2, 2 * kappa * k0, k0**2 + (C * omega) ** 2, -(force**2)])
    real = roots[(np.abs(roots.imag) <= 1e-9 * np.abs(roots)) & (roots.real > 0)].real
    return np.sort(np.sqrt(real))


def _fold_band(force: float, k3: float = K3) -> tuple[float, float]:
    """(f_low, f_high) [Hz]: where the relation has three roots, by root counting on a 1e-5 Hz grid near the
    folds (found first on a coarse grid)."""
    coarse = np.linspace(1.0, 4.0, 3001)
    three = np.array([len(_roots(force, 2 * math.pi * f, k3)) == 3 for f in coarse])
    inside = np.nonzero(three)[0]
    edges = []
    for lo, hi in ((coarse[inside[0] - 1], coarse[inside[0]]), (coarse[inside[-1]], coarse[inside[-1] + 1])):
        fine = np.linspace(lo, hi, 101)
        counts = np.array([len(_roots(force, 2 * math.pi * f, k3)) for f in fine])
        change = np.nonzero(np.diff(counts))[0][0]
        edges.append(0.5 * (fine[change] + fine[change + 1]))
    return edges[0], edges[1]


def _r3(a: float, omega: float) -> float:
    return abs(0.25 * K3 * a**2) / abs(complex(K + 1.5 * K3 * a**2 - 9 * M * omega**2, 3 * C * omega))


def _hb_bound(force: float, a: float, omega: float) -> float:
    """Twice the move of the root nearest a when k3 becomes k3 (1 +- r3)."""
    r3 = _r3(a, omega)
    moved = []
    for sign in (-1.0, 1.0):
        roots = _roots(force, omega, K3 * (1 + sign * r3))
        moved.append(abs(roots[np.argmin(np.abs(roots - a))] - a))
    return 2.0 * max(moved)


def _rk4_error(f: float) -> float:
    """|H_rk4 / H_zoh - 1| of the linearization m x'' + c x' + k x = u at f [Hz]: RK4's one-step map from its
    stability polynomial and held-input polynomial against the exact zero-order hold (scipy.linalg.expm), the
    integrator's own error on top of the hold that the force's sinc(omega dt / 2) accounts for."""
    from scipy.linalg import expm

    a = np.array([[0.0, 1.0], [-K / M, -C / M]])
    b = np.array([0.0, 1.0 / M])
    ha = a * DT
    eye = np.eye(2)
    phi = eye + ha + ha @ ha / 2 + ha @ ha @ ha / 6 + ha @ ha @ ha @ ha / 24
    gamma = DT * (eye + ha / 2 + ha @ ha / 6 + ha @ ha @ ha / 24) @ b
    big = expm(np.block([[a, b[:, None]], [np.zeros((1, 3))]]) * DT)
    phi_zoh, gamma_zoh = big[:2, :2], big[:2, 2]
    z = np.exp(2j * np.pi * f * DT)
    rk4 = np.linalg.solve(z * eye - phi, gamma)[0]
    zoh = np.linalg.solve(z * eye - phi_zoh, gamma_zoh)[0]
    return float(abs(rk4 / zoh - 1.0))


@pytest.fixture(scope="module")
def duffing_sweep():
    """The hardening Duffing oscillator swept up and down at FORCE, continuation from sine to sine."""
    return springlab.frequency(
        "nonlinear",
        input="force",
        response="block",
        **DUFFING,
        band=BAND,
        points=20,
        integrators=(),
        dt=DT,
        sines=SWEEP_POINTS,
        amplitudes=(FORCE,),
        sweep="both",
    )


def test_duffing_branches_follow_harmonic_balance_within_the_third_harmonic_bound(duffing_sweep):
    """At every swept frequency the measured first-harmonic amplitude is within the derived bound of the
    harmonic-balance root it is on, plus the run's own settling residue (twice) and RK4's own error on the
    linearization; the held input's sinc(omega dt / 2) is folded into the force."""
    up, down = duffing_sweep.sweeps
    assert (up.direction, down.direction) == ("up", "down")
    for branch in (up, down):
        for f, measured, residue in zip(branch.frequencies_hz, branch.response_amplitude, branch.residue):
            omega = 2 * math.pi * f
            force = FORCE * np.sinc(f * DT)
            roots = _roots(force, omega)
            root = roots[np.argmin(np.abs(np.log(roots / measured)))]
            allowed = _hb_bound(force, root, omega) + (2 * residue + _rk4_error(f)) * measured
            assert abs(measured - root) <= allowed
        assert branch.agrees


def test_duffing_sweeps_jump_at_the_harmonic_balance_folds(duffing_sweep):
    """Up jumps down after the upper fold, down jumps up after the lower fold; each measured jump interval
    (consecutive swept frequencies) holds its fold, within the fold's own first-order uncertainty (k3 moved by
    twice r3 at the fold)."""
    up, down = duffing_sweep.sweeps
    low, high = _fold_band(FORCE)
    a_fold = float(np.median(_roots(FORCE, 2 * math.pi * high * (1 - 1e-6))))
    r3 = _r3(a_fold, 2 * math.pi * high)
    widen = max(
        abs(_fold_band(FORCE, K3 * (1 + s * 2 * r3))[i] - f) for s in (-1, 1) for i, f in enumerate((low, high))
    )
    assert up.jump_hz is not None and down.jump_hz is not None
    assert up.jump_hz[0] - widen <= high <= up.jump_hz[1] + widen
    assert down.jump_hz[0] - widen <= low <= down.jump_hz[1] + widen
    # the jump is the branch's largest step between neighbouring frequencies: up falls from the upper branch, down
    # rises onto it; read in ascending frequency both are falls (a hardening spring's upper branch lies left)
    for branch, sign in ((up, -1.0), (down, -1.0)):
        order = np.argsort(branch.frequencies_hz)
        f, a = branch.frequencies_hz[order], branch.response_amplitude[order]
        steps = np.diff(np.log(a))
        largest = int(np.argmax(np.abs(steps)))
        assert (f[largest], f[largest + 1]) == branch.jump_hz and np.sign(steps[largest]) == sign
    step_up = dict(zip(up.frequencies_hz, up.response_amplitude))
    step_down = dict(zip(down.frequencies_hz, down.response_amplitude))
    # outside the three-root band the branches are one curve
    for f, a in step_up.items():
        if f < low or f > high:
            assert a == pytest.approx(step_down[f], rel=1e-2)
    lines = "\n".join(duffing_sweep.verdict())
    assert "harmonic balance predicts the jump" in lines and "jumps between" in lines


def _fold(d, force_at, bracket: tuple[float, float], upper: bool) -> float:
    """The fold [Hz] inside `bracket` of the relation of the oscillator d (m, c, k, k3) under the force amplitude
    force_at(f) [N]: where P(A) = [(k - m w^2 + 3/4 k3 A)^2 + (c w)^2] A - F^2 touches zero at one of its critical
    points P'(A) = 0 (the upper fold at the larger one, a hardening spring's local minimum; the lower fold at the
    smaller one), solved by brentq on P(A_crit(w), w): no discriminant, no root following."""
    from scipy.optimize import brentq

    kappa = 0.75 * d.k3

    def touching(f: float) -> float:
        omega = 2 * math.pi * f
        k0 = d.k - d.m * omega**2
        # P'(A) = 3 kappa^2 A^2 + 4 kappa k0 A + k0^2 + (c w)^2 = 0
        disc = 16 * kappa**2 * k0**2 - 12 * kappa**2 * (k0**2 + (d.c * omega) ** 2)
        a_crit = (-4 * kappa * k0 + (1 if upper else -1) * math.sqrt(max(disc, 0.0))) / (6 * kappa**2)
        return ((k0 + kappa * a_crit) ** 2 + (d.c * omega) ** 2) * a_crit - force_at(f) ** 2

    return brentq(touching, *bracket, xtol=1e-15, rtol=1e-15)


def test_duffing_folds_take_the_held_force_at_their_own_frequency(duffing_sweep):
    """Each branch's fold solves the harmonic-balance relation with the held sine's first harmonic,
    F sinc(omega dt / 2), evaluated at the fold itself (issue 34: it was evaluated at the band's centre). The
    reference, the relation's critical point touching zero, is solved here with the oscillator read back from
    the model; both sides are brentq solutions to ~1e-13 relative, so 1e-10 tells the two evaluations apart:
    the band-centre force moves these folds by 2.8e-6 and 2.0e-5 relative."""
    d = duffing_sweep.duffing
    up, down = duffing_sweep.sweeps
    force = d.gain * FORCE
    low, high = _fold_band(FORCE)  # the folds under the unheld force, 1e-5 Hz; the hold moves them ~1e-4 Hz

    def held(f: float) -> float:
        return force * np.sinc(f * DT)

    def at_centre(f: float) -> float:
        return force * np.sinc(math.sqrt(BAND[0] * BAND[1]) * DT)

    for branch, upper, guess in ((up, True, high), (down, False, low)):
        bracket = (guess - 1e-2, guess + 1e-2)
        expected = _fold(d, held, bracket, upper)
        assert branch.fold_hz is not None
        assert branch.fold_hz[0] == pytest.approx(expected, rel=1e-10, abs=0)
        assert abs(_fold(d, at_centre, bracket, upper) / expected - 1) > 1e-8


def test_sinestream_amplitudes_coincide_on_the_linear_slider_and_part_on_the_duffing_spring():
    """The slider is linear: its estimates at 0.5 N and 2 N per newton agree within the sum of their stated
    demodulation accuracies. The hardening spring's, at its resonance, part by orders of magnitude more."""
    linear = springlab.frequency("slider", band=(0.5, 3.0), integrators=(), points=20, sines=4, amplitudes=(0.5, 2.0))
    small, large = linear.sinestreams
    assert (small.amplitude, large.amplitude) == (0.5, 2.0)
    assert np.all(np.abs(large.estimate / small.estimate - 1.0) <= small.accuracy + large.accuracy)
    assert "coincide" in "\n".join(linear.verdict())
    duffing = springlab.frequency(
        "nonlinear",
        input="force",
        response="block",
        **DUFFING,
        band=(1.4, 1.8),
        integrators=(),
        points=10,
        dt=DT,
        sines=2,
        amplitudes=(0.05, 1.0),
    )
    small, large = duffing.sinestreams
    # at 1.4 Hz, below the bent resonance (the second sine is an octave above the band, where both are small)
    assert abs(large.estimate[0] / small.estimate[0] - 1.0) > 1e3 * (small.accuracy[0] + large.accuracy[0])
    assert "depends on the amplitude" in "\n".join(duffing.verdict())


_SENSED = """<mujoco>
  <option timestep="0.002" integrator="RK4" gravity="0 0 0"/>
  <worldbody><body name="block"><joint name="x" type="slide" axis="1 0 0" stiffness="800" damping="4"/>
    <geom type="box" size="0.05 0.05 0.05" mass="2"/><site name="s"/></body></worldbody>
  <actuator><motor name="drive" joint="x" gear="1"/></actuator>
  <sensor><jointpos name="xs" joint="x"/><accelerometer name="acc" site="s"/></sensor>
</mujoco>"""


@pytest.fixture(scope="module")
def sensed():
    return mujoco.MjModel.from_xml_string(_SENSED)


SLIDER = {"mass": 2.0, "stiffness": 800.0, "damping": 4.0}  # the sensed model's block too


def _tolerance(f: np.ndarray, dt: float) -> float:
    """ROUNDING eps kappa, kappa = max over f of ||X|| ||(x I - X)^-1|| for the continuous (X = A, x = j w) and
    the one-step (X = expm(A dt), x = exp(j w dt)) system of the 2 kg, 800 N/m, 4 N s/m block: two routes to
    the same linear model's H differ only by rounding in entries computed by centred differences of a linear
    function (test_frequency.py's argument)."""
    from scipy.linalg import expm

    m, k, d = SLIDER["mass"], SLIDER["stiffness"], SLIDER["damping"]
    a = np.array([[0.0, 1.0], [-k / m, -d / m]])
    phi = expm(a * dt)
    kappa = 0.0
    for w in 2 * np.pi * np.asarray(f):
        for x, mat in ((1j * w, a), (np.exp(1j * w * dt), phi)):
            kappa = max(kappa, np.linalg.norm(mat, 2) * np.linalg.norm(np.linalg.inv(x * np.eye(2) - mat), 2))
    return 1e3 * float(np.finfo(float).eps) * kappa


def test_a_jointpos_sensor_response_is_the_joint_position_and_an_accelerometer_its_acceleration(sensed):
    """The jointpos sensor's row from mjd_transitionFD's C picks the joint's position: the same exact and
    discrete responses as the joint, and the same sinestream estimate (both simulated at the same setting:
    within the two stated accuracies). The accelerometer (gravity off) reads the joint's acceleration."""
    kwargs = {"input": "drive", "band": (0.5, 20.0), "points": 30, "integrators": (), "sines": 4}
    joint = springlab.frequency(sensed, response="x", **kwargs)
    sensor = springlab.frequency(sensed, response="xs", **kwargs)
    tol = _tolerance(joint.frequencies_hz, joint.dt)
    assert sensor.units["response"] == "m"
    assert np.max(np.abs(sensor.exact / joint.exact - 1.0)) <= tol
    assert np.max(np.abs(sensor.discrete / joint.discrete - 1.0)) <= tol
    a, b = joint.sinestream, sensor.sinestream
    assert np.all(np.abs(b.estimate / a.estimate - 1.0) <= a.accuracy + b.accuracy)
    assert sensor.sinestream.agrees
    acc = springlab.frequency(sensed, response="acc[0]", input="drive", band=(0.5, 20.0), points=30, integrators=())
    joint_acc = springlab.frequency(
        sensed, response="x:acc", input="drive", band=(0.5, 20.0), points=30, integrators=()
    )
    # the accelerometer's rows are centred differences of a linear function too
    assert np.max(np.abs(acc.exact / joint_acc.exact - 1.0)) <= tol
    assert acc.units["response"] == "m/s^2"


def test_a_joint_force_input_is_the_motor_with_gear_one():
    """The slider's motor has gear 1: a force on the joint (qfrc_applied) is the same input, in the
    linearization (exact and discrete) and in MuJoCo's sinestream."""
    kwargs = {"band": (0.5, 20.0), "points": 30, "integrators": (), "sines": 4, **SLIDER}
    motor = springlab.frequency("slider", input="force", **kwargs)
    joint = springlab.frequency("slider", input="slider:force", **kwargs)
    assert joint.units["input"] == motor.units["input"] == "N"
    tol = _tolerance(motor.frequencies_hz, motor.dt)
    assert np.max(np.abs(joint.exact / motor.exact - 1.0)) <= tol
    assert np.max(np.abs(joint.discrete / motor.discrete - 1.0)) <= tol
    a, b = motor.sinestream, joint.sinestream
    assert np.all(np.abs(b.estimate / a.estimate - 1.0) <= a.accuracy + b.accuracy)
    assert joint.sinestream.agrees


@pytest.mark.parametrize(
    "args, words",
    [
        (["slider", "--response", "nosuch"], "valid: slider, slider:acc, slider:vel"),
        (["slider", "--input", "nosuch:force"], "slider:force"),
        (["slider", "--sinestream", "3", "--amplitude", "two"], "--amplitude takes"),
        (["slider", "--sinestream", "3", "--amplitude", "-1"], "amplitudes must be finite numbers > 0"),
        (["slider", "--sweep", "sideways"], "invalid choice"),
    ],
)
def test_bad_names_and_amplitudes_exit_2_with_one_line(args, words, capsys, tmp_path):
    out = tmp_path / "out"
    assert main(["frequency", *args, "--output", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and words in err
    assert not out.exists()


def test_an_unknown_sensor_lists_the_sensors_and_their_components(sensed):
    with pytest.raises(springlab.BadInputError) as caught:
        springlab.frequency(sensed, input="drive", response="nosuch", integrators=())
    message = str(caught.value)
    assert "xs" in message and "acc[0]" in message and "acc[2]" in message and "x:vel" in message


def test_the_cubic_oscillator_is_read_from_the_model_and_another_spring_is_not_one(duffing_sweep):
    """m, c, k, k3 read back from MuJoCo's forward dynamics are the parameters the test set (a cubic fit of a
    cubic force only rounds); a spring with a quadratic term is not the relation's form: no comparison."""
    from springlab.exact.harmonic_balance import cubic_oscillator
    from springlab.exact.linearize import OperatingPoint

    found = duffing_sweep.duffing
    assert (found.m, found.c, found.k, found.k3, found.gain) == pytest.approx((M, C, K, K3, 1.0), rel=1e-9)
    quadratic = mujoco.MjModel.from_xml_string(
        '<mujoco><option gravity="0 0 0"/><worldbody><body><joint name="x" type="slide" stiffness="100 50 1e4"'
        ' damping="1"/><geom size="0.1" mass="1"/></body></worldbody><actuator><motor joint="x"/></actuator>'
        "</mujoco>"
    )
    assert cubic_oscillator(quadratic, OperatingPoint.at(quadratic), "ctrl", 0, 0.1) is None
