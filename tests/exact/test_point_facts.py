"""The facts at a model's operating point (springlab.exact.point_facts) against closed forms.

References: the undamped fixed-free chain's fastest eigenfrequency omega_max (test_linearize's closed form) with
RK4's stability bound on the imaginary axis, omega dt = 2 sqrt(2), and semi-implicit Euler's, omega dt = 2
(the trace condition of x' = x + dt v', v' = v - dt omega^2 x); free fall under gravity, z(T) = -g T^2 / 2,
which RK4 integrates exactly (its error term is the fifth derivative, zero here); the drift of a point at rest
with acceleration g, g T^2 / 2. Tolerance on the limits: the bisection stops at a ratio of 1 + LIMIT_PRECISION
(1e-4) and MAP_MARGIN (1e-4 on the spectral radius) moves RK4's bound by about 1e-4 / (d|R|/dy = 2.5) relative,
so LIMIT_RELATIVE = 1e-3 is wide.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from helpers.linear_models import chain_frequencies, chain_xml
from springlab.errors import BadInputError
from springlab.exact.map_limits import MAP_MARGIN
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.point_facts import PERTURBED, SCENARIO_START, PointFacts, start_near
from springlab.sim.simulate import Setup

LIMIT_RELATIVE = 1e-3
GRAVITY = 9.81


def _at_rest(at: ModelAtPoint) -> Setup:
    point = at.point
    return Setup(point.qpos, point.qvel, point.act, point.ctrl)


def test_the_chain_s_map_limits_are_the_closed_forms_and_the_map_grows_just_above_them():
    n, k, m = 2, 100.0, 1.0
    at = ModelAtPoint.at(mujoco.MjModel.from_xml_string(chain_xml(n, k, m)))
    facts = PointFacts.measure(
        at, _at_rest(at), 1.0, guesses={"rk4": None, "euler": None}, above=1.02, rest_within=1e-3
    )
    omega = float(max(chain_frequencies(n, k, m)))
    assert facts.smooth and facts.watch.along.smooth and not facts.watch.diverged
    assert facts.drift_m == 0.0 and facts.rest is None  # at rest: no run from the point
    assert facts.maps is not None
    for name, bound in (("rk4", 2 * math.sqrt(2)), ("euler", 2.0)):
        read = facts.maps[name]
        assert read.limit_s is not None and read.above_s is not None
        assert read.limit_s * omega == pytest.approx(bound, rel=LIMIT_RELATIVE), name
        assert read.above_s == pytest.approx(1.02 * read.limit_s, rel=1e-12)
        assert read.growth_above is not None and read.growth_above > 1 + MAP_MARGIN
        # the direction is the eigenvector of the map there, with the eigenvalue's size given
        phi, vector = at.one_step_map(name, read.above_s), read.direction_above
        assert vector is not None
        rayleigh = complex(np.vdot(vector, phi @ vector) / np.vdot(vector, vector))
        np.testing.assert_allclose(phi @ vector, rayleigh * vector, atol=1e-8 * np.max(np.abs(vector)))
        assert abs(rayleigh) == pytest.approx(read.size_above, rel=1e-8)


def test_a_falling_body_drifts_and_its_run_from_the_point_is_free_fall():
    model = mujoco.MjModel.from_xml_string(
        f'<mujoco><option gravity="0 0 {-GRAVITY}" integrator="RK4" timestep="0.01"/><worldbody><body>'
        '<joint name="z" type="slide" axis="0 0 1"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>'
        "</body></worldbody></mujoco>"
    )
    at = ModelAtPoint.at(model)
    duration = 0.5
    facts = PointFacts.measure(at, _at_rest(at), duration, guesses={"rk4": None}, above=1.02, rest_within=1e-3)
    assert facts.drift_m == pytest.approx(GRAVITY * duration**2 / 2, rel=1e-12)
    rest = facts.rest
    assert rest is not None and not isinstance(rest, Exception)
    np.testing.assert_allclose(rest.qpos[:, 0], -GRAVITY * rest.time**2 / 2, atol=1e-12)
    assert rest.time[-1] == pytest.approx(duration)
    assert facts.maps is not None and facts.maps["rk4"].limit_s is None  # no spring, no damping: no limit


def test_a_box_pressed_into_the_floor_has_no_map_since_its_contact_makes_the_map_no_dynamics():
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><geom type="plane" size="1 1 .1"/><body pos="0 0 .049"><freejoint/>'
        '<geom type="box" size=".05 .05 .05" mass="1"/></body></worldbody></mujoco>'
    )
    at = ModelAtPoint.at(model)
    facts = PointFacts.measure(at, _at_rest(at), 0.2, guesses={"rk4": None}, above=1.02, rest_within=1e-3)
    assert not at.constraints.smooth and "contact" in at.constraints.counts
    assert facts.maps is None and not facts.smooth


def test_the_start_is_a_differing_scenario_state_else_the_seeded_perturbed_point():
    at = ModelAtPoint.at(mujoco.MjModel.from_xml_string(chain_xml(3)))
    perturb, duration = 1e-3, 2.0
    start = start_near(at, perturb, duration)
    assert start.source == PERTURBED and start.perturbed
    moved = np.abs(start.setup.qpos - at.point.qpos)  # slide joints: qpos is the tangent coordinate
    assert np.all(moved >= perturb / 2) and np.all(moved <= perturb)
    speed = np.abs(start.setup.qvel - at.point.qvel)
    assert np.all(speed >= perturb / duration / 2) and np.all(speed <= perturb / duration)
    np.testing.assert_array_equal(start_near(at, perturb, duration).setup.qpos, start.setup.qpos)  # seeded
    scenario = Setup(np.array([0.1, 0.0, 0.0]), np.zeros(3))
    given = start_near(at, perturb, duration, scenario)
    assert given.source == SCENARIO_START and not given.perturbed
    np.testing.assert_array_equal(given.setup.qpos, scenario.qpos)
    unmoved = Setup(at.point.qpos.copy(), at.point.qvel.copy())  # a scenario that starts at the point
    assert start_near(at, perturb, duration, unmoved).source == PERTURBED


def test_a_start_past_mujoco_s_limit_is_refused():
    at = ModelAtPoint.at(mujoco.MjModel.from_xml_string(chain_xml(2)))
    with pytest.raises(BadInputError, match="past MuJoCo's limit"):
        start_near(at, 1e-3, 1e-15)  # velocities of perturb / duration ~ 1e12 > 1e10
