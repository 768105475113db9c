"""`springlab.audit` on models with known answers: a chain of masses and springs (closed-form
eigenfrequencies, so closed-form stability limits), a pendulum (linear only near its bottom), a sphere
on a soft contact, and the five shipped scenes: slider and car, whose limits and orders `springlab stability`
and `springlab tradeoff` already measure; printer_head, whose belt damping lives on a tendon (closed forms
for where each integrator puts it); nonlinear (its linearization's undamped oscillator); kinematics (all
rigid: no limit).

Tolerances: the measured limit is bisected to a ratio of 1 + 1e-4 (springlab.exact.map_limits.LIMIT_PRECISION) on a
map good to ~1e-10, so 1e-3 relative to the closed form is wide; the contract asks agreement with
stability/tradeoff within 0.5 % (limits) and 0.1 (orders).
"""

from __future__ import annotations

import dataclasses
import importlib
import json
import math
import random

import mujoco
import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from helpers.contract import plain_json
from helpers.linear_models import chain_frequencies, chain_xml, pendulum_xml
from helpers.timing import constant_time_run
from springlab import scenes
from springlab.errors import BadInputError, UnknownNameError
from springlab.exact.limits import stability_limit
from springlab.exact.map_limits import map_limit
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.predicted_limits import predictions
from springlab.sim import model_files
from springlab.studies import stability, tradeoff
from springlab.studies.audit.audit import INTEGRATORS, audit
from springlab.studies.audit.limits import CONFIRM_ABOVE, stability_limits

LIMIT_RELATIVE = 1e-3


@pytest.fixture(scope="module")
def chain_audit():
    return audit(mujoco.MjModel.from_xml_string(chain_xml(4, 100.0, 1.0, 0.0)), tol=1e-3)


def test_chain_limits_are_two_and_2_83_over_the_highest_frequency(chain_audit):
    omega_max = chain_frequencies(4, 100.0, 1.0).max()
    limits = chain_audit.stability
    for name in ("euler", "implicit", "implicitfast"):
        assert limits[name].limit_dt_measured_s * omega_max == pytest.approx(2.0, rel=LIMIT_RELATIVE)
        assert limits[name].limit_dt_predicted_s * omega_max == pytest.approx(2.0, rel=LIMIT_RELATIVE)
    assert limits["rk4"].limit_dt_measured_s * omega_max == pytest.approx(2 * math.sqrt(2), rel=LIMIT_RELATIVE)
    assert limits["discrete"].limit_dt_measured_s is None  # implicit in springs: no limit
    assert all(limits[name].confirmed for name in ("euler", "implicit", "implicitfast", "rk4"))


def test_chain_is_linear_and_its_recommendation_meets_tol_against_the_exact_solution(chain_audit):
    result = chain_audit
    assert result.is_linear
    assert result.orders["rk4"] == pytest.approx(4.0, abs=0.1)
    assert result.orders["euler"] == pytest.approx(1.0, abs=0.1)
    pick = result.recommendation
    assert pick.verified and pick.error <= result.tol
    # independent reference: the closed-form chain (M from the relative coordinates, K = k I), expm
    n, k, m = 4, 100.0, 1.0
    i = np.arange(n)
    mass = m * (n - np.maximum.outer(i, i))
    system = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(mass, k * np.eye(n)), np.zeros((n, n))]])
    model = mujoco.MjModel.from_xml_string(chain_xml(n, k, m, 0.0))
    model.opt.integrator = mujoco.mjtIntegrator.__members__[
        {"euler": "mjINT_EULER", "implicit": "mjINT_IMPLICIT", "implicitfast": "mjINT_IMPLICITFAST"}.get(
            pick.integrator, f"mjINT_{pick.integrator.upper()}"
        )
    ]
    model.opt.timestep = pick.dt
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = result.start.qpos, result.start.qvel  # the start moves positions and velocities
    x0 = np.concatenate([result.start.qpos, result.start.qvel])
    steps = round(result.duration / pick.dt)
    sim, ref = [x0], [x0]
    for s in range(1, steps + 1):
        mujoco.mj_step(model, data)
        sim.append(np.concatenate([data.qpos, data.qvel]))
        ref.append(expm(system * s * pick.dt) @ x0)
    sim, ref = np.array(sim), np.array(ref)
    error = max(
        np.max(np.abs(sim[:, :n] - ref[:, :n])) / np.max(np.abs(ref[:, :n])),
        np.max(np.abs(sim[:, n:] - ref[:, n:])) / np.max(np.abs(ref[:, n:])),
    )
    assert error <= result.tol


