"""springlab frequency's scene questions (issue 23, Scenes): the car's road-driven single mass (transmissibility and
its isolation frequency sqrt(2) omega_n), the quarter car's body acceleration, both pitch-plane modes, what the
printer head's belt resonance means for positioning, and dm_control's models against an independent
linearization.

Every reference is built here from the scene's parameters (closed forms, numpy/scipy eigenproblems and matrix
exponentials, centred differences of mj_forward written out below). Tolerances as in test_frequency.py: the
linearization's entries are centred differences, good to sqrt(eps) relative where a preload rounds them (the
car carries its weight on its springs), and a relative perturbation delta of A moves H(j omega) by at most
kappa delta, kappa = ||A|| ||(j omega I - A)^-1||.
"""

from __future__ import annotations

import math
import pathlib

import dm_control  # a test-only dependency (the `test` extra): MJCF models nobody here wrote
import mujoco
import numpy as np
import pytest
import scipy.linalg

import springlab
from springlab.scenes import get as get_scene

EPS = float(np.finfo(float).eps)
SUITE = pathlib.Path(dm_control.__file__).parent / "suite"


def _kappa(a: np.ndarray, points: np.ndarray) -> float:
    """max over the points of ||A|| ||(x I - A)^-1||_2."""
    n = a.shape[0]
    norm = np.linalg.norm(a, 2)
    return max(norm * np.linalg.norm(np.linalg.inv(x * np.eye(n) - a), 2) for x in points)


# -- the car, a single mass driven by the road through spring and damper ---------------------------------------


@pytest.mark.parametrize("zeta", [0.0, 0.2, 1.0, 3.0], ids=["undamped", "underdamped", "critical", "overdamped"])
def test_single_mass_transmissibility_and_its_isolation_at_sqrt2_omega_n(zeta):
    """|X/Y| = |X''/Y''| = |(c s + k) / (m s^2 + c s + k)| in every damping regime, and |T| falls below 1 at
    sqrt(2) omega_n whatever the damping."""
    car = get_scene("car")
    params = car.resolve(car.scenario("damped_release"), {"damping_ratio": zeta})
    m, k = params["mass"], params["stiffness"]
    c = 2 * zeta * math.sqrt(k * m)
    f_n = math.sqrt(k / m) / (2 * math.pi)
    band = (f_n / 20, f_n * 8)
    result = springlab.frequency("car", "damped_release", damping_ratio=zeta, band=band, points=90, integrators=())
    assert (result.input, result.response) == ("road_acceleration", "heave:acc")
    assert result.units == {"input": "m/s^2", "response": "m/s^2"}  # the transmissibility: per unit, dimensionless
    s = 2j * np.pi * result.frequencies_hz
    closed = (c * s + k) / (m * s**2 + c * s + k)
    a = np.array([[0.0, 1.0], [-k / m, -c / m]])
    tol = math.sqrt(EPS) * _kappa(a, s)
    assert np.max(np.abs(result.exact / closed - 1.0)) <= tol
    # the crossing: |T(f)| = 1 solved by the model's own response; its error is the response's relative error
    # divided by the slope d ln|T| / d ln f there (closed form, by a centred difference), plus brentq's 1e-14
    f_iso = math.sqrt(2) * f_n
    h = 1e-4
    slope = abs(np.log(np.abs(_single(m, c, k, f_iso * (1 + h)) / _single(m, c, k, f_iso * (1 - h)))) / (2 * h))
    found = result.answers["isolation_frequency_hz"]
    assert found == pytest.approx(f_iso, rel=math.sqrt(EPS) * _kappa(a, [2j * np.pi * f_iso]) / slope + 1e-13)
    assert result.answers["isolation_frequency_closed_form_hz"] == pytest.approx(f_iso, rel=4 * EPS)
    assert any("isolation" in line for line in result.verdict())


def _single(m: float, c: float, k: float, f: float) -> complex:
    s = 2j * math.pi * f
    return (c * s + k) / (m * s**2 + c * s + k)


