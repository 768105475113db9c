"""A Case (springlab.scenes.base.Case): a scenario with its resolved parameters and compiled model, shared by every
hook and run of it; its runs are the plain prepare -> build -> setup -> simulate sequence, bit for bit."""

from __future__ import annotations

import dataclasses
import math
import pickle

import numpy as np
import pytest

import springlab
from springlab import scenes
from springlab.exact import analytic
from springlab.sim.simulate import simulate


def test_a_case_runs_the_plain_sequence_bit_for_bit_and_as_springlab_run():
    scene = scenes.get("slider")
    chosen = scene.scenario("harmonic")
    params = scene.resolve(chosen, {"mass": 2.0})
    model = scene.build(params, chosen)
    case = scene.case("harmonic", {"mass": 2.0})
    assert case.params == params
    setup = case.setup(1000, 2e-3)
    plain = simulate(
        model, integrator="rk4", dt=2e-3, duration=2.0, qpos=setup.qpos, qvel=setup.qvel, control=setup.control
    )
    ours = case.simulate("rk4", 2e-3, 2.0)
    np.testing.assert_array_equal(ours.qpos, plain.qpos)
    np.testing.assert_array_equal(ours.qvel, plain.qvel)
    result = springlab.run("slider", "harmonic", integrator="rk4", dt=2e-3, duration=2.0, mass=2.0)
    np.testing.assert_array_equal(result.trajectory.qpos, ours.qpos)
    assert result.case.params == case.params


def test_a_case_is_frozen_keeps_its_own_parameters_and_its_model_serves_every_setting():
    overrides = {"mass": 2.0}
    case = scenes.get("slider").case("free", overrides)
    with pytest.raises(dataclasses.FrozenInstanceError):
        case.model = None  # type: ignore[misc]
    resolved = dict(case.params)
    rebuilt = type(case).compiled(case.scene, case.scenario, resolved)
    resolved["mass"] = 99.0  # the caller's dict is the caller's
    assert rebuilt.params["mass"] == 2.0
    before = (int(case.model.opt.integrator), float(case.model.opt.timestep))
    for integrator, dt in (("euler", 1e-3), ("rk4", 4e-3)):
        case.simulate(integrator, dt, 0.1)
    assert (int(case.model.opt.integrator), float(case.model.opt.timestep)) == before


def test_what_depends_only_on_the_case_is_computed_once():
    case = scenes.get("slider").case("free")
    calls = []

    def compute():
        calls.append(1)
        return object()

    first = case.memo("probe", compute)
    assert case.memo("probe", compute) is first and len(calls) == 1
    m, k, d = case.physical()
    assert case.modes() == [(math.sqrt(k / m), analytic.damping_ratio(m, k, d))]  # the slider's one mode


def test_a_pickled_case_runs_the_same_motion_against_the_closed_form():
    # a case travels to dask workers: its memo is left behind and recomputed, its runs are the same
    case = scenes.get("slider").case("underdamped", {"x0": 0.05})
    case.physical()
    copy = pickle.loads(pickle.dumps(case))
    assert copy.params == case.params and copy.scene.name == case.scene.name
    a, b = case.simulate("rk4", 1e-3, 1.0), copy.simulate("rk4", 1e-3, 1.0)
    np.testing.assert_array_equal(a.qpos, b.qpos)
    m, k, d = copy.physical()
    x, _ = analytic.free_response(a.time, m, k, d, 0.05, case.params["v0"])
    # RK4 at omega dt = 0.02 over 1 s: its global error ~ (omega dt)^4 omega t / 120 of the amplitude, < 1e-8
    np.testing.assert_allclose(a.qpos[:, 0], x, rtol=0, atol=1e-8 * 0.05)
