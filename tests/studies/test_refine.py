"""springlab refine: the three-axis trade reads a scene's declaration, never its name.

The claims: the discretization error it reports is the exact model's gap to the continuum (checked here against
the continuum's roots and the model's own M, K); its observed order is the declared one; every run's error splits
into the two parts it reports; the recommendation is the cheapest run whose parts add up to at most tol, and a
fresh run at that setting confirms it; refining costs twice (per step, and through the stability limit of the
explicit integrators, which w_max growing like N sets); bad input is exit 2.
"""

from __future__ import annotations

import json
import math
import random

import pytest

from springlab import scenes
from springlab.cli.main import main
from springlab.errors import BadInputError
from springlab.runs.run import prepare, run_scenario
from springlab.scenes.drill_string.lumped import LumpedString
from springlab.studies import refine

SIZES = (2, 4, 8)


@pytest.fixture(scope="module")
def study():
    return refine.refine("drill_string", tol=2e-3, sizes=SIZES, integrators=("rk4", "euler", "discrete"))


def test_the_study_reads_the_declaration_of_the_scenes_that_make_one():
    declared = refine.refinable_scenes()
    assert declared == [name for name, scene in scenes.SCENES.items() if scene.refinable is not None]
    with pytest.raises(BadInputError, match="no model size to refine"):
        refine.refine("slider")


def test_the_discretization_error_is_the_exact_models_gap_to_the_continuum(study):
    scene = scenes.get("drill_string")
    for cost in study.sizes:
        _, chosen, params = prepare("drill_string", "modes", {"n_elements": cost.size})
        model = scene.build(params, chosen)
        f_model = LumpedString.of(model).modes()[0][0]
        f_rod = scene.rod(model).frequencies(1)[0]
        assert cost.discretization_error == pytest.approx(abs(f_model / f_rod - 1), rel=1e-12)
    # lumped masses: second order in 1/N, already at these few elements (2.00 measured from 16 to 64)
    assert study.discretization_order == pytest.approx(2.0, abs=0.15)
    assert study.expected_order == 2.0


def test_every_runs_error_splits_into_its_two_parts(study):
    for run in study.runs:
        if run.diverged:
            assert run.error is None and run.error_bound is None
            continue
        assert run.error <= run.error_bound * (1 + 1e-12) + 1e-15  # the triangle inequality, up to round-off
        assert run.discretization_error == next(c.discretization_error for c in study.sizes if c.size == run.size)


def test_the_recommendation_is_the_cheapest_run_within_tol_and_a_fresh_run_confirms_it(study):
    pick = study.recommendation
    assert pick is not None and pick.verified and pick.found
    details = pick.details
    assert details["discretization_error"] + details["integration_error"] == pytest.approx(pick.error, rel=1e-12)
    assert pick.error <= pick.tolerance
    meeting = [r for r in study.runs if r.run.valid and r.error_bound <= pick.tolerance]
    assert pick.row in meeting and details["size"] == pick.row.size
    # the cheapest in counted work: steps x evaluations per step (rk4 4) x degrees of freedom (N + 1 here)
    for run in study.runs:
        assert run.cost == run.steps * (4 if run.integrator == "rk4" else 1) * (run.size + 1)
    cheapest = min(meeting, key=lambda r: (r.cost, r.error_bound))
    # the first candidate verified (the recommendation may be a later one only if a verification failed)
    assert pick.rejected == 0 and pick.row is cheapest
    again = run_scenario("drill_string", "modes", integrator=pick.integrator, dt=pick.dt, n_elements=pick.row.size)
    q = again.quantities
    assert abs(q["mode_1_frequency_hz"] / q["mode_1_frequency_hz_continuum"] - 1) <= pick.tolerance


def test_no_run_beyond_its_stability_limit_is_on_the_front_or_recommended():
    # issue 34: at N = 4, euler at dt = 1 s is 12x past its limit (0.0849 s) and ended before it blew up
    study = refine.refine("drill_string", tol=0.2, sizes=(4, 8), integrators=("euler", "rk4"))
    four = next(c for c in study.sizes if c.size == 4)
    past = [r for r in study.runs if r.size == 4 and r.integrator == "euler" and r.dt == 1.0]
    assert len(past) == 1 and not past[0].diverged and past[0].error_bound <= 0.2
    assert past[0].beyond_limit and past[0].dt > four.stable_dt_s["euler"]
    for run in study.runs:  # beyond_limit is exactly dt above the limit on the size's fastest mode
        limit = next(c for c in study.sizes if c.size == run.size).stable_dt_s[run.integrator]
        assert run.beyond_limit == (limit is not None and run.dt > limit * (1 + 1e-9))
    assert study.pareto and not any(r.beyond_limit or r.diverged for r in study.pareto)
    assert study.recommendation.found and not study.recommendation.row.beyond_limit
    assert all(s["dt"] != 1.0 for s in study.to_dict()["pareto"])


