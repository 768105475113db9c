"""MuJoCo's linearization of any model (springlab.exact.linearize) against closed forms: a chain of masses
and springs, a pendulum at the bottom and upright, a free body, a sphere resting on a soft contact.

Tolerances: the finite differences are centred with step h = FD_STEP; on a linear model they are
exact up to round-off, eps |x| / h relative (~1e-10); on a smooth nonlinear one the truncation
h^2 |f'''| / 6 adds ~1e-12. Eigenvalues of a well-separated spectrum inherit that error times
their condition number (the chain's is ~1), so 1e-7 relative holds with a wide margin.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from scipy.linalg import expm

from helpers.linear_models import FD_RELATIVE, chain_frequencies, chain_xml, pendulum_xml
from springlab.errors import BadInputError
from springlab.exact import linearize as lin


def test_chain_modes_are_the_closed_form_frequencies():
    n, k, m = 6, 250.0, 0.5
    result = lin.linearize(mujoco.MjModel.from_xml_string(chain_xml(n, k, m)))
    measured = sorted(mode.frequency_hz * 2 * math.pi for mode in result.modes)
    np.testing.assert_allclose(measured, chain_frequencies(n, k, m), rtol=FD_RELATIVE)
    assert all(mode.kind == "oscillatory" and abs(mode.damping_ratio) < FD_RELATIVE for mode in result.modes)
    assert not result.physically_unstable
    assert result.fastest.frequency_hz == max(mode.frequency_hz for mode in result.modes)


def test_chain_mass_and_stiffness_matrices_are_the_closed_forms():
    # relative coordinates: x_i = q_0 + ... + q_i, so M_ij = m (n - max(i, j)); each spring acts on its own q
    n, k, m, d = 4, 80.0, 1.5, 0.3
    result = lin.linearize(mujoco.MjModel.from_xml_string(chain_xml(n, k, m, d)))
    i = np.arange(n)
    np.testing.assert_allclose(result.M, m * (n - np.maximum.outer(i, i)), rtol=FD_RELATIVE)
    np.testing.assert_allclose(result.K, k * np.eye(n), rtol=FD_RELATIVE, atol=FD_RELATIVE * k)
    np.testing.assert_allclose(result.C, d * np.eye(n), rtol=FD_RELATIVE, atol=FD_RELATIVE * d)


@pytest.mark.parametrize("dt", [1e-3, 0.05])
def test_one_step_maps_are_each_integrators_closed_form_map_on_a_linear_chain(dt):
    n, k, m, d = 3, 100.0, 1.0, 0.4
    model = mujoco.MjModel.from_xml_string(chain_xml(n, k, m, d))
    result = lin.linearize(model)
    mass, damping, stiffness = result.M, result.C, result.K
    eye = np.eye(n)

    def semi_implicit(effective):
        # v' = v + dt effective^-1 (-K q - C v), q' = q + dt v'
        kick = np.linalg.solve(effective, np.hstack([-stiffness, -damping]))
        velocity = np.hstack([np.zeros((n, n)), eye]) + dt * kick
        return np.vstack([np.hstack([eye, np.zeros((n, n))]) + dt * velocity, velocity])

    z = dt * result.A
    expected = {
        "euler": semi_implicit(mass + dt * damping),  # joint damping implicit, springs explicit
        "implicit": semi_implicit(mass + dt * damping),
        "implicitfast": semi_implicit(mass + dt * damping),
        "rk4": np.eye(2 * n) + z + z @ z / 2 + z @ z @ z / 6 + z @ z @ z @ z / 24,
    }
    # discrete: (M + dt C + dt^2 K) a = -K q - C v - dt K v, v' = v + dt a, q' = q + dt v'
    accel = np.linalg.solve(
        mass + dt * damping + dt * dt * stiffness, np.hstack([-stiffness, -damping - dt * stiffness])
    )
    velocity = np.hstack([np.zeros((n, n)), eye]) + dt * accel
    expected["discrete"] = np.vstack([np.hstack([eye, np.zeros((n, n))]) + dt * velocity, velocity])
    for name, matrix in expected.items():
        np.testing.assert_allclose(
            lin.one_step_map(model, name, dt), matrix, rtol=FD_RELATIVE, atol=FD_RELATIVE, err_msg=name
        )


def test_pendulum_at_the_bottom_swings_at_sqrt_g_over_l_and_upright_it_topples_at_the_same_rate():
    length, g = 0.5, 9.81
    model = mujoco.MjModel.from_xml_string(pendulum_xml(length))
    bottom = lin.linearize(model, lin.operating_point(model, "bottom"))
    (mode,) = bottom.modes
    assert mode.kind == "oscillatory" and not mode.physically_unstable
    assert mode.frequency_hz * 2 * math.pi == pytest.approx(math.sqrt(g / length), rel=FD_RELATIVE)
    top = lin.linearize(model, lin.OperatingPoint.at(model, qpos=[math.pi]))
    assert top.physically_unstable  # physics, not a numerical failure
    assert top.max_growth_rate == pytest.approx(math.sqrt(g / length), rel=FD_RELATIVE)
    assert [m.kind for m in top.modes] == ["growing", "decaying"]


def test_a_free_body_is_rigid_motion_not_an_instability():
    # six Jordan blocks at lambda = 0: finite differences split them by sqrt(error), which the
    # growth tolerance must cover
    xml = (
        '<mujoco><option gravity="0 0 0"/><worldbody><body pos="0.3 -0.2 1"><freejoint/>'
        '<geom type="box" size="0.1 0.2 0.3" mass="2"/></body></worldbody></mujoco>'
    )
    model = mujoco.MjModel.from_xml_string(xml)
    result = lin.linearize(model)
    assert result.A.shape == (12, 12)
    assert all(mode.kind == "rigid" for mode in result.modes) and not result.physically_unstable
    assert result.fastest is None
    phi = lin.one_step_map(model, "rk4", 0.01)
    np.testing.assert_allclose(phi, np.block([[np.eye(6), 0.01 * np.eye(6)], [np.zeros((6, 6)), np.eye(6)]]), atol=1e-8)


def test_a_sphere_resting_on_a_soft_contact_rings_at_one_over_timeconst_times_dampratio():
    # with constant impedance d = d0 = dwidth, MuJoCo's solref (timeconst, dampratio) makes the
    # contact a mass-spring-damper: d k = 1/(tc^2 zeta^2), d b = 2/tc, whatever the mass (docs: solref)
    tc, zeta, d0, g = 0.05, 0.5, 0.9, 9.81
    rest = g * (1 - d0) * tc**2 * zeta**2  # penetration at rest (docs: solref)
    xml = (
        f'<mujoco><option gravity="0 0 -{g}"/><default><geom condim="1" solref="{tc} {zeta}"'
        f' solimp="{d0} {d0} 0.001"/></default><worldbody><geom type="plane" size="1 1 0.1"/>'
        '<body><joint name="z" type="slide" axis="0 0 1"/><geom type="sphere" size="0.1" mass="3"/>'
        f'</body></worldbody><keyframe><key qpos="{0.1 - rest}"/></keyframe></mujoco>'
    )
    model = mujoco.MjModel.from_xml_string(xml)
    (mode,) = lin.linearize(model).modes
    assert mode.frequency_hz * 2 * math.pi == pytest.approx(1 / (tc * zeta), rel=1e-6)
    assert mode.damping_ratio == pytest.approx(zeta, rel=1e-6)


def test_the_exact_map_is_the_matrix_exponential():
    model = mujoco.MjModel.from_xml_string(chain_xml(2, 10.0, 1.0, 0.1))
    result = lin.linearize(model)
    np.testing.assert_allclose(result.exact_map(0.3), expm(0.3 * result.A))


def test_unknown_keyframe_and_bad_dt_are_bad_input():
    model = mujoco.MjModel.from_xml_string(pendulum_xml())
    with pytest.raises(BadInputError, match="unknown keyframe 'side'; valid: 0 \\(bottom\\), 1 \\(top\\)"):
        lin.operating_point(model, "side")
    with pytest.raises(BadInputError, match="unknown keyframe '7'"):
        lin.operating_point(model, 7)
    with pytest.raises(BadInputError, match="dt must be"):
        lin.one_step_map(model, "euler", -1.0)