#: audit.json's keys, in order: the object's `to_dict()` keeps every one
AUDIT_KEYS = [
    "question",
    "answer",
    "answer_numbers",
    "model",
    "operating_point",
    "operating_point_state",
    "perturb",
    "excitation",
    "duration_s",
    "linear",
    "linearity",
    "modes",
    "fastest_mode",
    "stability",
    "stability_criterion",
    "own_setting",
    "constraints_broken",
    "reference",
    "sweep",
    "orders",
    "pareto",
    "recommendation",
    "cost_basis",
    "timings_s",
]


def test_the_audit_json_is_the_objects_to_dict_and_its_facts_are_attributes(chain_audit, capsys, monkeypatch):
    from springlab import files
    from springlab.cli import main as cli_main
    from springlab.cli.commands import audit as audit_command

    result = chain_audit
    data = result.to_dict()
    assert list(data) == AUDIT_KEYS and plain_json(data)
    assert list(data["own_setting"]) == [
        "integrator",
        "dt",
        "stable",
        "error",
        "margin",
        "wall_time_s",
        "margin_confirmed",
        "cost",
        "behaviour",
        "growth",
    ]
    assert list(data["operating_point_state"]) == [
        "settle_s",
        "at_point",
        "along_motion",
        "at_rest",
        "drift_m",
        "linear_map",
        "creep",
        "settling_helps",
    ]
    assert list(data["operating_point_state"]["at_point"]) == [
        "elements",
        "counts",
        "dry_friction",
        "max_abs_qvel",
        "max_abs_qacc",
    ]
    assert list(data["excitation"]) == ["qpos", "qvel", "ctrl", "moved", "still", "source"]
    assert list(data["recommendation"]) == [
        "integrator",
        "dt",
        "error",
        "tolerance",
        "verified",
        "cost",
        "wall_time_s",
        "ties",
        "near",
        "rejected",
        "text",
    ]
    assert list(data["linearity"]) == ["change", "tolerance"]
    assert list(data["stability"]["rk4"]) == [
        "limit_dt_predicted_s",
        "limit_dt_measured_s",
        "confirmed",
        "margin",
        "detail",
        "limit_dt_s",
        "method",
        "prediction",
        "runs_bounded_dt_s",
        "runs_blew_up_dt_s",
    ]
    assert list(data["sweep"][0]) == [
        "integrator",
        "dt",
        "steps",
        "error",
        "wall_time_s",
        "cost",
        "diverged",
        "beyond_limit",
    ]
    # the attributes are the JSON's facts, and they hang together: the margin is the limit over the own dt
    pick, own = result.recommendation, result.own
    assert (pick.integrator, pick.dt, pick.error, pick.verified) == tuple(
        data["recommendation"][k] for k in ("integrator", "dt", "error", "verified")
    )
    assert pick.verified and pick.error <= pick.tolerance == result.tol
    assert own.integrator == "euler" and own.dt == 0.002  # MuJoCo's defaults, which the chain keeps
    assert own.margin == result.stability[own.integrator].margin
    assert own.margin == result.stability["euler"].limit_dt_measured_s / own.dt
    assert result.stability["rk4"].limit_dt_measured_s == data["stability"]["rk4"]["limit_dt_measured_s"]
    assert result.own_ok == (own.stable and own.error <= result.tol)
    # `springlab audit --json` prints exactly to_dict() (inf and nan as null), and the text is `message`
    monkeypatch.setattr(audit_command, "run_audit", lambda *args, **options: result)
    code = cli_main.main(["audit", "chain.xml", "--json"])
    assert code == (0 if result.own_ok else 1)
    assert json.loads(capsys.readouterr().out) == files.json_ready(data)
    cli_main.main(["audit", "chain.xml"])
    assert capsys.readouterr().out == result.question_answer.text() + "\n" + result.message + "\n"