def test_the_same_study_twice_gives_the_same_recommendation_and_front():
    options = dict(tol=0.2, sizes=(4, 8), integrators=("euler", "rk4"))
    first, second = refine.refine("drill_string", **options), refine.refine("drill_string", **options)
    assert first.recommendation.found and first.recommendation.text == second.recommendation.text
    assert first.recommendation.setting == second.recommendation.setting
    assert [r.setting for r in first.pareto] == [r.setting for r in second.pareto]


def test_the_recommendation_is_the_same_however_noisy_the_timer(monkeypatch):
    noise = random.Random(7)
    monkeypatch.setattr(refine, "time_run", lambda job, **options: noise.uniform(1e-6, 1.0))
    options = dict(tol=1e-2, sizes=(2, 4), integrators=("euler", "rk4", "discrete"))
    first, second = refine.refine("drill_string", **options), refine.refine("drill_string", **options)
    assert first.recommendation.found and first.recommendation.setting == second.recommendation.setting
    assert first.recommendation.text == second.recommendation.text
    assert [r.setting for r in first.pareto] == [r.setting for r in second.pareto]
    assert [r.wall_time_s for r in first.runs] != [r.wall_time_s for r in second.runs]


def test_refining_costs_twice_the_stable_dt_of_an_explicit_integrator_falls_like_one_over_n(study):
    rates = {c.size: c.fastest_rate_rad_s for c in study.sizes}
    # w_max of a lumped string ~ 2 c N / L (the top mode's neighbours oscillate in antiphase)
    assert rates[8] / rates[4] == pytest.approx(2.0, rel=0.1)
    for cost in study.sizes:
        assert cost.stable_dt_s["discrete"] is None  # MuJoCo's discrete integrator has no limit on springs
        for name in ("rk4", "euler"):
            limit = cost.stable_dt_s[name]
            assert limit is not None and limit * cost.fastest_rate_rad_s == pytest.approx(
                2 * math.sqrt(2) if name == "rk4" else 2.0, rel=1e-6
            )
    # beyond euler's limit the runs diverge or are far off; discrete's survive everywhere
    assert not any(r.diverged for r in study.runs if r.integrator == "discrete")


def test_the_json_carries_the_documented_keys(study):
    data = study.to_dict()
    assert set(data) >= {
        "scene",
        "scenario",
        "question",
        "size_parameter",
        "runs",
        "sizes",
        "pareto",
        "discretization_order",
        "cost_growth",
        "step_cost_growth",
        "recommendation",
    }
    assert json.loads(json.dumps(data)) == data
    assert set(data["runs"][0]) >= {"size", "integrator", "dt", "error", "discretization_error", "integration_error"}
    assert set(data["runs"][0]) >= {"cost", "beyond_limit"} and "cost_basis" in data
    assert set(data["recommendation"]) >= {"tol", "size", "integrator", "dt", "error", "discretization_error"}
    assert set(data["recommendation"]) >= {"integration_error", "wall_time_s", "verified", "verdict", "error_bound"}
    assert set(data["recommendation"]) >= {"cost", "ties", "near", "rejected", "text"}


@pytest.mark.parametrize(
    "argv, words",
    [
        (["refine", "slider"], "no model size to refine"),
        (["refine", "drill_string", "--question", "bogus"], "valid: mode_1_frequency_hz"),
        (["refine", "drill_string", "--sizes", "0,4"], "n_elements must be"),
        (["refine", "drill_string", "--sizes", "4,x"], "--sizes takes whole numbers"),
        (["refine", "drill_string", "--tol", "-1"], "tol must be"),
        (["refine", "drill_string", "--set", "n_elements=4"], "sets n_elements itself"),
    ],
)
def test_bad_input_is_exit_2_in_one_line(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