def test_quarter_car_body_acceleration_is_omega_squared_times_its_transmissibility():
    """Comfort is about acceleration: road height -> body acceleration = -omega^2 T_qc (the quarter car)."""
    car = get_scene("car")
    params = car.resolve(car.scenario("road_bump"), {})
    ms, ks, cs = params["mass"] / 4, params["stiffness"] / 4, params["damping"] / 4
    mu, kt = params["unsprung_mass"], params["tire_stiffness"]
    result = springlab.frequency("car", response="heave:acc", points=80, integrators=())
    s = 2j * np.pi * result.frequencies_hz
    body = ms * s**2 + cs * s + ks
    wheel = mu * s**2 + cs * s + ks + kt
    closed = s**2 * kt * (cs * s + ks) / (body * wheel - (cs * s + ks) ** 2)
    a = np.zeros((4, 4))
    a[0, 2] = a[1, 3] = 1.0
    a[2] = [-ks / ms, ks / ms, -cs / ms, cs / ms]
    a[3] = [ks / mu, -(ks + kt) / mu, cs / mu, -cs / mu]
    assert np.max(np.abs(result.exact / closed - 1.0)) <= math.sqrt(EPS) * _kappa(a, s)
    assert result.units["response"] == "m/s^2"
    assert result.answers == {}  # the scene's own answer belongs to its declared response only


# -- the car's pitch and heave ---------------------------------------------------------------------------------


def _pitch_plane(params: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """M, C, K of the textbook pitch-plane model q = (heave, pitch) from the parameters (front length x - a
    theta, rear x + b theta)."""
    a, b = params["front_axle_distance"], params["rear_axle_distance"]
    jac = np.array([[1.0, -a], [1.0, b]])
    mass = np.diag([params["mass"], params["pitch_inertia"]])
    stiff = jac.T @ np.diag([params["front_stiffness"], params["rear_stiffness"]]) @ jac
    damp = jac.T @ np.diag([params["front_damping"], params["rear_damping"]]) @ jac
    return mass, damp, stiff


def test_pitch_heave_both_resonances_are_the_two_modes_named_by_their_node():
    """Lightly damped (0.05): the push over the front axle -> pitch response has two peaks, one per mode; their
    poles are the eigenvalues of the state matrix of M, C, K, the undamped frequencies those of K phi = w^2 M phi;
    the mode whose node lies outside the wheelbase is heave-dominated, the one inside pitch-dominated."""
    zeta = 0.05
    car = get_scene("car")
    params = car.resolve(car.scenario("pitch_heave"), {"damping_ratio": zeta})
    params["front_damping"] = (
        2
        * zeta
        * math.sqrt(
            params["front_stiffness"]
            * params["mass"]
            * params["rear_axle_distance"]
            / (params["front_axle_distance"] + params["rear_axle_distance"])
        )
    )
    params["rear_damping"] = (
        2
        * zeta
        * math.sqrt(
            params["rear_stiffness"]
            * params["mass"]
            * params["front_axle_distance"]
            / (params["front_axle_distance"] + params["rear_axle_distance"])
        )
    )
    mass, damp, stiff = _pitch_plane(params)
    result = springlab.frequency("car", "pitch_heave", damping_ratio=zeta, points=80, integrators=())
    assert (result.input, result.response) == ("push", "pitch")
    # the exact response: pitch per push force at station p (generalized force (1, -p)), closed form
    p = params["push_position"]
    s = 2j * np.pi * result.frequencies_hz
    closed = np.array([np.linalg.solve(mass * x**2 + damp * x + stiff, [1.0, -p])[1] for x in s])
    state = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(mass, stiff), -np.linalg.solve(mass, damp)]])
    assert np.max(np.abs(result.exact / closed - 1.0)) <= math.sqrt(EPS) * _kappa(state, s)
    # two resonances, at the two damped poles
    lam, vectors = np.linalg.eig(state)
    poles = sorted(lam[lam.imag > 0], key=abs)
    assert len(result.resonances) == 2
    spread = math.sqrt(EPS) * np.linalg.cond(vectors) * np.linalg.norm(state, 2)
    for found, pole in zip(result.resonances, poles):
        assert 2 * math.pi * found.natural_frequency_hz == pytest.approx(abs(pole), abs=spread)
        assert found.pole_damping_ratio == pytest.approx(-pole.real / abs(pole), abs=spread / abs(pole))
    # undamped modes and their names
    values, shapes = scipy.linalg.eigh(stiff, mass)
    answers = result.answers
    for i in (1, 2):
        omega, shape = math.sqrt(values[i - 1]), shapes[:, i - 1]
        node = shape[0] / shape[1]
        assert answers[f"mode_{i}_frequency_hz"] == pytest.approx(omega / (2 * math.pi), rel=1e3 * EPS)
        assert answers[f"mode_{i}_node_m"] == pytest.approx(node, rel=1e6 * EPS)
        outside = not (-params["rear_axle_distance"] <= node <= params["front_axle_distance"])
        assert answers[f"mode_{i}_shape"] == ("heave-dominated (bounce)" if outside else "pitch-dominated")
        assert answers[f"mode_{i}_resonance_hz"] == result.resonances[i - 1].frequency_hz
    assert {answers["mode_1_shape"], answers["mode_2_shape"]} == {"heave-dominated (bounce)", "pitch-dominated"}


