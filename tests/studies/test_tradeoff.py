"""The speed-accuracy trade: batched runs equal single runs, orders match theory, the advice is verified."""

import dataclasses
import json
import math

import numpy as np
import pytest

import springlab
from helpers.timing import constant_time_run
from springlab import scenes
from springlab.cli.main import main
from springlab.errors import BadInputError, DivergedError
from springlab.sim import batch
from springlab.sim.simulate import INTEGRATORS, simulate
from springlab.studies import tradeoff

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: tradeoff.json's recommendation: the keys it always had, and the shared recommendation's (docs/json.md)
RECOMMENDATION_KEYS = {"tol", "integrator", "dt", "max_rel_error", "wall_time_s"} | {
    "verified",
    "cost",
    "ties",
    "near",
    "rejected",
    "text",
}


def _scene_model(scenario, **overrides):
    case = scenes.get("slider").case(scenario, overrides)
    return case, case.model


@pytest.mark.parametrize("scenario", ["step", "harmonic"])
def test_batched_runs_are_bit_identical_to_single_simulate_calls(scenario):
    # per-simulation timestep and integrator in one batch, runs of different lengths
    case, model = _scene_model(scenario)
    configs = [("euler", 0.01), ("implicit", 0.004), ("implicitfast", 0.0025), ("rk4", 0.003), ("discrete", 0.02)]
    jobs = []
    for name, dt in configs:
        steps = round(1.0 / dt)
        jobs.append(batch.Job(model, name, dt, steps, case.setup(steps, dt)))
    for job, batched in zip(jobs, batch.run_batched(jobs)):
        single = simulate(
            model,
            integrator=job.integrator,
            dt=job.dt,
            duration=1.0,
            qpos=job.setup.qpos,
            qvel=job.setup.qvel,
            control=job.setup.control,
        )
        np.testing.assert_array_equal(batched.time, single.time)
        np.testing.assert_array_equal(batched.qpos, single.qpos)
        np.testing.assert_array_equal(batched.qvel, single.qvel)


def test_batched_runs_of_different_models_are_bit_identical_to_single_runs():
    # the extremes table batches sliders of different mass and stiffness (Batch.set_models)
    jobs, models = [], []
    for stiffness, name in ((100.0, "rk4"), (1e6, "euler"), (3.0, "discrete")):
        case, model = _scene_model("free", stiffness=stiffness)
        models.append(model)
        jobs.append(batch.Job(model, name, 1e-4, 700, case.setup(700, 1e-4)))
    for job, batched in zip(jobs, batch.run_batched(jobs)):
        single = simulate(
            job.model,
            integrator=job.integrator,
            dt=job.dt,
            duration=0.07,
            qpos=job.setup.qpos,
            qvel=job.setup.qvel,
            control=job.setup.control,
        )
        np.testing.assert_array_equal(batched.qpos, single.qpos)
        np.testing.assert_array_equal(batched.qvel, single.qvel)


def test_a_batched_blow_up_is_reported_as_divergence_never_as_a_result():
    # euler at omega*dt = 3 > 2.1 blows up; MuJoCo would reset it silently
    case, model = _scene_model("free")
    stable = batch.Job(model, "euler", 0.01, 2000, case.setup(2000, 0.01))
    unstable = batch.Job(model, "euler", 0.3, 2000, case.setup(2000, 0.3))
    good, bad = batch.run_batched([stable, unstable])
    assert not isinstance(good, DivergedError)
    assert isinstance(bad, DivergedError)
    assert "diverged" in str(bad) and "BADQ" in str(bad)


def test_the_sweep_covers_five_integrators_at_12_or_more_timesteps(slider_free_sweep):
    runs = slider_free_sweep.runs
    assert {r.integrator for r in runs} == set(INTEGRATORS)
    for name in INTEGRATORS:
        assert len({r.dt for r in runs if r.integrator == name}) >= 12
    assert not any(r.diverged for r in runs)  # omega*dt <= 1 is inside every stability limit
    assert all(r.wall_time_s > 0 and r.steps == round(5.0 / r.dt) for r in runs)


@pytest.mark.parametrize(
    "name, order", [("euler", 1), ("implicit", 1), ("implicitfast", 1), ("rk4", 4), ("discrete", 1)]
)
def test_observed_order_matches_the_integrators_theoretical_order(slider_free_sweep, name, order):
    assert slider_free_sweep.orders[name] == pytest.approx(order, abs=0.3)


def test_sweep_errors_are_exactly_what_springlab_run_reports(slider_free_sweep):
    for run in slider_free_sweep.runs[::9]:
        result = springlab.run("slider", "free", integrator=run.integrator, dt=run.dt)
        assert run.max_rel_error == result.max_rel_error == max(e.max_rel for e in result.errors.values())
        assert run.verdict is result.verdict


