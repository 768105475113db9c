"""The resonance test on the printer head: a chirp through the motor, the carriage accelerometer, the fitted belt.

One raw MuJoCo run (mujoco.rollout, no scene API) of a 2 s linear chirp of 1 N from 50 to 400 Hz; its
accelerometer record is noiseless, and each test adds a seeded generator's Gaussian noise to it (the sensor's
noise does not act on the physics, so one run serves every seed). References built here: the two-mass model's
exact motion by scipy.linalg.expm stepped with the held force, the carriage's acceleration from the belt's
force (k s + c s') / m_c; the true belt mode from the masses and the belt.
"""

import math

import mujoco
import numpy as np
import pytest
import scipy.linalg
from mujoco import rollout

import springlab.sim.model_files
from springlab.exact import positioning, resonance, shaping
from springlab.scenes.printer_head import control

EPS = np.finfo(float).eps
DT = 1e-4
EVERY = 3  # accelerometer samples every 3 steps: 3.3 kHz, an ADXL345's rate class
BAND = (50.0, 400.0)
NOISE = 0.5  # sensor noise [m/s^2] per sample, the order of a MEMS accelerometer read at kHz rates


@pytest.fixture(scope="module")
def chirp_run():
    """(model, force per step [N], accelerometer [m/s^2] at every step) of the chirp from rest."""
    spec = mujoco.MjSpec.from_file(str(springlab.sim.model_files.path("printer_head")))
    control.add_instruments(spec)
    model = spec.compile()
    model.opt.timestep = DT
    force = resonance.chirp(1.0, *BAND, 2.0, DT)
    data = mujoco.MjData(model)
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    _, sensors = rollout.rollout(model, data, state, force[None, :, None])
    address = model.sensor(control.ACCELEROMETER).adr[0]  # its first axis: along the rail
    return model, force, sensors[0, :, address]


def _truth(model):
    """(m_c, m_m, k, c, omega_n [rad/s], zeta [-]) of the model."""
    m_c, m_m = model.body("carriage").mass[0], model.body("motor").mass[0]
    k, c = model.tendon_stiffness[0], model.tendon_damping[0]
    mu = m_c * m_m / (m_c + m_m)
    return m_c, m_m, k, c, math.sqrt(k / mu), c / (2 * math.sqrt(k * mu))


def _expm_acceleration(m_c, m_m, k, c, force):
    """The carriage's acceleration [m/s^2] at the start of each step, the force held over each step (expm)."""
    a = np.array(
        [[0, 0, 1, 0], [0, 0, 0, 1], [-k / m_c, k / m_c, -c / m_c, c / m_c], [k / m_m, -k / m_m, c / m_m, -c / m_m]]
    )
    block = np.zeros((5, 5))
    block[:4, :4], block[3, 4] = a * DT, DT / m_m
    step = scipy.linalg.expm(block)
    x, out = np.zeros(4), np.empty(len(force))
    for j, f in enumerate(force):
        out[j] = (k * (x[1] - x[0]) + c * (x[3] - x[2])) / m_c
        x = step[:4, :4] @ x + step[:4, 4] * f
    return out


def _expm_envelope(m_c, m_m, k, c, segments):
    """The carriage's ring-down envelope [m] after force segments [(duration [s], force [N]), ...] from rest."""
    a = np.zeros((5, 5))
    a[:4, :4] = [
        [0, 0, 1, 0],
        [0, 0, 0, 1],
        [-k / m_c, k / m_c, -c / m_c, c / m_c],
        [k / m_m, -k / m_m, c / m_m, -c / m_m],
    ]
    a[3, 4] = 1 / m_m
    x = np.zeros(5)
    for duration, f in segments:
        x[4] = f
        x = scipy.linalg.expm(a * duration) @ x
    mu = m_c * m_m / (m_c + m_m)
    omega, zeta = math.sqrt(k / mu), c / (2 * math.sqrt(k * mu))
    stretch, rate = x[1] - x[0], x[3] - x[2]
    return m_m / (m_c + m_m) * math.hypot(stretch, (rate + zeta * omega * stretch) / (omega * math.sqrt(1 - zeta**2)))