def test_pitch_heave_at_the_default_damping_merges_the_two_modes_into_one_peak():
    """At zeta 0.3 per axle the closed-form |H| has a single local maximum: the tool says the pitch mode has no
    peak of its own, and still names it."""
    car = get_scene("car")
    params = car.resolve(car.scenario("pitch_heave"), {})
    mass, damp, stiff = _pitch_plane(params)
    result = springlab.frequency("car", "pitch_heave", points=40, integrators=())
    f = np.geomspace(*result.band_hz, 4000)
    closed = np.abs(
        [
            np.linalg.solve(-mass * w**2 + 1j * w * damp + stiff, [1.0, -params["push_position"]])[1]
            for w in 2 * np.pi * f
        ]
    )
    peaks = np.nonzero((closed[1:-1] > closed[:-2]) & (closed[1:-1] >= closed[2:]))[0]
    assert len(peaks) == len(result.resonances) == 1
    assert result.answers["mode_2_resonance_hz"] is None and result.answers["mode_2_shape"] == "pitch-dominated"


# -- the printer head: what the belt's resonance means for positioning -----------------------------------------


def _ring_down_after_move(params: dict, duration: float, force: float, tau: np.ndarray) -> np.ndarray:
    """The damped two-mass model's carriage deviation [m] from its resting place at evenly spaced times `tau` [s]
    (tau[0] = 0) after a bang-bang move (+F for half of `duration`, -F for the other half), by matrix exponentials of
    (q_c, q_m, v_c, v_m, F)."""
    m_c, m_m, k, c = (params[n] for n in ("carriage_mass", "motor_mass", "belt_stiffness", "belt_damping"))
    a = np.zeros((5, 5))
    a[0, 2] = a[1, 3] = 1.0
    a[2, :4] = [-k / m_c, k / m_c, -c / m_c, c / m_c]
    a[3, :4] = [k / m_m, -k / m_m, c / m_m, -c / m_m]
    a[3, 4] = 1.0 / m_m
    half = scipy.linalg.expm(a * duration / 2)
    state = half @ np.array([0.0, 0.0, 0.0, 0.0, force])
    state[4] = -force
    state = half @ state
    state[4] = 0.0
    # the centre of mass is at rest at D now: the carriage's deviation from it is a pure belt vibration
    total = m_c + m_m
    free = _free(a, state, tau)
    return free[:, 0] - (m_c * free[:, 0] + m_m * free[:, 1]) / total