def test_pareto_front_is_exactly_the_non_dominated_runs(slider_free_sweep):
    runs = [r for r in slider_free_sweep.runs if r.run.valid]
    front = slider_free_sweep.pareto

    def dominates(a, b):
        return (
            a.cost <= b.cost
            and a.max_rel_error <= b.max_rel_error
            and (a.cost < b.cost or a.max_rel_error < b.max_rel_error)
        )

    for r in runs:
        dominated = any(dominates(other, r) for other in runs)
        # of runs equal in cost and error (euler, implicit and implicitfast on this slider) the first stands
        twin = any(o is not r and o.cost == r.cost and o.max_rel_error == r.max_rel_error for o in front)
        assert (r in front) == (not dominated and not twin)
    assert [r.cost for r in front] == sorted(r.cost for r in front)
    # counted work: steps x evaluations per step (rk4 4, the others 1) on a one-DOF model
    assert all(r.cost == r.steps * (4 if r.integrator == "rk4" else 1) for r in slider_free_sweep.runs)


def test_recommendation_for_1e_6_is_rk4_verified_and_at_least_as_coarse_as_any_passing_grid_run(slider_free_sweep):
    pick = tradeoff.recommend(slider_free_sweep, 1e-6, timing_repeats=1)
    assert pick.found and pick.integrator == "rk4" and pick.tolerance == 1e-6
    assert pick.dt is not None and pick.error is not None
    # verified: an independent run at that setting meets the tolerance
    again = springlab.run("slider", "free", integrator="rk4", dt=pick.dt, tol=1e-6)
    assert again.passed and pick.error <= 1e-6 and again.max_rel_error == pick.error
    # cheapest in steps: no rk4 grid run with fewer steps meets 1e-6, and the pick is not finer than the grid's best
    rk4 = [r for r in slider_free_sweep.runs if r.integrator == "rk4"]
    passing = [r for r in rk4 if r.max_rel_error <= 1e-6]
    assert pick.dt >= max(r.dt for r in passing)
    assert all(r.max_rel_error > 1e-6 for r in rk4 if r.dt > pick.dt)
    # by hand: RK4's global error omega t (omega dt)^4 / 120 on an amplitude x0 exp(-zeta omega t) peaks at
    # t = 1/(zeta omega) as x0 (omega dt)^4 / (120 e zeta); omega = 10 rad/s, zeta = 0.05
    limit = (1e-6 * 120 * math.e * 0.05) ** 0.25 / 10
    assert 0.85 * limit < pick.dt <= limit


def test_a_tolerance_below_round_off_has_no_recommendation(slider_free_sweep):
    pick = tradeoff.recommend(slider_free_sweep, 1e-16, timing_repeats=1)
    assert not pick.found and pick.integrator is None and pick.dt is None


def test_run_auto_meets_the_tolerance_with_the_recommended_setting(monkeypatch):
    # the pick ranks counted work and the test reads no wall time: the trade-off's timer (its timing runs of every
    # setting again, alone) is the constant of helpers/timing.py; the real one is held by the tests above
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)
    result = springlab.run("slider", "exercise", integrator="auto", tol=1e-5)
    assert result.passed and result.tolerance == 1e-5
    assert result.integrator == "rk4"
    assert result.max_rel_error is not None and result.max_rel_error <= 1e-5


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({}, "needs tol"),
        ({"tol": 1e-6, "dt": 0.01}, "chooses dt itself"),
        ({"tol": -1.0}, "tol must be a finite number > 0"),
    ],
)
def test_auto_rejects_incomplete_requests_with_one_clear_line(kwargs, match):
    with pytest.raises(BadInputError, match=match):
        springlab.run("slider", "exercise", integrator="auto", **kwargs)