def test_the_pick_is_the_cheapest_in_counted_work_and_no_timer_moves_it(chain_audit, monkeypatch):
    # counted work: steps x evaluations per step (rk4 4, the others 1) x degrees of freedom (the chain's 4)
    result = chain_audit
    for run in result.runs:
        evaluations = 4 if run.integrator == "rk4" else 1
        assert run.cost == run.steps * evaluations * 4 and run.steps == round(result.duration / run.dt)
    pick = result.recommendation
    budget = result.tol - result.reference.error_estimate
    inside = [
        r
        for r in result.runs
        if r.error is not None
        and r.error <= budget
        and r.dt <= 0.9 * result.stability[r.integrator].limit_dt_s  # RECOMMEND_LIMIT_FRACTION
    ]
    assert pick.found and pick.cost == min(r.cost for r in inside)
    assert [r.cost for r in result.pareto] == sorted(r.cost for r in result.pareto)
    # measured times reversed between the integrators (rk4 the cheapest per step): the same pick and front
    audit_module = importlib.import_module("springlab.studies.audit.audit")
    fake = {"euler": 5e-6, "implicit": 4e-6, "implicitfast": 3e-6, "rk4": 1e-7, "discrete": 2e-6}
    monkeypatch.setattr(audit_module, "cost_per_step", lambda model, start, name, dt: fake[name])
    again = audit(mujoco.MjModel.from_xml_string(chain_xml(4, 100.0, 1.0, 0.0)), tol=1e-3)
    assert (again.recommendation.setting, again.recommendation.error) == (pick.setting, pick.error)
    assert [r.setting for r in again.pareto] == [r.setting for r in result.pareto]
    assert again.runs[0].time_s == fake[again.runs[0].integrator] * again.runs[0].steps  # reported beside


def test_the_pick_and_front_do_not_move_when_the_timer_returns_noise(monkeypatch):
    # every measured cost per step is drawn at random over four decades: the ranking reads counted work only
    audit_module = importlib.import_module("springlab.studies.audit.audit")
    noise = random.Random(11)
    monkeypatch.setattr(audit_module, "cost_per_step", lambda model, start, name, dt: noise.uniform(1e-7, 1e-3))
    options = dict(integrators=["euler", "implicitfast", "discrete", "rk4"], tol=1e-3)
    first, second = (audit(mujoco.MjModel.from_xml_string(chain_xml(2, 100.0, 1.0, 0.0)), **options) for _ in "12")
    assert first.recommendation.found and first.recommendation.setting == second.recommendation.setting
    assert first.recommendation.text == second.recommendation.text
    assert (first.recommendation.ties, first.recommendation.near) == (
        second.recommendation.ties,
        second.recommendation.near,
    )
    assert [r.setting for r in first.pareto] == [r.setting for r in second.pareto]
    # the noise reached the measured times: they differ, the answer does not
    assert [r.time_s for r in first.runs] != [r.time_s for r in second.runs]


def test_the_audit_cannot_be_changed_once_returned(chain_audit):
    result = chain_audit
    for target, name, value in (
        (result, "tol", 1.0),
        (result, "recommendation", None),
        (result.recommendation, "dt", 1.0),
        (result.own, "stable", False),
        (result.stability["rk4"], "confirmed", False),
        (result.runs[0], "error", 0.0),
        (result.reference, "converged", False),
        (result.timings, "total_s", 0.0),
    ):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(target, name, value)
    with pytest.raises(TypeError):
        result.stability["rk4"] = result.stability["euler"]
    with pytest.raises(TypeError):
        result.orders["rk4"] = 1.0
    with pytest.raises(AttributeError):
        result.runs.append(result.runs[0])


def test_the_audit_to_pandas_is_its_sweep_one_row_per_setting(chain_audit):
    frame = chain_audit.to_pandas()
    rows = chain_audit.to_dict()["sweep"]
    assert list(frame.columns) == list(rows[0]) and len(frame) == len(rows) == len(chain_audit.runs)
    for record, row in zip(frame.to_dict("records"), rows):
        for key, value in row.items():
            assert record[key] == value or (value is None and record[key] != record[key]), (key, row)
    # every integrator x timestep once: the sweep's grid
    assert len(set(zip(frame["integrator"], frame["dt"]))) == len(frame)
    assert set(frame["integrator"]) == set(INTEGRATORS)


