"""The drill string's MJCF for any number of elements: MjSpec edits of models/drill_string.xml.

The shipped file is the string at N = 2 (top drive, one rotor `e1`, the bit) and the template: `generate`
replaces its rotor and elements by N - 1 rotors `e1` ... `e<N-1>` and N element tendons, and writes the
parameters into the numerics, inertias, stiffnesses and the bit's frictionloss. Python computes
those values once here, from the parameters, and writes them into the spec; every later computation
reads them back from the compiled model (springlab.scenes.drill_string.lumped).

Two encodings of the same physics (`ENCODINGS`):

* ``"tendons"`` (the scene's): every rotor on its own hinge to the world, element i a fixed tendon
  (angle below minus angle above) with stiffness; the mass matrix is diagonal.
* ``"chain"``: every rotor hinged to the one above, the joint angle the element's twist, the element's
  stiffness the joint's; the mass matrix is dense (each rotor carries the ones below). Kept for the
  scale benchmark only: its bit joint measures twist, so a frictionloss on it would be friction
  inside the last element, not against the rock, and the scene never builds it with friction.
"""

from __future__ import annotations

import math

import mujoco

#: the encodings `generate` writes
ENCODINGS = ("tendons", "chain")
#: the top drive's inertia [kg m^2]: a flywheel this heavy holds its speed whatever the string does
TOP_INERTIA = 1e12
#: the pipe is drawn this many times its diameter (the length is drawn compressed, see the model's note)
DRAWN_DIAMETER_FACTOR = 3.0
#: the drawn BHA's radius [m]
DRAWN_BHA_RADIUS = 0.2
#: MuJoCo refuses deeper body trees: the chain encoding stops below it (the tendon encoding has no such limit)
CHAIN_DEPTH_LIMIT = 1000


def polar_moment(outer_diameter: float, inner_diameter: float) -> float:
    """J_p = pi (D^4 - d^4) / 32 [m^4] of a tube."""
    return math.pi * (outer_diameter**4 - inner_diameter**4) / 32.0


def _inertial(body: mujoco.MjsBody, mass: float, inertia: float) -> None:
    """An explicit inertial [kg, kg m^2] at the body's origin (the geoms are pictures); setting its frame too
    makes MjSpec.to_xml write it, so a saved generated model keeps its physics."""
    body.explicitinertial = True
    body.mass = mass
    body.inertia = [inertia, inertia, inertia]
    body.ipos = [0.0, 0.0, 0.0]
    body.iquat = [1.0, 0.0, 0.0, 0.0]


def _numeric(spec: mujoco.MjSpec, name: str, value: float) -> None:
    spec.numeric(name).data = [float(value)]


