"""The audit recognises friction creep (issue 33, item 2): on the test gripper (tests/data/gripper.xml) a box that
Coulomb friction holds slides at a steady speed; the audit names the body and its speed, says integrator and
timestep do not remove it, points to `springlab friction-settings MODEL.xml`, and never calls a setting verified
without saying its error cannot see the creep. "Settle longer" only where a run shows the motion dying out.

References: a plain `mj_step` loop written here (the creep), and the closed-form decay of a damped oscillator.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from helpers.audit import stub_the_timer
from helpers.paths import DATA
from springlab.studies.audit.audit import audit

GRIPPER = DATA / "gripper.xml"
SETTLE_S = 4.0


@pytest.fixture(scope="module")
def gripper_audit():
    with pytest.MonkeyPatch.context() as patch:
        stub_the_timer(patch)  # the module's tests read no wall time
        return audit(str(GRIPPER), settle_s=SETTLE_S, tol=1e-2, integrators=["euler", "rk4"], dts=[0.004, 0.002])


def plain_creep(settle_s: float, duration: float) -> float:
    """The box's mean speed [m/s] over the second half of `duration` after `settle_s`, by a plain mj_step loop
    from keyframe 'grasp' with its controls held."""
    model = mujoco.MjModel.from_xml_path(str(GRIPPER))
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("grasp").id)
    box = model.body("box").id
    marks = {}
    for k in range(round((settle_s + duration) / model.opt.timestep) + 1):
        t = k * model.opt.timestep
        for name, at in (("half", settle_s + duration / 2), ("end", settle_s + duration)):
            if abs(t - at) < model.opt.timestep / 2:
                mujoco.mj_forward(model, data)
                marks[name] = data.xipos[box].copy()
        mujoco.mj_step(model, data)
    return float(np.linalg.norm(marks["end"] - marks["half"]) / (duration / 2))


@pytest.mark.slow
def test_the_audit_names_the_creeping_body_its_speed_and_the_friction_study(gripper_audit):
    findings = gripper_audit.point_state.creep
    assert [f.body for f in findings] == ["box"]
    # settling restarts MuJoCo's solver without its warm start: the speeds agree to a few per cent, not to round-off
    assert findings[0].speed_m_s == pytest.approx(plain_creep(SETTLE_S, gripper_audit.duration), rel=0.05)
    assert findings[0].coulomb_margin > 1
    message = gripper_audit.message
    assert "friction creep: 'box' slides at" in message and "integrator and timestep do not remove it" in message
    assert f"springlab friction-settings {GRIPPER}" in message
    assert "settling longer may bring it to rest" not in message
    for line in [*message.splitlines(), gripper_audit.answer]:
        if "verified" in line:
            assert "does not see the creep" in line, line
    numbers = gripper_audit.question_answer.numbers
    assert numbers["creep_speed_m_s"] == findings[0].speed_m_s
    state = gripper_audit.to_dict()["operating_point_state"]
    assert state["creep"][0]["body"] == "box" and state["settling_helps"] is False


def _oscillator(damping: float) -> str:
    """A 1 kg mass on a 400 N/m spring (20 rad/s), released from 0.1 m by its keyframe."""
    return f"""<mujoco><worldbody><body><joint name="x" type="slide" stiffness="400" damping="{damping}"/>
      <geom type="sphere" size="0.05" mass="1" contype="0" conaffinity="0"/></body></worldbody>
      <keyframe><key qpos="0.1"/></keyframe></mujoco>"""


@pytest.mark.parametrize(("damping", "helps"), [(0.0, False), (8.0, True)])
def test_settle_longer_is_advised_only_where_the_motion_dies_out(tmp_path, damping, helps, untimed):
    # zeta = c / (2 sqrt(k m)) = 0.2: over 0.5 s the amplitude falls by exp(-zeta omega 0.5) = exp(-2), far below
    # half; undamped it keeps its amplitude, so its second half moves as much as its first
    path = tmp_path / "oscillator.xml"
    path.write_text(_oscillator(damping))
    result = audit(str(path), integrators=["rk4"], dts=[0.004, 0.002])
    assert not result.point_state.at_rest and not result.point_state.creep
    assert result.point_state.settling_helps is helps
    message = result.message
    assert ("may bring it to rest" in message) is helps
    assert ("settling longer does not help" in message) is (not helps)
