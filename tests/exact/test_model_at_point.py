"""A model at its operating point (springlab.exact.model_at_point.ModelAtPoint) against closed forms, and the
audit computing each point's linearization once.

References: the fixed-free chain's eigenfrequencies and its M, K in relative coordinates (test_linearize's
closed forms), RK4's one-step map R(dt A) = I + z + z^2/2 + z^3/6 + z^4/24 on a linear model, and a pendulum's
angular acceleration -g/l sin(theta) away from the bottom. Tolerance: centred finite differences on a linear
model are exact to round-off, eps |x| / h relative (~1e-10), so FD_RELATIVE = 1e-7 as in test_linearize.
"""

from __future__ import annotations

import collections
import dataclasses
import math

import mujoco
import numpy as np
import pytest

from helpers.linear_models import FD_RELATIVE, chain_frequencies, chain_xml, pendulum_xml
from springlab.errors import UnknownNameError
from springlab.exact import linearize as linearize_module
from springlab.exact import model_at_point
from springlab.exact.model_at_point import ModelAtPoint
from springlab.exact.operating_point import OperatingPoint
from springlab.studies.audit.audit import audit


def test_the_chain_at_rest_has_the_closed_form_modes_and_mass_matrix():
    n, k, m = 4, 120.0, 0.8
    at = ModelAtPoint.at(mujoco.MjModel.from_xml_string(chain_xml(n, k, m)))
    measured = sorted(mode.frequency_hz * 2 * math.pi for mode in at.linear.modes)
    np.testing.assert_allclose(measured, chain_frequencies(n, k, m), rtol=FD_RELATIVE)
    i = np.arange(n)
    np.testing.assert_allclose(at.linear.M, m * (n - np.maximum.outer(i, i)), rtol=FD_RELATIVE)
    values, vectors = at.linear.eigenvectors
    np.testing.assert_allclose(at.linear.A @ vectors, vectors * values, atol=1e-9 * np.max(np.abs(values)))
    assert at.constraints.smooth and at.constraints.max_abs_qacc == 0.0  # at rest, nothing active


def test_what_depends_on_the_point_alone_is_computed_once_and_the_object_is_frozen():
    at = ModelAtPoint.at(mujoco.MjModel.from_xml_string(chain_xml(2)))
    assert at.linear is at.linear and at.data is at.data and at.constraints is at.constraints
    with pytest.raises(dataclasses.FrozenInstanceError):
        at.point = OperatingPoint.at(at.model)  # type: ignore[misc]


@pytest.mark.parametrize("dt", [1e-3, 0.04])
def test_rk4_map_is_r_of_dt_a_with_or_without_a_reused_scratch_and_the_model_is_untouched(dt):
    model = mujoco.MjModel.from_xml_string(chain_xml(3, 100.0, 1.0, 0.4))
    own = (int(model.opt.integrator), float(model.opt.timestep))
    at = ModelAtPoint.at(model)
    z = dt * at.linear.A
    expected = np.eye(len(z)) + z + z @ z / 2 + z @ z @ z / 6 + z @ z @ z @ z / 24
    fresh = at.one_step_map("rk4", dt)
    np.testing.assert_allclose(fresh, expected, rtol=FD_RELATIVE, atol=FD_RELATIVE)
    at.one_step_map("euler", 3 * dt, at.workspace)  # the workspace keeps another setting from before
    np.testing.assert_array_equal(at.one_step_map("rk4", dt, at.workspace), fresh)
    assert (int(model.opt.integrator), float(model.opt.timestep)) == own


def test_step_maps_resolve_the_name_once_and_give_rk4_s_map_at_each_dt():
    at = ModelAtPoint.at(mujoco.MjModel.from_xml_string(chain_xml(2, 100.0, 1.0, 0.4)))
    maps = at.step_maps("rk4", at.workspace)
    for dt in (1e-3, 0.04):
        z = dt * at.linear.A
        expected = np.eye(len(z)) + z + z @ z / 2 + z @ z @ z / 6 + z @ z @ z @ z / 24
        np.testing.assert_allclose(maps(dt), expected, rtol=FD_RELATIVE, atol=FD_RELATIVE)
    with pytest.raises(UnknownNameError, match="rk4"):  # the message lists the valid names
        at.step_maps("rk5")


def test_rates_away_from_the_bottom_are_the_pendulum_s_angular_acceleration():
    length, gravity, theta = 0.5, 9.81, 0.3
    model = mujoco.MjModel.from_xml_string(pendulum_xml(length))
    at = ModelAtPoint(model, OperatingPoint.at(model, qpos=np.array([theta])))
    qvel, qacc = at.rates
    assert qvel == 0.0
    # a point mass on a massless rod; MuJoCo's inertia at the tip (1e-9 kg m^2) is 1e-8 of m l^2
    assert qacc == pytest.approx(-gravity / length * math.sin(theta), rel=1e-7)
    assert at.data.qacc[0] == pytest.approx(qacc, rel=1e-12)  # the model's own forward pass agrees


def test_the_audit_linearizes_each_model_at_each_point_once(monkeypatch):
    """A claim about the code's work, not its numbers: in one audit() call each model is linearized once at each
    operating point, however many of its steps (prediction, map scan, linearity check, exact reference) read
    the linearization. Counted by wrapping springlab.exact.linearize.linearize where it is defined and where
    ModelAtPoint imported it, so a step that linearized by itself would be counted too."""
    seen: collections.Counter = collections.Counter()
    original = linearize_module.linearize

    def counted(model, point, **kwargs):
        # one key per (model, point) pair: the model's own or its spring-less copy, the operating point or a
        # state along the motion
        seen[(int(model.opt.disableflags), point.label, tuple(point.qpos), tuple(point.qvel))] += 1
        return original(model, point, **kwargs)

    monkeypatch.setattr(model_at_point, "linearize", counted)
    monkeypatch.setattr(linearize_module, "linearize", counted)
    audit(mujoco.MjModel.from_xml_string(chain_xml(2)), integrators=["euler", "rk4", "discrete"], dts=[0.02, 0.01])
    assert seen and max(seen.values()) == 1, seen
    at_point = [key for key in seen if key[1] == "qpos0 (no keyframe)"]
    assert len(at_point) == 2  # the model and its copy without springs (discrete's explicit stiffness)
