"""The friction-settings study: it reads the scene's declaration, separates model from integration error,
and its pick for a tolerance is verified by a run; where nothing meets the tolerance it names the floor."""

from __future__ import annotations

import json
import math
import random

import pytest

import springlab
from springlab.runs.run import prepare
from springlab.scenes import get
from springlab.scenes.capabilities.friction import CONTACT_FRICTION, JOINT_FRICTION
from springlab.studies import friction_settings as study_module
from springlab.studies import settings
from springlab.studies.friction_settings import friction_settings, grid, mujoco_defaults

#: a small grid: each setting at MuJoCo's default and at its last declared value
SCENE = get("friction")
SPEC = SCENE.dry_friction
ENDS = {s.name: (s.mujoco_default, s.values[-1]) for s in SPEC.settings}
INTEGRATORS = ("euler", "rk4")
DTS = (2e-3, 1e-3, 5e-4)


@pytest.fixture(scope="module")
def small_study():
    """The joint decay and the hold on the small grid, picks for 1e-2: computed once for this module (200 runs,
    5 s of CPU on one core, paid by whichever of its readers comes first: they are all marked slow)."""
    return friction_settings(
        "friction", ["coulomb_decay", "incline_hold"], tol=1e-2, integrators=INTEGRATORS, dts=DTS, values=ENDS
    )


@pytest.mark.slow
def test_the_study_sweeps_only_the_settings_that_act_on_each_cases_friction(small_study):
    joint, hold = small_study.cases
    assert joint.friction == JOINT_FRICTION and hold.friction == CONTACT_FRICTION
    assert {s.name for s in joint.settings} == {"solref_timeconst", "solimp_d0", "noslip_iterations"}
    assert {s.name for s in hold.settings} == {s.name for s in SPEC.settings}
    # 2^3 (joint) and 2^5 (contact) settings x 2 integrators x 3 dts, less the time constants MuJoCo would
    # raise to 2 dt (0.002 s at dt = 0.002 s)
    assert len(joint.runs) == 8 * 2 * 3 - 4 * 2 and len(hold.runs) == 32 * 2 * 3 - 16 * 2
    groups = grid(SPEC, SPEC.case("coulomb_decay"), INTEGRATORS, DTS, ENDS)
    assert len(joint.runs) == sum(len(g) for g in groups)
    assert all(b[2] == a[2] / 2 and a[:2] == b[:2] for g in groups for a, b in zip(g, g[1:]))


@pytest.mark.slow
def test_mujocos_defaults_are_the_baseline_and_their_error_is_the_models(small_study):
    integrator, dt = mujoco_defaults()
    assert (integrator, dt) == ("euler", 0.002)  # read from MuJoCo, as MuJoCo's documentation states them
    for case in small_study.cases:
        default = case.default
        assert default is not None and default.integrator == integrator and default.dt == dt
        assert all(default.settings[s.name] == s.mujoco_default for s in case.settings)
        model = case.default_model
        assert model is not None and model.converged and model.model_error > 1e-2
        # the run at MuJoCo's defaults is within 20 % of the model's error: integration adds little to it
        assert abs(default.error - model.model_error) <= 0.2 * model.model_error


