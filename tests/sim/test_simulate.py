"""The simulate path: same numbers as a plain mj_step loop, deterministic, never a silent blow-up."""

import copy
import dataclasses
import math

import mujoco
import numpy as np
import pytest

import springlab
from springlab import scenes
from springlab.errors import DivergedError
from springlab.exact.limits import stability_limit
from springlab.sim.simulate import INTEGRATORS, simulate


def _slider_model(scenario="step"):
    case = scenes.get("slider").case(scenario)
    return case, case.model


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
@pytest.mark.parametrize("scenario", ["step", "harmonic"])
def test_rollout_path_is_bit_identical_to_a_plain_mj_step_loop(integrator, scenario):
    case, model = _slider_model(scenario)
    setup = case.setup(500, 1e-3)
    trajectory = simulate(
        model, integrator=integrator, dt=1e-3, duration=0.5, qpos=setup.qpos, qvel=setup.qvel, control=setup.control
    )
    model.opt.integrator, model.opt.timestep = INTEGRATORS[integrator], 1e-3  # the plain loop's own setting
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:], data.ctrl[:] = setup.qpos, setup.qvel, setup.control
    qpos = [data.qpos.copy()]
    for _ in range(500):
        mujoco.mj_step(model, data)
        qpos.append(data.qpos.copy())
    np.testing.assert_array_equal(trajectory.qpos, np.array(qpos))
    assert trajectory.time[0] == 0.0 and trajectory.time[-1] == pytest.approx(0.5)


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
def test_simulate_never_modifies_its_callers_model(integrator):
    # as mujoco.rollout: one model may serve many runs (a sweep), so no run may leak its setting into it
    _, model = _slider_model("free")
    before = (int(model.opt.integrator), float(model.opt.timestep), model.body_mass.copy(), model.qpos0.copy())
    simulate(model, integrator=integrator, dt=7e-4, duration=0.07)
    after = (int(model.opt.integrator), float(model.opt.timestep), model.body_mass.copy(), model.qpos0.copy())
    assert before[:2] == after[:2]
    np.testing.assert_array_equal(before[2], after[2])
    np.testing.assert_array_equal(before[3], after[3])


def test_runs_are_deterministic():
    a = springlab.run("slider", "harmonic", duration=1.0)
    b = springlab.run("slider", "harmonic", duration=1.0)
    np.testing.assert_array_equal(a.pos["slider"], b.pos["slider"])
    np.testing.assert_array_equal(a.vel["slider"], b.vel["slider"])


def test_a_blow_up_that_mujoco_resets_silently_is_reported_as_divergence():
    # euler at omega*dt = 3 > 2.1: MuJoCo hits its 1e10 limit and auto-resets qpos to 0
    with pytest.raises(DivergedError, match="exceeds the euler stability limit"):
        springlab.run("slider", "free", integrator="euler", dt=0.3, duration=60.0)


def test_the_divergence_step_is_the_first_non_finite_row_of_qpos_or_qvel():
    # a rollout's record (time, qpos, qvel, one more column) summed whole, or qpos and qvel apart when cut: the
    # first row with an inf or nan in qpos or qvel, whatever the other columns hold or a huge finite sum overflows to
    from springlab.sim import simulate as sim

    model = type("Sizes", (), {"nq": 3, "nv": 2, "na": 1})()
    rows = 400

    def record() -> np.ndarray:
        states = np.random.default_rng(1).standard_normal((rows, 7))
        states[:, 0] = np.arange(rows) * 0.01
        return states

    def first_bad(trajectory) -> int | None:
        bad = ~(np.isfinite(trajectory.qpos).all(axis=1) & np.isfinite(trajectory.qvel).all(axis=1))
        return int(np.flatnonzero(bad)[0]) if bad.any() else None

    cases = []
    for row, column, value in [(123, 2, np.nan), (77, 5, -np.inf), (300, 6, np.nan), (10, 1, 1e308)]:
        states = record()
        states[row, column] = value
        states[row + 1, column] = value  # 1e308 twice: the sum overflows, the values are finite
        cases.append(sim._split(model, states, "rk4", 0.01, 0.0))
    cases.append(
        dataclasses.replace(cases[0], qpos=cases[0].qpos[:100], qvel=cases[0].qvel[:100], time=cases[0].time[:100])
    )
    for trajectory in cases:
        assert sim.divergence_step(trajectory) == first_bad(trajectory)
    assert [sim.divergence_step(t) for t in cases] == [123, 77, None, None, None]


