"""What MuJoCo's documentation says about its dry friction, checked on MuJoCo itself.

springlab's friction-settings study sweeps a setting only for the friction it acts on
(springlab.scenes.friction.scene.SETTINGS: `acts_on`) and skips time constants below two timesteps;
these are the claims it relies on, each from MuJoCo's docs (doc/ in the mujoco package: modeling.rst
"Friction", "Slow slippage", "Solver settings"; XMLreference.rst "impratio", "noslip_iterations";
computation/index.rst "Parameters") or its source (engine_core_constraint.c mj_makeImpedance,
engine_solver.c mj_solNoSlip), checked here on small models built in this file, without springlab.

Where MuJoCo 4.0 does not do what its docs say, the test asserts what it does and says so: the
study measures what MuJoCo does, and the scene's model is built around it.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

G = 9.81
#: the creep of a constant load is a fixed point of MuJoCo's step, reached to round-off after hundreds
#: of constraint time constants; the models below run the solver to tolerance 1e-15 (MuJoCo's default
#: 1e-8 stops Newton at ~4e-9 of the force), so the comparison holds to this relative accuracy
FIXED_POINT = 1e-9

JOINT = """
<mujoco>
  <option timestep="{dt}" integrator="{integrator}" gravity="{force} 0 0" impratio="{impratio}" cone="{cone}"
          noslip_iterations="{noslip}" tolerance="1e-15"/>
  <worldbody>
    <body>
      <joint type="slide" axis="1 0 0" frictionloss="{friction}" solreffriction="{solref}" solimpfriction="{solimp}"/>
      <inertial pos="0 0 0" mass="{mass}" diaginertia="1 1 1"/>
      <geom type="sphere" size="0.05" contype="0" conaffinity="0"/>
    </body>
  </worldbody>
</mujoco>"""

CONTACT = """
<mujoco>
  <option timestep="0.001" integrator="implicitfast" impratio="{impratio}" cone="{cone}" noslip_iterations="{noslip}"
          tolerance="1e-15"/>
  <worldbody>
    <frame euler="0 20 0">
      <geom type="plane" size="1 1 0.1" friction="0.5 0 0" solref="{solref}" solimp="{solimp}"/>
      <body pos="0 0 0.0499">
        {joints}
        <inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/>
        <geom type="box" size="0.05 0.05 0.05" friction="0.5 0 0" solref="{solref}" solimp="{solimp}"/>
      </body>
    </frame>
  </worldbody>
</mujoco>"""
SLIDES = '<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 1 0"/><joint type="slide" axis="0 0 1"/>'


def _joint(**options):
    values = dict(
        dt=1e-3,
        integrator="implicitfast",
        force=1.0,
        impratio=1,
        cone="pyramidal",
        noslip=0,
        friction=2.0,
        solref="0.02 1",
        solimp="0.9 0.95 0.001 0.5 2",
        mass=1.0,
    )
    values.update(options)
    return mujoco.MjModel.from_xml_string(JOINT.format(**values))


def _contact(joints=SLIDES, **options):
    values = dict(impratio=1, cone="elliptic", noslip=0, solref="0.02 1", solimp="0.9 0.95 0.001 0.5 2")
    values.update(options)
    return mujoco.MjModel.from_xml_string(CONTACT.format(joints=joints, **values))


def _run(model, seconds):
    """(qpos, qvel) of every step of a run from rest."""
    data = mujoco.MjData(model)
    steps = round(seconds / model.opt.timestep)
    qpos, qvel = np.empty((steps, model.nq)), np.empty((steps, model.nv))
    for i in range(steps):
        mujoco.mj_step(model, data)
        qpos[i], qvel[i] = data.qpos, data.qvel
    return qpos, qvel


def _creep(model, seconds=3.0):
    """The velocity of the first joint at the end of a run from rest [m/s]: a held block's steady creep."""
    return float(_run(model, seconds)[1][-1, 0])


@pytest.mark.parametrize("integrator", ["Euler", "implicitfast", "RK4"])
@pytest.mark.parametrize("dt", [2e-3, 5e-4])
@pytest.mark.parametrize(
    "timeconst, d0, dw", [(0.02, 0.9, 0.95), (0.005, 0.9, 0.95), (0.02, 0.99, 0.95), (0.02, 0.9, 0.99)]
)
def test_frictionloss_creeps_at_the_documented_first_order_rate_whatever_the_timestep(
    integrator, dt, timeconst, d0, dw
):
    # modeling.rst: a_c + d (b v + k r) = (1 - d) a_u with k = 0, d = solimp[0] and b = 2 / (d_w timeconst)
    # for friction loss; a load f below F then leaves v = (1 - d0) a_u / (d0 b): MuJoCo's model error,
    # the same at every dt (a fixed point of the step)
    force = 1.0
    model = _joint(dt=dt, integrator=integrator, force=force, solref=f"{timeconst} 1", solimp=f"{d0} {dw} 0.001 0.5 2")
    b = 2.0 / (dw * timeconst)
    expected = (1 - d0) * force / (d0 * b)
    assert _creep(model) == pytest.approx(expected, rel=FIXED_POINT)