def test_pendulum_is_linear_for_a_small_swing_and_nonlinear_for_a_large_one(untimed):
    model = mujoco.MjModel.from_xml_string(pendulum_xml())
    small = audit(model, keyframe="bottom", perturb=1e-4, integrators=["rk4", "euler"], duration=1.0)
    large = audit(model, keyframe="bottom", perturb=1.0, integrators=["rk4", "euler"], duration=1.0)
    assert small.is_linear and not large.is_linear
    assert large.reference.converged


def test_an_upright_pendulum_is_reported_physically_unstable_not_numerically(untimed):
    model = mujoco.MjModel.from_xml_string(pendulum_xml())
    result = audit(model, keyframe="top", perturb=1e-3, integrators=["rk4"], duration=1.0)
    modes = result.to_dict()["modes"]
    assert any(m["physically_unstable"] for m in modes)
    rate = math.sqrt(9.81 / 0.5)
    # RK4 is R(dt A) on the linearization: its limit is set by the decaying root -rate (2.785/rate)
    assert result.stability["rk4"].limit_dt_measured_s * rate == pytest.approx(2.7853, rel=LIMIT_RELATIVE)
    assert result.own.stable


@pytest.mark.slow
def test_a_sphere_bouncing_on_a_soft_contact_audits_and_its_recommendation_meets_tol(untimed):
    xml = (
        '<mujoco><option gravity="0 0 -9.81"/><worldbody><geom type="plane" size="1 1 0.1"/>'
        '<body pos="0 0 0.2"><joint type="slide" axis="0 0 1"/><geom type="sphere" size="0.1" mass="1"/>'
        "</body></worldbody></mujoco>"
    )
    model = mujoco.MjModel.from_xml_string(xml)
    tol = 1e-2
    result = audit(model, tol=tol, duration=0.5, integrators=["euler", "rk4", "implicitfast"])
    assert not result.is_linear  # free fall, then contact
    pick = result.recommendation
    assert pick.verified
    # independent reference: RK4 at 1e-5 s, itself converged (its difference to 2e-5 s is tol/100 or less)
    reference = _final_state(model, "rk4", 1e-5, result)
    coarser = _final_state(model, "rk4", 2e-5, result)
    chosen = _final_state(model, pick.integrator, pick.dt, result)
    motion = abs(reference[0] - result.start.qpos[0])
    assert abs(coarser[0] - reference[0]) <= tol / 100 * motion
    assert abs(chosen[0] - reference[0]) <= tol * motion


def _final_state(model, integrator, dt, result):
    work = model.__copy__()
    work.opt.integrator = INTEGRATORS[integrator]
    work.opt.timestep = dt
    data = mujoco.MjData(work)
    data.qpos[:], data.qvel[:] = result.start.qpos, result.start.qvel
    for _ in range(round(result.duration / dt)):
        mujoco.mj_step(work, data)
    return np.concatenate([data.qpos, data.qvel])


@pytest.mark.slow
@pytest.mark.parametrize("scene", ["slider", "car"])
def test_a_shipped_scene_audit_agrees_with_stability_and_tradeoff(scene, shipped_audit, slider_free_sweep, monkeypatch):
    # the contract: limits within 0.5 %, orders within 0.1 wherever both measure one (the audit's grid
    # stops at 1e-3 of its largest dt, so discrete on the car stays above the fit's 0.1 error cap)
    result = shipped_audit(scene)
    (mode,) = result.linear.modes
    omega, zeta = mode.frequency_hz * 2 * math.pi, mode.damping_ratio
    boundaries = stability.measure_boundaries(("euler", "implicitfast", "rk4"), (abs(zeta),))
    for row in boundaries:
        assert result.stability[row.integrator].limit_dt_measured_s * omega == pytest.approx(
            row.measured_omega_dt, rel=5e-3
        )
        assert row.theory_omega_dt == pytest.approx(stability_limit(row.integrator, abs(zeta)))
    # the orders come from the errors alone: the slider's default scenario's sweep is the session's
    # (tests/conftest.py, one timing per run), which test_tradeoff.py reads too; another scene's sweep is timed by
    # a constant (its timer was half of its cost), which leaves its errors and orders the same
    scenario = result.model.split("'")[3]
    shared = (scene, scenario) == ("slider", "free")
    if not shared:
        monkeypatch.setattr(tradeoff, "time_run", constant_time_run)
    sweep = slider_free_sweep if shared else tradeoff.sweep(scene, scenario, timing_repeats=1)
    compared = [name for name, order in sweep.orders.items() if order is not None and result.orders[name] is not None]
    assert {"euler", "rk4"} <= set(compared)
    for name in compared:
        assert result.orders[name] == pytest.approx(sweep.orders[name], abs=0.1), name