def _rk4_acceleration_bound(model, force):
    """Bound [m/s^2] per step on RK4's error in the carriage acceleration
    (tests/scenes/printer_head/test_printer_shaping.py's argument: each step adds |R(z) - e^z| |eta - eta_eq| to the
    belt mode's coordinate, which decays by |R(z)| per step after; the acceleration is
    -Re((omega^2 + 2 zeta omega s) eta))."""
    m_c, m_m, k, c, omega, zeta = _truth(model)
    s = complex(-zeta * omega, omega * math.sqrt(1 - zeta**2))
    z = s * DT
    per_step = abs(z) ** 5 / 120 / (1 - abs(z) / 6)
    decay = abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)
    total = m_c + m_m
    a = np.array(
        [[0, 0, 1, 0], [0, 0, 0, 1], [-k / m_c, k / m_c, -c / m_c, c / m_c], [k / m_m, -k / m_m, c / m_m, -c / m_m]]
    )
    block = np.zeros((5, 5))
    block[:4, :4], block[3, 4] = a * DT, DT / m_m
    step = scipy.linalg.expm(block)
    x, error, out = np.zeros(4), 0.0, np.empty(len(force))
    for j, f in enumerate(force):
        out[j] = abs(omega**2 + 2 * zeta * omega * s) * error
        # the carriage's deviation from the centre of mass and its rate; the equilibrium under the held force
        deviation = x[0] - (m_c * x[0] + m_m * x[1]) / total
        rate = x[2] - (m_c * x[2] + m_m * x[3]) / total
        offset = deviation + f / (total * omega**2)
        distance = abs(complex(offset, -(rate + zeta * omega * offset) / s.imag))
        error = decay * error + per_step * distance
        x = step[:4, :4] @ x + step[:4, 4] * f
    return out


def test_mujoco_accelerometer_is_the_exact_accelerance(chirp_run):
    model, force, measured = chirp_run
    m_c, m_m, k, c, omega, zeta = _truth(model)
    exact = _expm_acceleration(m_c, m_m, k, c, force)
    bound = _rk4_acceleration_bound(model, force)
    assert np.all(
        np.abs(measured - exact) <= bound + 64 * EPS * np.max(np.abs(exact)) * np.sqrt(np.arange(1, len(force) + 1))
    )
    # the fit's model (a 2-state ZOH filter) is the same motion, to round-off
    fitted_model = resonance.accelerance_response(force, DT, 1, omega, zeta, 1 / (m_c + m_m))
    assert np.max(np.abs(fitted_model - exact)) <= 1e-9 * np.max(np.abs(exact))


def _fit(force, acceleration, seed):
    rng = np.random.default_rng(seed)
    samples = acceleration[::EVERY]
    return resonance.fit_resonance(force, samples + NOISE * rng.standard_normal(samples.size), DT, EVERY, BAND)


def _sensitivity(model, force):
    """G = (J^T J)^-1 J^T of the sampled record in theta = (omega, zeta, 1 / M) at the truth (the test's expm)."""
    m_c, m_m, k, c, omega, zeta = _truth(model)
    columns = []
    for j, relative in enumerate((1e-6, 1e-5, 1e-6)):
        theta = np.array([omega, zeta, 1 / (m_c + m_m)])
        records = []
        for sign in (1, -1):
            t = theta.copy()
            t[j] *= 1 + sign * relative
            # back to the two-mass model: 1 / M sets M (m_c : m_m kept), omega sets k, zeta sets c
            total = 1 / t[2]
            carriage, motor = m_c * total / (m_c + m_m), m_m * total / (m_c + m_m)
            reduced = carriage * motor / total
            stiffness, damping = reduced * t[0] ** 2, 2 * t[1] * t[0] * reduced  # omega^2 mu, 2 zeta omega mu
            records.append(_expm_acceleration(carriage, motor, stiffness, damping, force)[::EVERY])
        columns.append((records[0] - records[1]) / (2 * relative * theta[j]))
    jacobian = np.column_stack(columns)
    return np.linalg.solve(jacobian.T @ jacobian, jacobian.T), jacobian


def test_noiseless_fit_is_off_the_truth_by_rk4_only(chirp_run):
    model, force, measured = chirp_run
    *_, omega, zeta = _truth(model)
    fit = resonance.fit_resonance(force, measured[::EVERY], DT, EVERY, BAND)
    sensitivity, _ = _sensitivity(model, force)
    # the record differs from the exact one by at most the RK4 bound; the estimate moves by at most G applied to it
    bound = np.abs(sensitivity) @ _rk4_acceleration_bound(model, force)[::EVERY]
    assert abs(2 * math.pi * fit.frequency_hz - omega) <= bound[0] + 1e-9 * omega
    assert abs(fit.damping_ratio - zeta) <= bound[1] + 1e-7 * zeta
    # and that bias is well inside the noisy test's interval (half-width 0.0089 Hz, below)
    assert bound[0] / (2 * math.pi) < 0.1 * 0.0089


def test_interval_width_is_the_noise_through_the_jacobian(chirp_run):
    """Each seed's 95 % interval is 2 x 1.96 sigma sqrt((J^T J)^-1)_00 at the truth, to the spread of the residual
    variance (relative sd 1 / sqrt(2 n) = 0.9 %, five of them allowed)."""
    model, force, measured = chirp_run
    _, jacobian = _sensitivity(model, force)
    theory = 2 * resonance.Z95 * NOISE * math.sqrt(np.linalg.inv(jacobian.T @ jacobian)[0, 0]) / (2 * math.pi)
    samples = measured[::EVERY].size
    for seed in range(3):
        low, high = _fit(force, measured, seed).frequency_ci95
        assert high - low == pytest.approx(theory, rel=5 / math.sqrt(2 * samples))
    assert theory == pytest.approx(0.0177, abs=0.0005)  # the width the docs state [Hz]


