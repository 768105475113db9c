"""The tolerance of a switched input (road_bump): piecewise systems and the exact input error.

compare.predicted_error carries the errors committed before a switch on with
the new system's exact flow. Checked here against two independent facts:
splitting a run at a "switch" that changes nothing must not change the
prediction, and for RK4 the prediction is the real leading-order error, so the
measured error of a switched run sits at about half the (2x safety) tolerance.
"""

import numpy as np
import pytest

import springlab
from springlab import scenes
from springlab.runs import compare
from springlab.scenes.base import Reference


def _oscillator_reference(time, omega=30.0, zeta=0.1):
    a = np.array([[0.0, 1.0], [-(omega**2), -2 * zeta * omega]])
    lam, vec = np.linalg.eig(a)
    coef = np.linalg.solve(vec, [1.0, 0.0])
    z = (vec @ (coef[:, None] * np.exp(np.outer(lam, time)))).real.T
    return a, z


@pytest.mark.parametrize("integrator", ["rk4", "euler"])
def test_a_switch_that_changes_nothing_leaves_the_prediction_unchanged(integrator):
    time = np.arange(2001) * 1e-3
    a, z = _oscillator_reference(time)
    plain = Reference(pos={"x": z[:, 0]}, vel={"x": z[:, 1]}, system=a, states=z, rows={"x": (0, 1)})
    split = Reference(
        pos={"x": z[:, 0]}, vel={"x": z[:, 1]}, system=a, states=z, rows={"x": (0, 1)}, switches=[(0.7, a), (1.3, a)]
    )
    expected = compare.predicted_error(plain, integrator, 1e-3, time)
    got = compare.predicted_error(split, integrator, 1e-3, time)
    for column in expected:
        assert got[column] == pytest.approx(expected[column], rel=1e-9)


def test_a_switch_off_the_step_grid_is_refused():
    time = np.arange(101) * 1e-3
    a, z = _oscillator_reference(time)
    reference = Reference(
        pos={"x": z[:, 0]}, vel={"x": z[:, 1]}, system=a, states=z, rows={"x": (0, 1)}, switches=[(0.0505, a)]
    )
    with pytest.raises(ValueError, match="not on the step grid"):
        compare.predicted_error(reference, "rk4", 1e-3, time)


@pytest.mark.parametrize("dt", [1e-3, 2e-3])
def test_rk4_error_of_the_switched_bump_is_predicted_not_just_bounded(dt):
    # 0.5 s is on both grids: no input error, the tolerance is 2 x the leading-order prediction
    result = springlab.run("car", "road_bump", integrator="rk4", dt=dt)
    worst = max(e["max_rel"] for e in result.to_dict()["errors"].values())
    assert 0.25 * result.to_dict()["tolerance"] <= worst <= result.to_dict()["tolerance"]


def test_input_error_is_zero_on_the_grid_and_exactly_the_realized_difference_off_it():
    case = scenes.get("car").case("road_bump")
    on_grid = case.reference(np.arange(2001) * 5e-4, dt=5e-4)
    assert all(value == 0.0 for value in on_grid.input_error.values())
    assert on_grid.tolerance_basis == ""
    off_grid = case.reference(np.arange(1429) * 7e-4, dt=7e-4)
    assert off_grid.input_error["wheel_vel"] > 0.0
    assert off_grid.switches[0][0] == pytest.approx(714 * 7e-4)