def test_limits_split_joint_and_tendon_damping_as_each_integrator_does():
    # one slide (m 1 kg, k 100 N/m: omega 10 rad/s) damped by its joint (zeta_j 0.05) and by a fixed
    # tendon on the same joint (zeta_t 0.15). euler: only joint damping implicit; implicit(fast): the
    # tendon too (it stays inside M's sparsity). v' = v + h (-w^2 x - 2 zeta w v) / (1 + 2 zeta_i w h),
    # x' = x + h v' has trace < 1 + det while w h < 2 s + 2 sqrt(s^2 + 1), s = zeta_i - zeta_e
    zeta_joint, zeta_tendon, omega = 0.05, 0.15, 10.0
    xml = (
        '<mujoco><option gravity="0 0 0"/><worldbody><body><joint name="x" type="slide" axis="1 0 0"'
        f' stiffness="100" damping="{2 * zeta_joint * omega}"/><inertial pos="0 0 0" mass="1"'
        ' diaginertia="1 1 1"/></body></worldbody><tendon><fixed'
        f' damping="{2 * zeta_tendon * omega}"><joint joint="x" coef="1"/></fixed></tendon></mujoco>'
    )
    model = mujoco.MjModel.from_xml_string(xml)
    at = ModelAtPoint.at(model)
    predicted = predictions(at, ("euler", "implicit", "implicitfast"))
    maps = {name: map_limit(at, name, 10.0, p.limit_s, CONFIRM_ABOVE) for name, p in predicted.items()}
    limits = stability_limits(at, predicted, maps)

    def bound(s):
        return 2 * s + 2 * math.hypot(s, 1.0)

    expected = {"euler": bound(zeta_joint - zeta_tendon), "implicit": bound(zeta_joint + zeta_tendon)}
    expected["implicitfast"] = expected["implicit"]
    for name, omega_dt in expected.items():
        assert limits[name].limit_dt_predicted_s * omega == pytest.approx(omega_dt, rel=LIMIT_RELATIVE), name
        assert limits[name].limit_dt_measured_s * omega == pytest.approx(omega_dt, rel=LIMIT_RELATIVE), name
        assert limits[name].confirmed, name


def _belt(model):
    """(m_c, m_m, k, c) [kg, kg, N/m, N s/m] of the printer head's two slides and its belt tendon."""
    m_c, m_m = (float(model.body(name).mass[0]) for name in ("carriage", "motor"))
    belt = model.tendon("belt")
    return m_c, m_m, float(model.tendon_stiffness[belt.id]), float(model.tendon_damping[belt.id])


