"""Sobol indices: the pipeline (SALib sampling, the executor, SALib analysis) recovers the Ishigami
function's analytic indices, and on the printer head the indices are a consistent variance split;
the result is an immutable object whose `to_dict()` is design.json's `sobol` entry."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from springlab.errors import BadInputError
from springlab.studies.design import sobol

#: the printer head's Sobol inputs, in sampling order (its declaration's `sobol`)
PARAMETERS = ("carriage_mass", "belt_stiffness", "damping_ratio", "drive_force", "move_distance")


def ishigami_exact(a: float, b: float) -> tuple[list[float], list[float]]:
    """Analytic first-order and total indices of sin x1 + a sin^2 x2 + b x3^4 sin x1, x ~ U(-pi, pi)^3
    (Ishigami & Homma 1990; Sobol' & Levitan 1999)."""
    v1 = 0.5 * (1 + b * math.pi**4 / 5) ** 2
    v2 = a**2 / 8
    v13 = b**2 * math.pi**8 * (1 / 18 - 1 / 50)
    total = v1 + v2 + v13
    return [v1 / total, v2 / total, 0.0], [(v1 + v13) / total, v2 / total, v13 / total]


def test_ishigami_indices_through_the_executor_are_within_their_intervals_of_the_analytic_values():
    indices = sobol.ishigami(4096, a=7.0, b=0.1, seed=0)
    first, total = ishigami_exact(7.0, 0.1)
    for j, name in enumerate(("x1", "x2", "x3")):
        # the 95 % bootstrap intervals SALib reports, at a fixed seed
        assert abs(indices["S1"][name] - first[j]) <= indices["S1_conf"][name], name
        assert abs(indices["ST"][name] - total[j]) <= indices["ST_conf"][name], name
    # and the intervals are informative: far narrower than the indices they bound
    assert max(indices["ST_conf"].values()) < 0.1


@pytest.mark.slow
def test_printer_head_indices_split_the_variance_consistently():
    study = sobol.run_sobol("printer_head", 64)
    assert study.names == PARAMETERS
    s = study.to_dict()
    assert s["runs"] == 64 * 7 and s["unsettled"] == 0
    conf = s["S1_conf"]
    # first-order shares of one variance cannot add up past 1 (up to their joint sampling error)
    assert s["first_order_sum"] <= 1.0 + math.sqrt(sum(c * c for c in conf.values()))
    for name in PARAMETERS:
        # a property's total effect includes its effect alone
        assert s["ST"][name] + s["ST_conf"][name] >= s["S1"][name] - s["S1_conf"][name], name
        assert s["ST"][name] >= -s["ST_conf"][name]
    assert set(s["ranking"]) == set(PARAMETERS)


@pytest.mark.parametrize("n", [0, 3, 12, 100])
def test_base_samples_must_be_a_power_of_two(n):
    with pytest.raises(BadInputError, match="power of 2"):
        sobol.check_base_samples(n, 5)


def test_design_sobol_json_has_the_documented_entry(small_design_study):
    # the entry `design --sobol 8 --json` prints (tests/studies/design/test_design.py: to_dict is what the
    # command prints)
    entry = small_design_study.to_dict()["sobol"]
    assert {"parameters", "S1", "S1_conf", "ST", "ST_conf", "runs"} <= set(entry)
    assert entry["runs"] == 8 * 7
    for key in ("S1", "S1_conf", "ST", "ST_conf"):
        assert set(entry[key]) == set(PARAMETERS)


def test_sobol_to_dict_and_to_pandas_carry_the_attributes(small_design_study):
    study = small_design_study.sobol
    entry = study.to_dict()
    assert json.loads(json.dumps(entry)) == entry
    assert entry["ranking"] == list(study.ranking) and entry["interactions"] == dict(study.interactions)
    assert entry["first_order_sum"] == study.first_order_sum and entry["runs"] == study.runs
    frame = study.to_pandas()
    assert list(frame.index) == list(study.names)
    for name in study.names:
        row = frame.loc[name]
        assert (row["low"], row["high"]) == study.ranges[name] == tuple(entry["parameters"][name]["range"])
        for key in ("S1", "S1_conf", "ST", "ST_conf"):
            assert row[key] == entry[key][name] == study.indices[key][name]
        assert row["interactions"] == pytest.approx(row["ST"] - row["S1"], abs=1e-15)
        assert row["elasticity"] == study.elasticities[name] and row["unit"] == entry["parameters"][name]["unit"]


def test_sobol_result_cannot_be_changed_once_returned(small_design_study):
    study = small_design_study.sobol
    with pytest.raises(dataclasses.FrozenInstanceError):
        study.seed = 1
    with pytest.raises(TypeError):
        study.indices["S1"]["drive_force"] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        study.positioning_time_s[0] = 0.0


def test_design_sobol_refuses_a_bad_n_before_simulating(cli):
    code, _, err = cli("design", "printer_head", "--sobol", "10")
    assert code == 2 and "power of 2" in err and err.count("\n") == 1