def _free(a: np.ndarray, state: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """States at the evenly spaced times `tau` [s] (tau[0] = 0) of z' = A z from `state`, one expm step reused."""
    step = scipy.linalg.expm(a * (tau[1] - tau[0]))
    out = np.empty((len(tau), len(state)))
    out[0] = state
    for i in range(1, len(tau)):
        out[i] = step @ out[i - 1]
    return out


def test_printer_head_positioning_times_follow_from_the_belt_resonance():
    """The belt's frequency from the resonance's pole, the minimum-time move, and the quietest move time of the
    damped belt: every bang-bang move at least that long rings within the band in the two-mass model's exact
    ring-down, a move just shorter beyond it; the undamped bound is kept, labelled as such."""
    head = get_scene("printer_head")
    params = head.resolve(head.scenario("move"), {})
    m_c, m_m, k, c = (params[n] for n in ("carriage_mass", "motor_mass", "belt_stiffness", "belt_damping"))
    total, mu = m_c + m_m, m_c * m_m / (m_c + m_m)
    omega, zeta = math.sqrt(k / mu), c / (2 * math.sqrt(k * mu))
    period = 2 * math.pi / (omega * math.sqrt(1 - zeta**2))
    distance, band, force = params["move_distance"], params["positioning_band"], params["drive_force"]
    result = springlab.frequency("printer_head", points=60, integrators=())
    got = result.answers
    assert got["belt_frequency_hz"] == pytest.approx(omega / (2 * math.pi), rel=math.sqrt(EPS))
    assert got["belt_damping_ratio"] == pytest.approx(zeta, rel=math.sqrt(EPS))
    assert got["minimum_move_time_s"] == pytest.approx(2 * math.sqrt(distance * total / force))
    assert got["motor_anti_resonance_hz"] == pytest.approx(math.sqrt(k / m_c) / (2 * math.pi), rel=1e3 * EPS)
    assert got["quiet_move_time_undamped_s"] == pytest.approx(
        4 / omega * math.sqrt(distance / band), rel=math.sqrt(EPS)
    )
    quiet = got["quiet_move_time_s"]
    assert round(quiet, 4) == 0.0890
    # the ring-down's first period holds its largest deviation; sampled at period / 4000 a peak reads low by
    # (2 pi / 4000)^2 / 8 = 3e-7, and the pole's frequency carries sqrt(eps): 1e-6 of the band covers both
    tau = np.linspace(0.0, period, 4001)
    rng = np.random.default_rng(23)
    for duration in quiet * (1 + np.concatenate([[1e-6], rng.uniform(0, 0.1, 5)])):
        ring = _ring_down_after_move(params, duration, 4 * total * distance / duration**2, tau)
        assert np.max(np.abs(ring)) <= band * (1 + 1e-6)
    shorter = quiet - 2e-6
    assert np.max(np.abs(_ring_down_after_move(params, shorter, 4 * total * distance / shorter**2, tau))) > band
    # the full-force move: its exact ring-down leaves the band for good at minimum_move_positioning_time_s
    fastest = got["minimum_move_time_s"]
    after = np.arange(0.0, 0.03, 1e-7)
    ring = _ring_down_after_move(params, fastest, force, after)
    last_outside = after[np.flatnonzero(np.abs(ring) > band)[-1]]
    assert fastest + last_outside - 1e-9 <= got["minimum_move_positioning_time_s"] <= fastest + last_outside + 1.1e-7
    # ... whatever its phase on the belt it leaves at most worst_residual_m: (1 + e^(-sigma T/2))^2 a / (omega^2
    # sqrt(1 - zeta^2)), a = F / M, reached when each half-move lasts an odd number of half damped periods
    worst = force / total * (1 + math.exp(-zeta * omega * fastest / 2)) ** 2 / (omega**2 * math.sqrt(1 - zeta**2))
    assert got["worst_residual_m"] == pytest.approx(worst, rel=math.sqrt(EPS))
    assert np.max(np.abs(ring)) <= got["worst_residual_m"]
    settle = math.log(got["worst_residual_m"] / band) / (zeta * omega)
    assert got["worst_positioning_time_s"] == pytest.approx(fastest + settle, rel=1e-6)
    assert sum(line.startswith("positioning") for line in result.verdict()) == 1


# -- any MJCF: dm_control's models against an independent linearization ------------------------------------------


def _hanging(name: str, qpos: list[float]) -> mujoco.MjModel:
    """dm_control's model with a keyframe at rest at `qpos` (the pole hanging down: a stable operating point)."""
    spec = mujoco.MjSpec.from_file(str(SUITE / f"{name}.xml"))
    spec.add_key(name="hanging", qpos=qpos)
    return spec.compile()


def _centred_linearization(model: mujoco.MjModel, qpos: np.ndarray, actuator: int, h: float):
    """(A, b) of x = (dq, v) from centred differences of mj_forward's qacc, step h (written out here)."""
    data = mujoco.MjData(model)
    nv = model.nv

    def qacc(dq: np.ndarray, v: np.ndarray, u: float) -> np.ndarray:
        data.qpos[:] = qpos
        mujoco.mj_integratePos(model, data.qpos, dq, 1.0)
        data.qvel[:] = v
        data.ctrl[:] = 0.0
        data.ctrl[actuator] = u
        mujoco.mj_forward(model, data)
        return data.qacc.copy()

    zero = np.zeros(nv)
    a = np.zeros((2 * nv, 2 * nv))
    a[:nv, nv:] = np.eye(nv)
    for j in range(nv):
        e = np.zeros(nv)
        e[j] = h
        a[nv:, j] = (qacc(e, zero, 0.0) - qacc(-e, zero, 0.0)) / (2 * h)
        a[nv:, nv + j] = (qacc(zero, e, 0.0) - qacc(zero, -e, 0.0)) / (2 * h)
    b = np.zeros(2 * nv)
    b[nv:] = (qacc(zero, zero, h) - qacc(zero, zero, -h)) / (2 * h)
    return a, b


@pytest.mark.parametrize(
    "name, qpos, actuator, response",
    [("pendulum", [math.pi], "torque", "hinge"), ("cartpole", [0.0, math.pi], "slide", "hinge_1")],
)
def test_dm_control_model_exact_response_is_an_independent_linearization(name, qpos, actuator, response):
    """The exact response of a dm_control model hanging at rest (any MJCF: the audit's linearization) against
    c (j omega I - A)^-1 b from centred differences of mj_forward written here, step h = eps^(1/3).

    Both linearizations are centred differences of the same smooth forward dynamics: each entry is off by
    O(h^2) truncation plus eps / h rounding (relative to the entry's scale), so the responses agree to
    (eps^(2/3) + eps / 1e-6 + 1e-12) kappa, the library's step being 1e-6."""
    model = _hanging(name, qpos)
    result = springlab.frequency(model, input=actuator, response=response, points=60, integrators=())
    h = EPS ** (1 / 3)
    a, b = _centred_linearization(model, np.array(qpos, float), model.actuator(actuator).id, h)
    dof = model.joint(response).dofadr[0]
    c = np.zeros(2 * model.nv)
    c[dof] = 1.0
    s = 2j * np.pi * result.frequencies_hz
    independent = np.array([c @ np.linalg.solve(x * np.eye(2 * model.nv) - a, b) for x in s])
    per_entry = EPS ** (2 / 3) + EPS / 1e-6 + 1e-12
    assert np.max(np.abs(result.exact / independent - 1.0)) <= 10 * per_entry * _kappa(a, s)
    # hanging down, each model rings: its pendulum's resonance is a lightly damped pole of A
    poles = np.linalg.eigvals(a)
    (found,) = [r for r in result.resonances if r.magnitude == max(x.magnitude for x in result.resonances)]
    nearest = min(poles[poles.imag > 0], key=lambda p: abs(abs(p) - 2 * np.pi * found.natural_frequency_hz))
    assert 2 * np.pi * found.natural_frequency_hz == pytest.approx(abs(nearest), rel=1e-6)


# -- the demo's frequency section -----------------------------------------------------------------------------


@pytest.mark.slow
def test_demo_frequency_step_writes_every_declared_question_and_the_report_shows_its_verdict(tmp_path, monkeypatch):
    """Every scene's declared frequency questions: bode.png, frequency.json and frequency.csv written, and the
    report's scene section shows the bode plot with the verdict lines (band, dt per integrator, the scene's
    answer)."""
    from springlab.demo import report, steps
    from springlab.studies.frequency import declared_scenarios

    # the figures' resolution and the number of integrators searched are not the claim
    monkeypatch.setattr(steps, "DEMO_FREQUENCY_POINTS", 30)
    monkeypatch.setattr(steps, "DEMO_FREQUENCY_INTEGRATORS", ("rk4",))
    state = steps.DemoState(out=tmp_path)
    artifacts = steps.frequency_step(state)
    declared = [(s.name, q) for s in springlab.scenes.SCENES.values() for q in declared_scenarios(s.name)]
    assert ("car", "damped_release") in declared and ("printer_head", "move") in declared
    plots = [a for a in artifacts if a.kind == "plot"]
    assert len(plots) == len(declared)
    for scene, scenario in declared:
        folder = tmp_path / scene / "frequency" / scenario
        assert {p.name for p in folder.iterdir()} == {"bode.png", "frequency.json", "frequency.csv"}
    state.artifacts.extend(artifacts)
    page = report.build_html(state)
    for plot in plots:
        assert plot.path in page and "needs dt" in plot.answer
        for line in plot.answer.splitlines():
            assert report._e(line) in page
    assert "isolation" in page and "positioning" in page and "pitch-dominated" in page


def test_command_takes_a_scene_parameter_and_prints_the_answers(capsys):
    """`--set` reaches the scene: lighter dampers show both pitch-plane peaks; frequency.json carries the answers."""
    import json

    from springlab.cli.main import main

    main(["frequency", "car", "pitch_heave", "--set", "damping_ratio=0.05", "--points", "40", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert len(data["resonances"]) == 2 and all(r["natural_frequency_hz"] > 0 for r in data["resonances"])
    assert data["answers"]["mode_2_shape"] == "pitch-dominated" and data["answers"]["mode_2_resonance_hz"] > 0