def generate(spec: mujoco.MjSpec, params: dict[str, float], *, encoding: str = "tendons") -> None:
    """Rewrite the spec as the string of params["n_elements"] elements (in place).

    Parameters
    ----------
    spec
        a fresh spec of models/drill_string.xml.
    params
        the scene's parameters (SI): n_elements, length [m], shear_modulus [Pa], density [kg/m^3],
        outer_diameter, inner_diameter [m], bit_inertia [kg m^2], bit_friction_torque [N m],
        top_speed_rpm [rpm], spin_up_time [s].
    encoding
        one of ENCODINGS.
    """
    if encoding not in ENCODINGS:
        raise ValueError(f"encoding must be one of {', '.join(ENCODINGS)}, got {encoding!r}")
    n = int(round(params["n_elements"]))
    if encoding == "chain" and n > CHAIN_DEPTH_LIMIT:
        raise ValueError(f"the chain encoding stops at {CHAIN_DEPTH_LIMIT} elements (MuJoCo's body-tree depth)")
    length, jp = params["length"], polar_moment(params["outer_diameter"], params["inner_diameter"])
    h = length / n
    stiffness = params["shear_modulus"] * jp / h
    node = params["density"] * jp * h  # a rotor's share of the pipe
    area = math.pi * (params["outer_diameter"] ** 2 - params["inner_diameter"] ** 2) / 4.0
    node_mass = params["density"] * area * h
    for name in ("length", "shear_modulus", "density", "outer_diameter", "inner_diameter"):
        _numeric(spec, name, params[name])
    _numeric(spec, "top_speed_rpm", params["top_speed_rpm"])
    _numeric(spec, "spin_up_time", params["spin_up_time"])
    drawn = float(spec.numeric("drawn_length").data[0])
    spec.text(
        "note:length"
    ).data = f"length drawn 1:{length / drawn:.3g} ({length:g} m as {drawn:g} m), diameter {DRAWN_DIAMETER_FACTOR:g}x"

    for tendon in list(spec.tendons):
        spec.delete(tendon)
    template = spec.body("e1")
    radius = DRAWN_DIAMETER_FACTOR * params["outer_diameter"] / 2.0
    spec.delete(template)
    top = spec.body("top_drive")
    dz = drawn / n

    def rotor(parent: mujoco.MjsBody, i: int, z: float) -> mujoco.MjsBody:
        body = parent.add_body(name=f"e{i}", pos=[0.0, 0.0, z])
        _inertial(body, node_mass, node)
        body.add_joint(name=f"e{i}", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
        _pipe(body, f"e{i}")
        return body

    def _pipe(body: mujoco.MjsBody, name: str) -> None:
        """The element above the node, drawn as a pipe with a stripe turning with the node."""
        pipe = body.add_geom(
            name=f"{name}_pipe", type=mujoco.mjtGeom.mjGEOM_CYLINDER, pos=[0, 0, dz / 2], size=[radius, dz / 2, 0]
        )
        pipe.material = "pipe"
        for side, sign in (("stripe", 1.0), ("stripe_back", -1.0)):  # two, so one always faces the camera
            stripe = body.add_geom(
                name=f"{name}_{side}",
                type=mujoco.mjtGeom.mjGEOM_BOX,
                pos=[sign * radius, 0, dz / 2],
                size=[0.3 * radius, 0.3 * radius, dz / 2],
            )
            stripe.material = "stripe"

    # the bit node carries half an element of pipe and the BHA; it is rebuilt after the rotors, so the
    # hinges' order (qpos, qvel, the mass matrix) runs from the top drive down to the bit
    bit_inertia = node / 2 + params["bit_inertia"]
    template_joint = spec.joint("bit")
    friction_settings = (list(template_joint.solref_friction), list(template_joint.solimp_friction))
    drawn_geoms = [(g.name, g.type, list(g.size), list(g.pos), g.material) for g in spec.body("bit").geoms]
    spec.delete(spec.body("bit"))

    def make_bit(parent: mujoco.MjsBody, name: str, z: float, stiffness: float = 0.0) -> mujoco.MjsBody:
        body = parent.add_body(name=name, pos=[0.0, 0.0, z])
        _inertial(body, node_mass / 2 + 1.0, bit_inertia)
        joint = body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
        joint.frictionloss = params["bit_friction_torque"] if encoding == "tendons" else 0.0
        joint.solref_friction, joint.solimp_friction = friction_settings
        joint.stiffness = [stiffness, 0.0, 0.0]
        for geom_name, kind, size, pos, material in drawn_geoms:
            geom = body.add_geom(name=geom_name.replace("bit", name, 1), type=kind, size=size, pos=pos)
            geom.material = material
        _pipe(body, f"{name}_element")
        return body

    if encoding == "tendons":
        for i in range(1, n):
            rotor(spec.worldbody, i, -dz * i)
        make_bit(spec.worldbody, "bit", -drawn)
        names = ["top", *(f"e{i}" for i in range(1, n)), "bit"]
        for i in range(n):
            tendon = spec.add_tendon(name=f"element_{i + 1}")
            tendon.stiffness = [stiffness, 0.0, 0.0]
            tendon.wrap_joint(names[i], -1.0)
            tendon.wrap_joint(names[i + 1], 1.0)
        return

    # chain: rebuild the bit below the last rotor; every joint's angle is its element's twist
    parent, z_parent = top, float(top.pos[2])
    for i in range(1, n):
        z = -dz * i
        parent = rotor(parent, i, z - z_parent)
        parent.joints[0].stiffness = [stiffness, 0.0, 0.0]
        z_parent = z
    make_bit(parent, "bit_chain", -drawn - z_parent, stiffness)