@pytest.mark.slow
def test_printer_head_audit_places_the_belt_damping_where_each_integrator_does(shipped_audit, monkeypatch):
    # the belt is a fixed tendon between two slides on separate branches: euler integrates its damping
    # explicitly (only dof_damping is implicit), implicit/implicitfast only its diagonal (D keeps the
    # sparsity of M). Closed forms in the relative coordinate e = q_m - q_c, u = e':
    # u' = u + h g (-k e - c u), e' = e + h u', stable while h^2 g k + 2 h g c < 4, with
    # g = 1/m_c + 1/m_m (euler) or 1/(m_c + h c) + 1/(m_m + h c) (the implicit solve with D = c I)
    result = shipped_audit("printer_head")  # audit("printer_head", tol=1e-3), shared with the demo's audit test
    m_c, m_m, k, c = _belt(mujoco.MjModel.from_xml_path(str(model_files.path("printer_head"))))
    reduced = m_c * m_m / (m_c + m_m)
    omega, zeta = math.sqrt(k / reduced), c / (2 * math.sqrt(k * reduced))
    oscillatory = [m for m in result.linear.modes if m.kind == "oscillatory"]
    assert len(oscillatory) == 1 and all(m.kind == "rigid" for m in result.linear.modes if m not in oscillatory)
    (mode,) = oscillatory
    assert mode.rate_rad_s == pytest.approx(omega, rel=1e-6) and mode.damping_ratio == pytest.approx(zeta, rel=1e-6)

    def limit(g):
        return brentq(lambda h: h * h * g(h) * k + 2 * h * g(h) * c - 4, 0.1 / omega, 4 / omega, xtol=1e-15)

    expected = {
        "euler": limit(lambda h: 1 / m_c + 1 / m_m),
        "implicit": limit(lambda h: 1 / (m_c + h * c) + 1 / (m_m + h * c)),
    }
    expected["implicitfast"] = expected["implicit"]
    assert expected["euler"] * omega == pytest.approx(-2 * zeta + 2 * math.hypot(zeta, 1))  # all explicit
    for name, dt in expected.items():
        assert result.stability[name].limit_dt_measured_s == pytest.approx(dt, rel=LIMIT_RELATIVE), name
        assert result.stability[name].limit_dt_predicted_s == pytest.approx(dt, rel=LIMIT_RELATIVE), name
    # rk4 is explicit in everything: where the damping lives does not matter, the slider's boundary holds
    (row,) = stability.measure_boundaries(("rk4",), (zeta,))
    assert result.stability["rk4"].limit_dt_measured_s * omega == pytest.approx(row.measured_omega_dt, rel=5e-3)
    assert all(result.stability[name].confirmed for name in ("euler", "implicit", "implicitfast", "rk4"))
    # the four integrators compared below; the orders come from the errors alone, so the sweep's timer (half
    # of its cost) is replaced by a constant that leaves them the same. And the trade-off's default grid is
    # swept down to its 10th timestep, 7.25 us (omega dt from 1 down to 0.009: two decades of power law to fit
    # the orders on): its 3 finest, 4.3 to 1.5 us (70 000 to 200 000 steps of the 0.3 s move per integrator),
    # were 3/4 of its CPU (the orders agree with the audit's within 0.023 on these 10, 0.041 on all 13)
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)
    scenario = result.model.split("'")[3]
    case = scenes.case("printer_head", scenario)
    grid = tradeoff.timestep_grid(tradeoff.fastest_rate(case), case.scenario.duration)
    sweep = tradeoff.sweep(
        "printer_head",
        scenario,
        integrators=("euler", "implicit", "implicitfast", "rk4"),
        dts=grid[:10],
        timing_repeats=1,
    )
    compared = [name for name, order in sweep.orders.items() if order is not None and result.orders[name] is not None]
    assert {"euler", "implicit", "implicitfast", "rk4"} <= set(compared)
    for name in compared:
        assert result.orders[name] == pytest.approx(sweep.orders[name], abs=0.1), name


def test_nonlinear_audit_limits_are_the_undamped_oscillators_and_euler_is_first_order(untimed):
    # the softening spring f = -(k1 x + k3 x^3) linearizes at x = 0 to omega = sqrt(k1 / m), undamped;
    # its default scenario has no exact reference, so the orders are checked against the textbook's
    result = audit("nonlinear", tol=1e-3)
    model = mujoco.MjModel.from_xml_path(str(model_files.path("nonlinear")))
    omega = math.sqrt(float(model.jnt_stiffness[0]) / float(model.body("block").mass[0]))
    (mode,) = result.linear.modes
    assert mode.kind == "oscillatory" and mode.rate_rad_s == pytest.approx(omega, rel=1e-6)
    for row in stability.measure_boundaries(("euler", "implicitfast", "rk4"), (0.0,)):
        assert result.stability[row.integrator].limit_dt_measured_s * omega == pytest.approx(
            row.measured_omega_dt, rel=5e-3
        )
    for name, omega_dt in {"euler": 2.0, "implicit": 2.0, "implicitfast": 2.0, "rk4": 2 * math.sqrt(2)}.items():
        assert result.stability[name].limit_dt_measured_s * omega == pytest.approx(omega_dt, rel=LIMIT_RELATIVE), name
        assert result.stability[name].confirmed, name
    assert not result.is_linear and result.reference.converged
    for name in ("euler", "implicit", "implicitfast"):
        assert result.orders[name] == pytest.approx(1.0, abs=0.1), name