@pytest.mark.slow
def test_the_pick_is_the_cheapest_verified_run_and_a_run_of_it_passes(small_study):
    for case in small_study.cases:
        pick = case.pick
        assert pick is not None and pick.found and pick.row.error <= 1e-2
        run = springlab.run(
            "friction", case.scenario, integrator=pick.row.integrator, dt=pick.row.dt, tol=1e-2, **pick.row.settings
        )
        assert run.passed and run.max_rel_error == pytest.approx(pick.error, rel=1e-12)
        # the candidates: valid runs within tol whose measured integration error (where measured) is within it too
        candidates = settings.ranked(
            r
            for r in case.runs
            if r.run.valid and r.error <= 1e-2 and (r.integration_error is None or r.integration_error <= 1e-2)
        )
        ahead = candidates[: candidates.index(pick.row)]
        assert len(ahead) == pick.rejected and all(r.cost <= pick.row.cost for r in ahead)
        assert all(r.cost >= pick.row.cost for r in candidates[len(ahead) :])
        for other in ahead:  # every cheaper candidate fails its own verification
            again = springlab.run(
                "friction", case.scenario, integrator=other.integrator, dt=other.dt, tol=1e-2, **other.settings
            )
            assert not again.passed
        # counted work: steps x evaluations per step (rk4 4) x degrees of freedom x (1 + 0.1 per NoSlip iteration)
        _, chosen, params = prepare("friction", case.scenario, {})
        dofs = SCENE.build(params, chosen).nv
        for r in case.runs:
            noslip = 1 + settings.NOSLIP_ITERATION_WORK * r.settings["noslip_iterations"]
            evaluations = r.steps * (4 if r.integrator == "rk4" else 1)
            assert r.cost == pytest.approx(evaluations * dofs * noslip, rel=1e-12)


@pytest.mark.slow
def test_the_pareto_front_is_sorted_and_undominated(small_study):
    for case in small_study.cases:
        front = case.pareto
        assert [r.cost for r in front] == sorted(r.cost for r in front)
        assert all(b.error < a.error for a, b in zip(front, front[1:]))
        runs = [r for r in case.runs if not r.diverged]
        for point in front:  # no run is both cheaper and more accurate than a point of the front
            assert not any(r.cost < point.cost and r.error < point.error for r in runs)


@pytest.mark.slow
def test_the_pick_is_the_same_however_noisy_the_cpu_timer(small_study, monkeypatch):
    # the module's joint decay, timed by the CPU, against the same case and options timed by noise
    first = small_study.cases[0]
    noise = random.Random(3)
    monkeypatch.setattr(study_module._time, "thread_time", lambda: noise.uniform(0.0, 1.0))
    options = dict(tol=1e-2, integrators=INTEGRATORS, dts=DTS, values=ENDS)
    second = friction_settings("friction", ["coulomb_decay"], **options).cases[0]
    assert first.scenario == second.scenario == "coulomb_decay"
    assert first.pick.found and first.pick.setting == second.pick.setting
    assert first.pick.text == second.pick.text and first.answer() == second.answer()
    assert [r.setting for r in first.pareto] == [r.setting for r in second.pareto]
    assert [r.cpu_time_s for r in first.runs] != [r.cpu_time_s for r in second.runs]  # the noise did arrive


@pytest.mark.slow
def test_noslip_makes_a_held_block_stop_creeping(small_study):
    hold = small_study.cases[1]
    stopped = [
        r
        for r in hold.runs
        if r.settings["noslip_iterations"] > 0 and r.settings["elliptic_cone"] == 1.0 and not r.diverged
    ]
    assert stopped and all(abs(r.values["creep_velocity_m_s"]) <= 1e-12 for r in stopped)


def test_where_no_setting_reaches_the_tolerance_the_study_says_the_floor_is_mujocos():
    study = friction_settings(
        "friction", ["coulomb_decay"], tol=1e-6, integrators=("rk4",), dts=(1e-3, 5e-4), values=ENDS
    )
    case = study.cases[0]
    assert case.pick is not None and not case.pick.found
    assert "MuJoCo's model is the floor" in case.pick.text
    assert study.to_dict()["cases"][0]["pick"]["floor"] == case.pick.text
    best = case.best_model
    assert best.model_error > 1e-6 and f"{best.model_error:.2g}" in case.pick.text


def test_bad_arguments_are_bad_input():
    with pytest.raises(springlab.errors.BadInputError, match="at least two timesteps"):
        friction_settings("friction", dts=(1e-3,))
    with pytest.raises(springlab.errors.BadInputError, match="sweeps"):
        friction_settings("friction", impratio=10.0)
    with pytest.raises(springlab.errors.BadInputError, match="no swept setting"):
        friction_settings("friction", values={"mass": (1.0,)})