def test_frictionloss_ignores_the_damping_ratio_and_the_shape_of_solimp():
    # modeling.rst, Friction: "the damping ratio is ignored"; width, midpoint and power "have no effect"
    base = _run(_joint(), 0.5)
    for options in (
        dict(solref="0.02 3"),
        dict(solimp="0.9 0.95 0.05 0.5 2"),
        dict(solimp="0.9 0.95 0.001 0.2 6"),
    ):
        other = _run(_joint(**options), 0.5)
        assert np.array_equal(base[0], other[0]) and np.array_equal(base[1], other[1]), options


def test_impratio_and_the_cone_act_on_contacts_only():
    # XMLreference.rst, impratio: "frictional-to-normal constraint impedance for ... friction cones";
    # cone: "the type of contact friction cone". A joint's friction loss is neither.
    base = _run(_joint(), 0.5)
    for options in (dict(impratio=100), dict(cone="elliptic")):
        other = _run(_joint(**options), 0.5)
        assert np.array_equal(base[1], other[1]), options
    contact = _creep(_contact())
    assert _creep(_contact(impratio=10)) < 0.5 * contact
    assert abs(_creep(_contact(cone="pyramidal")) - contact) > 0.5 * contact


@pytest.mark.parametrize("impratio", [1.0, 10.0, 100.0])
def test_impratio_divides_the_creep_of_an_elliptic_contact(impratio):
    # source (mj_makeImpedance): the friction rows' R is the normal's / impratio; with a flat impedance
    # (d0 = dw = d) each of the box's n = 4 corner contacts adds D = impratio d m / (1 - d), so a load a_u
    # along the surface creeps at v = (1 - d) a_u / (n impratio d b), b = 2 / (d timeconst)
    d, timeconst = 0.9, 0.02
    model = _contact(impratio=impratio, solimp=f"{d} {d} 0.001 0.5 2", solref=f"{timeconst} 1")
    load = G * math.sin(math.radians(20))
    expected = (1 - d) * load / (4 * impratio * d * 2 / (d * timeconst))
    assert _creep(model) == pytest.approx(expected, rel=FIXED_POINT)


def test_an_elliptic_contacts_friction_impedance_is_the_one_at_its_penetration_not_d0():
    # modeling.rst, Friction: friction dimensions of elliptic cones "have zero position violation", so "the
    # impedance is always d0" and the sigmoid's shape has no effect. In MuJoCo 4.0 a contact's impedance is
    # evaluated at the contact's penetration for all its rows (mj_makeImpedance): its width changes the creep
    base = _creep(_contact())
    assert abs(_creep(_contact(solimp="0.9 0.95 0.000001 0.5 2")) - base) > 0.3 * base
    assert abs(_creep(_contact(solref="0.02 2")) - base) > 0.05 * base  # through the penetration, too


def test_noslip_stops_the_creep_of_friction_loss_and_of_elliptic_contacts_but_not_of_pyramidal_ones():
    # modeling.rst, Slow slippage: NoSlip "sets the regularizer to zero for the updated friction dimensions";
    # its sweep (mj_solNoSlip) covers the dry-friction rows of joints too. With pyramidal cones it leaves the
    # creep as it was in MuJoCo 4.0 (measured on this box; the docs do not say so)
    joint = _creep(_joint())
    assert joint > 1e-4 and abs(_creep(_joint(noslip=3))) <= FIXED_POINT * joint
    elliptic = _creep(_contact())
    assert elliptic > 1e-4 and abs(_creep(_contact(noslip=3))) <= FIXED_POINT * elliptic
    pyramidal = _creep(_contact(cone="pyramidal"))
    assert _creep(_contact(cone="pyramidal", noslip=3)) == pytest.approx(pyramidal, rel=1e-6)


def test_noslip_leaves_an_elliptic_contact_alone_when_a_friction_direction_has_no_degree_of_freedom():
    # why the friction scene's block has a lateral joint: without it one friction row of each contact has an
    # empty Jacobian, and NoSlip leaves the contact untouched (measured on MuJoCo 4.0)
    planar = '<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 0 1"/>'
    creep = _creep(_contact(joints=planar))
    assert creep > 1e-4
    assert _creep(_contact(joints=planar, noslip=3)) == pytest.approx(creep, rel=1e-6)


def test_a_time_constant_below_two_timesteps_is_raised_to_two_timesteps():
    # modeling.rst, solref: "at least two times larger than the simulation time step ... enforced internally"
    # (refsafe): the study skips such values, whose runs repeat the run at 2 dt
    dt = 1e-3
    raised = _run(_joint(dt=dt, solref=f"{2 * dt} 1"), 0.3)
    below = _run(_joint(dt=dt, solref=f"{0.5 * dt} 1"), 0.3)
    above = _run(_joint(dt=dt, solref=f"{4 * dt} 1"), 0.3)
    assert np.array_equal(raised[1], below[1])
    assert not np.array_equal(raised[1], above[1])