def test_tradeoff_cli_json_and_outputs_follow_the_contract(tmp_path, cli, monkeypatch):
    computed = []
    original = tradeoff.tradeoff
    monkeypatch.setattr(tradeoff, "tradeoff", lambda *a, **k: computed.append(original(*a, **k)) or computed[-1])
    code, out, err = cli(
        "tradeoff", "slider", "exercise", "--tol", "1e-4", "--duration", "2", "--json", "--output", str(tmp_path / "t")
    )
    assert code == 0, err
    data = json.loads(out)
    assert {"runs", "orders", "pareto", "recommendation"} <= set(data)
    for row in data["runs"] + data["pareto"]:
        assert {"integrator", "dt", "max_rel_error", "steps", "wall_time_s"} <= set(row)
    assert set(data["orders"]) == set(INTEGRATORS)
    assert set(data["recommendation"]) == RECOMMENDATION_KEYS
    assert data["recommendation"]["max_rel_error"] <= 1e-4
    assert json.loads((tmp_path / "t" / "tradeoff.json").read_text())["runs"] == data["runs"]
    assert (tmp_path / "t" / "tradeoff.png").read_bytes()[:8] == PNG_SIGNATURE
    # the JSON is the trade-off's to_dict(): its attributes, serialised
    (result,) = computed
    assert data == result.to_dict()
    pick = result.recommendation
    assert pick is not None and pick.to_dict(tradeoff.RECOMMENDATION_NAMES) == data["recommendation"]
    assert pick.tolerance == 1e-4 and data["recommendation"]["text"] == pick.text
    assert data["recommendation"]["integrator"] == pick.integrator and data["recommendation"]["dt"] == pick.dt
    # one row per run: the JSON's run rows, plus whether the run is on the Pareto front
    frame = result.to_pandas()
    assert frame.drop(columns="pareto").to_dict("records") == data["runs"]
    assert int(frame["pareto"].sum()) == len(result.pareto) == len(data["pareto"])
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.recommendation = None
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.runs[0].dt = 1.0


def test_tradeoff_cli_rejects_a_scenario_without_exact_reference_or_unknown_names(capsys, monkeypatch):
    assert main(["tradeoff", "nosuchscene"]) == 2
    assert "valid:" in capsys.readouterr().err
    assert main(["tradeoff", "slider", "free", "--tol", "0"]) == 2
    assert "tol must be" in capsys.readouterr().err


def test_run_auto_cli_with_unreachable_tol_exits_2_naming_the_best_reachable(cli, monkeypatch):
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)  # no wall time read (the test above)
    code, _, err = cli("run", "slider", "exercise", "--integrator", "auto", "--tol", "1e-18")
    assert code == 2
    assert err.count("\n") == 1 and "best reached" in err


def test_round_down_never_rounds_a_timestep_up():
    values = np.geomspace(1e-9, 1e3, 20001)
    rounded = np.array([tradeoff.round_down(v) for v in values])
    assert np.all(rounded <= values) and np.all(rounded > 0.89 * values)
    assert tradeoff.round_down(0.006) == 0.006 and tradeoff.round_down(0.0010989) == 0.001


def test_timestep_grid_spans_three_decades_below_omega_dt_1():
    grid = tradeoff.timestep_grid(10.0, 5.0)
    assert len(grid) >= 12 and grid == sorted(grid, reverse=True)
    assert grid[0] == pytest.approx(0.1) and grid[-1] == pytest.approx(1e-4)
    # a long duration raises the smallest dt to keep every run within MAX_SWEEP_STEPS
    long = tradeoff.timestep_grid(10.0, 100.0)
    assert 100.0 / long[-1] <= tradeoff.MAX_SWEEP_STEPS * 1.01 and len(long) >= 12
    assert math.isclose(long[0], 0.1)


def test_a_stop_condition_ends_batched_runs_exactly_where_simulate_ends_them():
    case, model = _scene_model("free")

    def crossed(qpos, qvel):  # the block reaches the relaxed length
        return qpos[:, 0] <= 0.0

    jobs = [batch.Job(model, name, 0.01, 300, case.setup(300, 0.01), crossed) for name in ("euler", "rk4")]
    for job, batched in zip(jobs, batch.run_batched(jobs)):
        single = simulate(
            model,
            integrator=job.integrator,
            dt=0.01,
            duration=3.0,
            qpos=job.setup.qpos,
            qvel=job.setup.qvel,
            control=job.setup.control,
            stop=crossed,
        )
        assert batched.stopped and single.stopped and batched.steps < 300
        np.testing.assert_array_equal(batched.qpos, single.qpos)


def test_a_scenario_without_an_exact_trajectory_cannot_be_swept():
    from springlab.scenes.slider import Slider

    class ChecksOnly(Slider):  # validated by scalar checks alone, like the non-linear scenes
        def reference(self, case, time, *, dt):
            return None

    with pytest.raises(BadInputError, match="no exact reference trajectory.*valid: none in this scene"):
        tradeoff.sweep(ChecksOnly(), "free")


def test_timesteps_a_scene_rejects_are_replaced_by_accepted_ones():
    # a scene whose input switches at t = 4 s accepts only dt dividing 4 s
    def setup(dt):
        return object() if abs(4.0 / dt - round(4.0 / dt)) < 1e-9 else None

    grid = tradeoff._accepted_grid(tradeoff.timestep_grid(None, 12.0), setup)
    assert len(grid) >= 12 and all(setup(dt) is not None for dt in grid)