def test_kinematics_audit_has_no_limit_because_every_mode_is_rigid(untimed):
    # free slides driven by prescribed forces: no stiffness and no damping, so no timestep is too large
    result = audit("kinematics", tol=1e-3)
    model = mujoco.MjModel.from_xml_path(str(model_files.path("kinematics")))
    assert not np.any(model.jnt_stiffness) and not np.any(model.dof_damping)
    assert result.linear.modes and all(m.kind == "rigid" for m in result.linear.modes)
    assert result.linear.fastest is None
    for limit in result.stability.values():
        assert limit.limit_dt_predicted_s is None and limit.limit_dt_measured_s is None and limit.confirmed is None
        assert "every mode is rigid" in limit.detail
    assert "every mode is rigid" in result.message
    # nothing pushes the slides in the audit's (unforced) runs: q = q0 + v0 t, which every integrator
    # steps exactly, so each error is round-off, eps per step at most
    eps = np.finfo(float).eps
    for row in result.to_dict()["sweep"]:
        assert row["error"] <= 10 * eps * row["steps"], row


@pytest.mark.parametrize(
    "option, message",
    [
        (
            {"dts": "1e-3,2e-3"},
            r"dts takes a sequence of timesteps in seconds, e.g. dts=\[0.002, 0.001\], not the string",
        ),
        ({"dts": "1e-3:1e-2:4"}, "the command line's --dt 'a,b,c' or 'LOW:HIGH:N'"),
        ({"dts": 1e-3}, r"dts takes a sequence of timesteps in seconds, e.g. dts=\[0.002, 0.001\]; got 0.001"),
        ({"integrators": "rk4,euler"}, r"integrators takes a sequence of names, e.g. integrators=\['rk4', 'euler'\]"),
        ({"integrators": []}, "integrators needs at least one of euler"),
    ],
)
def test_the_command_line_s_strings_are_refused_with_the_typed_form(option, message):
    with pytest.raises(BadInputError, match=message):
        audit("slider", **option)


def test_typed_timesteps_and_integrators_are_the_audit_s_grid_largest_first_each_once(untimed):
    result = audit(
        mujoco.MjModel.from_xml_string(chain_xml(1)), integrators=("rk4", "euler", "rk4"), dts=[0.005, 0.02, 0.01, 0.02]
    )
    assert [(r.integrator, r.dt) for r in result.runs] == [
        (name, dt) for name in ("rk4", "euler") for dt in (0.02, 0.01, 0.005)
    ]


def test_bad_input_is_one_error_before_any_work(tmp_path):
    with pytest.raises(BadInputError, match="no such model file or scene 'nowhere.xml'"):
        audit("nowhere.xml")
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body><joint type='hinge'/></body></worldbody>")
    with pytest.raises(BadInputError, match="cannot load"):
        audit(str(broken))
    with pytest.raises(UnknownNameError, match="unknown integrator 'rk5'"):
        audit("slider", integrators=["rk4", "rk5"])
    with pytest.raises(BadInputError, match="tol must be"):
        audit("slider", tol=-1)
    with pytest.raises(BadInputError, match="every dt must be a finite number > 0 s"):
        audit("slider", dts=[0.01, 0.0])
    with pytest.raises(BadInputError, match="unknown keyframe"):
        audit("slider", keyframe="nope")


def test_the_public_signature_types_every_input_without_any():
    import typing

    import springlab

    hints = typing.get_type_hints(springlab.audit)
    assert set(hints) >= {"model", "integrators", "dts", "tol", "duration", "perturb", "keyframe", "settle_s"}
    assert all("Any" not in repr(hint) for hint in hints.values()), hints