def test_the_command_prints_json_and_writes_its_files(tmp_path, cli):
    # in this process (an interpreter's start-up was most of this test; tests/cli/ start real ones)
    out = tmp_path / "settings"
    done = cli(
        "friction-settings",
        "friction",
        "coulomb_decay",
        "--integrators",
        "rk4",
        "--dt",
        "0.001,0.0005",
        "--tol",
        "1e-2",
        "--json",
        "--output",
        out,
    )
    assert done.code == 0, done.err
    data = json.loads(done.out)
    assert set(data) >= {"scene", "tol", "integrators", "dts", "mujoco_default", "runs", "cases", "cost_basis"}
    case = data["cases"][0]
    assert set(case) >= {"default_model_error", "model_errors", "pareto", "pick", "answer", "runs"}
    assert data["runs"] == len(case["runs"]) and all(math.isfinite(r["cpu_time_s"]) for r in case["runs"])
    assert {p.name for p in out.iterdir()} == {
        "friction_settings.json",
        "friction_settings.csv",
        "friction_settings.png",
    }
    assert json.loads((out / "friction_settings.json").read_text())["runs"] == data["runs"]


@pytest.mark.slow
def test_the_study_gives_the_same_errors_on_dask_workers(monkeypatch, dask_cluster):
    monkeypatch.setattr(study_module, "CHUNK_RUNS", 5)  # 16 runs: four chunks travel
    arguments = dict(integrators=("rk4",), dts=(1e-3, 5e-4), values=ENDS)
    local = friction_settings("friction", ["coulomb_decay"], **arguments)
    remote = friction_settings("friction", ["coulomb_decay"], executor=dask_cluster, **arguments)  # 2 workers
    assert len(local.cases[0].runs) == 16
    assert [r.max_rel_error for r in local.cases[0].runs] == [r.max_rel_error for r in remote.cases[0].runs]
    assert [r.values for r in local.cases[0].runs] == [r.values for r in remote.cases[0].runs]


@pytest.mark.slow
def test_the_demo_answers_how_much_mujocos_friction_drifts_and_what_stopping_it_costs(tmp_path, monkeypatch):
    from springlab.demo import report, steps
    from springlab.demo.state import DemoState

    # one of the demo's two integrators beside MuJoCo's default: 2/3 of its runs, the same section and
    # answer lines (rk4 at the smaller timesteps is what meets 1e-2 where euler cannot)
    monkeypatch.setattr(steps, "DEMO_FRICTION_INTEGRATORS", ("rk4",))
    # and its two largest timesteps: still a measured convergence, the same section and answer lines; and of
    # the swept settings NoSlip alone (the one that stops a creep) beside MuJoCo's defaults of the others: every
    # case keeps its default run, its model error and a pick or floor, so its line (the grid of every setting
    # is small_study's above; the contact cases' 2^5 settings were 6.4 of the study's 6.7 s of CPU)
    from springlab.studies import friction_settings as study_module

    full = study_module.friction_settings

    def smaller(*arguments, dts, values, **options):
        values = {name: v if name == "noslip_iterations" else v[:1] for name, v in values.items()}
        return full(*arguments, dts=dts[:2], values=values, **options)

    monkeypatch.setattr(study_module, "friction_settings", smaller)
    state = DemoState(out=tmp_path)
    written = steps.friction_step(state)
    assert {a.path for a in written} == {
        "friction/friction_settings/friction_settings.png",
        "friction/friction_settings/friction_settings.json",
        "friction/friction_settings/friction_settings.csv",
    }
    assert all((tmp_path / a.path).stat().st_size > 0 for a in written)
    answer = next(a for a in written if a.answer)
    assert answer.title == steps.FRICTION_QUESTION
    lines = answer.answer.splitlines()
    assert len(lines) == 4 and all("MuJoCo's defaults" in line for line in lines)
    state.artifacts.extend(written)
    page = report.build_html(state)
    assert "How much does MuJoCo&#x27;s friction drift" in page and "MuJoCo&#x27;s model error" in page