def test_growth_below_mujoco_limits_is_still_divergence():
    # rk4 just past its limit grows slowly: no MuJoCo warning yet, but the error dwarfs the signal
    with pytest.raises(DivergedError, match="rk4 stability limit"):
        springlab.run("slider", "undamped", integrator="rk4", dt=0.3, duration=30.0)


def test_discrete_integrator_never_diverges_even_far_past_explicit_limits():
    result = springlab.run("slider", "undamped", integrator="discrete", dt=1.0, duration=100.0)
    assert np.all(np.abs(result.pos["slider"]) <= result.parameters["x0"] + 1e-12)


@pytest.mark.parametrize("zeta", [0.0, 0.05, 1.0, 10.0])
def test_euler_family_limit_is_2zeta_plus_2sqrt_zeta2_plus_1(zeta):
    expected = 2 * zeta + 2 * math.sqrt(zeta**2 + 1)
    for name in ("euler", "implicit", "implicitfast"):
        assert stability_limit(name, zeta) == pytest.approx(expected)


def test_rk4_limit_is_2_sqrt2_undamped():
    # |1 - y^2/2 + y^4/24 + i(y - y^3/6)| = 1 at y = 2 sqrt(2)
    assert stability_limit("rk4", 0.0) == pytest.approx(2 * math.sqrt(2), rel=1e-9)
    assert math.isinf(stability_limit("discrete", 3.0))


def _plain_loop(model, integrator, dt, steps, setup):
    """qpos of `steps` mj_steps on a fresh MjData of a copy of `model` set to `integrator` and `dt`."""
    work = copy.copy(model)
    work.opt.integrator, work.opt.timestep = INTEGRATORS[integrator], dt
    data = mujoco.MjData(work)
    data.qpos[:], data.qvel[:] = setup.qpos, setup.qvel
    controls = np.broadcast_to(np.atleast_2d(setup.control), (steps, work.nu)) if work.nu else None
    qpos = [data.qpos.copy()]
    for k in range(steps):
        if controls is not None:
            data.ctrl[:] = controls[k]  # row k held over step k, as simulate's controls
        mujoco.mj_step(work, data)
        qpos.append(data.qpos.copy())
    return np.array(qpos)


def test_runs_on_the_threads_spare_data_equal_runs_on_fresh_data_across_models():
    # simulate keeps one scratch MjData per thread between runs: a run after a run of another model of the same
    # layout (another stiffness, another timestep), of another layout (the 33-DOF drill string), or after a
    # blow-up must be the run on a fresh MjData, bit for bit
    case, slider = _slider_model("step")
    stiffer = copy.copy(slider)
    stiffer.jnt_stiffness[:] *= 9.0
    drill = scenes.get("drill_string").case("breakaway")
    order = [(slider, case, "rk4", 1e-3), (stiffer, case, "euler", 2e-3), (drill.model, drill, "rk4", 1e-3)]
    with pytest.raises(DivergedError):  # leaves the spare holding a blown-up state
        simulate(stiffer, integrator="euler", dt=1.0, duration=50.0, qvel=[1.0])
    for model, scenario_case, integrator, dt in order + order[::-1]:
        setup = scenario_case.setup(300, dt)
        run = simulate(
            model,
            integrator=integrator,
            dt=dt,
            duration=300 * dt,
            qpos=setup.qpos,
            qvel=setup.qvel,
            control=setup.control if model.nu else None,
        )
        np.testing.assert_array_equal(run.qpos, _plain_loop(model, integrator, dt, 300, setup))
