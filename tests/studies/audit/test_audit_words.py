"""The audit's word for its own setting is what runs show (issue 33, item 3): one word each, and a setting past
a confirmed stability limit is never "stable".

Each case is a model whose RK4 limit is a closed form (omega dt = 2 sqrt(2) for an undamped mode), set to run at
a ratio of it; the word the audit prints is held to what a plain `mj_step` loop written here shows: bounded,
grows then saturates (the pendulum is nonlinear: its amplitude cannot grow forever), spins (a hinge turning over
and over), blows up (a linear chain: nothing bounds it).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from helpers.linear_models import chain_frequencies, chain_xml, pendulum_xml
from springlab.studies.audit.audit import audit
from springlab.studies.audit.parts import BEHAVIOURS

#: RK4's stability limit on an undamped mode: omega dt < 2 sqrt(2)
RK4_LIMIT = 2 * math.sqrt(2)
#: the pendulum's small-swing frequency, sqrt(g / l) with l = 0.5 m [rad/s]
PENDULUM_OMEGA = math.sqrt(9.81 / 0.5)
START = 1e-3  # [rad] or [m]
STEPS = 2000


def _pendulum(ratio: float) -> str:
    dt = ratio * RK4_LIMIT / PENDULUM_OMEGA
    return pendulum_xml().replace("<option ", f'<option integrator="RK4" timestep="{dt!r}" ')


def _chain(ratio: float) -> str:
    dt = ratio * RK4_LIMIT / float(max(chain_frequencies(3, 100.0, 1.0)))
    return chain_xml(3).replace("<option ", f'<option integrator="RK4" timestep="{dt!r}" ')


def plain_run(xml: str) -> tuple[np.ndarray, bool]:
    """The test's own loop: STEPS mj_steps from every joint at START, at rest. Returns (qpos (STEPS, nq), whether
    MuJoCo flagged a bad acceleration or the state left 1e10)."""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    data.qpos[:] = START
    out = np.empty((STEPS, model.nq))
    for k in range(STEPS):
        mujoco.mj_step(model, data)
        out[k] = data.qpos
    bad = (mujoco.mjtWarning.mjWARN_BADQACC, mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL)
    flagged = any(data.warning[int(w)].number for w in bad)
    return out, bool(flagged or not np.all(np.abs(out) < 1e10))


def what_the_loop_shows(xml: str) -> str:
    """One word from the plain loop, by the definitions the audit's docs state."""
    q, flagged = plain_run(xml)
    if flagged:
        return "blows up"
    size = np.max(np.abs(q), axis=1)
    if size.max() > 2 * math.pi:
        return "spins"
    if size.max() < 10 * START:
        return "stable"
    half = len(size) // 2
    return "saturates" if size[half:].max() <= 2 * size[:half].max() else "grows"


@pytest.mark.parametrize(
    ("xml", "word"),
    [
        (_pendulum(0.9), "stable"),
        (_pendulum(1.08), "saturates"),  # issue 33: rk4 at 1.08x its limit was "stable with margin 0.926x"
        (_pendulum(1.5), "spins"),
        (_chain(1.07), "blows up"),
    ],
    ids=["pendulum-0.9x", "pendulum-1.08x", "pendulum-1.5x", "chain-1.07x"],
)
def test_the_own_settings_word_is_what_a_plain_loop_shows(xml, word, untimed):
    assert what_the_loop_shows(xml) == word  # the case is what it claims to be, by the test's own loop
    model = mujoco.MjModel.from_xml_string(xml)
    result = audit(model, keyframe=0 if model.nkey else None, integrators=["rk4"], dts=[0.02, 0.01], duration=20.0)
    limit = result.stability["rk4"]
    assert limit.confirmed
    assert result.own.behaviour == word and word in BEHAVIOURS
    line = next(line for line in result.message.splitlines() if line.startswith("your setting"))
    assert word in line
    past = model.opt.timestep >= limit.limit_dt_s
    assert result.own.stable is (not past) and ("stable with margin" in line) is (not past)
    assert ("UNSTABLE" in line) is past
    assert result.to_dict()["own_setting"]["behaviour"] == word
    assert ("is unstable" in result.answer) is past and (f"a run of it {word}" in result.answer) is past


NOTE_XML = """<mujoco><option timestep="0.002" gravity="0 0 0"/><worldbody>
  <geom name="floor" type="plane" size="1 1 0.1" solref="0.001 1"/>
  <body name="ghost" pos="0 0 1"><joint name="free_swing" type="hinge" solreflimit="0.001 1"/>
    <geom name="visual" type="sphere" size="0.1" contype="0" conaffinity="0" solref="0.001 1"/></body>
  <body name="ball" pos="0 0 0.5"><joint name="stop" type="hinge" range="-30 30" solreflimit="0.001 1"/>
    <geom name="touching" type="sphere" size="0.1" pos="0.2 0 0" solref="0.001 1"/></body>
</worldbody></mujoco>"""


def test_solref_notes_name_only_constraints_that_can_become_active():
    """A time constant of 1 ms is shorter than 2 dt = 4 ms everywhere here; only the floor and the ball's geom
    (which can touch) and the hinge with a range (whose limit can engage) can ever be active."""
    from springlab.studies.audit.limits import constraint_flags

    flagged = {flag.element for flag in constraint_flags(mujoco.MjModel.from_xml_string(NOTE_XML), 0.002)}
    assert flagged == {"geom 'floor'", "geom 'touching'", "joint limit 'stop'"}