@pytest.mark.slow
def test_interval_covers_the_true_frequency_in_at_least_38_of_40_seeds(chirp_run):
    model, force, measured = chirp_run
    *_, omega, _ = _truth(model)
    truth = omega / (2 * math.pi)
    covered = 0
    for seed in range(40):
        low, high = _fit(force, measured, seed).frequency_ci95
        covered += low <= truth <= high
    assert covered >= 38


def test_a_band_that_misses_the_resonance_says_so(chirp_run):
    model, _, _ = chirp_run
    force = resonance.chirp(1.0, 20.0, 60.0, 1.0, DT)
    data = mujoco.MjData(model)
    state = np.zeros(mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    _, sensors = rollout.rollout(model, data, state, force[None, :, None])
    record = sensors[0, ::EVERY, model.sensor(control.ACCELEROMETER).adr[0]]
    noisy = record + NOISE * np.random.default_rng(0).standard_normal(record.size)
    with pytest.raises(ValueError, match="band 20-60 Hz misses the belt's resonance"):
        resonance.fit_resonance(force, noisy, DT, EVERY, (20.0, 60.0))


def test_measured_resonance_chooses_the_shaper_and_mujoco_verifies_the_move(chirp_run):
    model, force, measured = chirp_run
    m_c, m_m, k, c, omega, zeta = _truth(model)
    fit = _fit(force, measured, 0)
    low, high = fit.frequency_ci95
    distance, band = model.numeric("move_distance").data[0], model.numeric("positioning_band").data[0]
    total = m_c + m_m
    duration = 2 * math.sqrt(distance * total / model.actuator("drive").ctrlrange[1])
    candidates = [shaping.make_shaper(name, fit.frequency_hz, fit.damping_ratio) for name in shaping.SHAPERS]
    chosen, worst = positioning.fastest_shaper(
        candidates, (low, fit.frequency_hz, high), fit.damping_ratio, distance, duration, band
    )
    # known to 0.01 Hz the belt needs no robustness: the shortest shaper wins, and each worst time is its time at
    # the interval's ends, the shaper's own duration plus the bang-bang move at most
    assert chosen.name == "zv"
    for shaper in candidates:
        assert worst[shaper.name] <= duration + shaper.duration + 1e-12
    # the chosen move on the true model in MuJoCo: the shaper's times rounded to a 25 us grid
    dt = 2.5e-5
    n_half = math.ceil(duration / 2 / dt)
    force_level = total * distance / (n_half * dt) ** 2
    offsets = np.round(chosen.times / dt).astype(int)
    control_sequence = np.zeros(2 * n_half + offsets[-1] + int(0.01 / dt))
    for amplitude, offset in zip(chosen.amplitudes, offsets):
        control_sequence[offset : offset + n_half] += amplitude * force_level
        control_sequence[offset + n_half : offset + 2 * n_half] -= amplitude * force_level
    true_model = mujoco.MjModel.from_xml_path(str(springlab.sim.model_files.path("printer_head")))
    true_model.opt.timestep = dt
    data = mujoco.MjData(true_model)
    state = np.zeros(mujoco.mj_stateSize(true_model, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(true_model, data, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    states, _ = rollout.rollout(true_model, data, state, control_sequence[None, :, None])
    end = 2 * n_half + offsets[-1] - 1  # the state after the shaped command's last step
    q_c, q_m, v_c, v_m = states[0, end, 1:5]
    stretch, rate = q_m - q_c, v_m - v_c
    envelope = m_m / total * abs(complex(stretch, (rate + zeta * omega * stretch) / (omega * math.sqrt(1 - zeta**2))))
    # the realized shaper's residual on the true belt: V of the rounded times x the unshaped move's (expm)
    realized = shaping.Shaper("zv", chosen.amplitudes, offsets * dt, fit.frequency_hz, fit.damping_ratio)
    unshaped = _expm_envelope(m_c, m_m, k, c, [(n_half * dt, force_level), (n_half * dt, -force_level)])
    expected = float(realized.vibration(omega / (2 * math.pi), zeta)) * unshaped
    # RK4's error: |R(z) - e^z| per step times the mode's distance from equilibrium, which the steps of the
    # shaped force (sum of |jumps| / (M omega^2) in carriage units) bound
    z = omega * dt
    jumps = 4 * force_level * np.sum(chosen.amplitudes)
    rk4 = len(control_sequence) * z**5 / 120 / (1 - z / 6) * jumps / (total * omega**2 * math.sqrt(1 - zeta**2))
    assert abs(envelope - expected) <= rk4 + 64 * EPS * distance * len(control_sequence)
    assert envelope < 0.1 * band
    # and the carriage stays within the band after the shaped command, in the run
    assert np.max(np.abs(states[0, end:, 1] - distance)) <= band
