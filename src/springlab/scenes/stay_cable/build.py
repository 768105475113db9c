"""The stay cable's MJCF for any number of nodes: an MjSpec scaffold and the edits that write a cable into it.

`scaffold()` is the model without a cable (options, look, camera, the numerics that hold the physical values)
and `generate(spec, params)` writes the cable of `params` into it (in place): N bodies `n1` ... `nN` on
transverse slide joints of the same names, the string's segments as fixed tendons, the damper, rain-wind's
modal damping and the wind's load. Python computes the values once, here, from the formulas of
springlab.exact.cable; every later computation reads them back from the compiled model.

How the physics is encoded, and why:

* **Segments as fixed tendons with stiffness** T / dx: `segment_i` (i = 0 ... N) is q_{i+1} - q_i, the anchors'
  q_0 = q_{N+1} = 0 dropped, so K = (T / dx) tridiag(-1, 2, -1) exactly and the mass matrix stays diagonal (each
  node on its own slide joint to the world: a step costs O(N), as the drill string's tendon encoding measured).
  Joint springs could only pull a node towards the line (K diagonal), not towards its neighbours. Every
  MuJoCo integrator treats tendon springs explicitly, as it treats joint springs.
* **Intrinsic damping and the damper as joint damping**: a viscous force towards the still line at every node
  (c_s dx, `TautCable.structural_node_damping`) and the damper's coefficient added at the node nearest a.
  Joint damping is what euler, implicit and implicitfast integrate implicitly; tendon damping is not (euler
  treats it explicitly, implicit and implicitfast only its diagonal: measured on the printer head's belt).
* **Rain-wind as modal tendons**: `aero_k` (k = 1 ... aero_modes) has the coefficients sin(j k pi / (N + 1)) and
  the damping d_k of `TautCable.aero_mode_damping` (negative for rain-wind): C += d_k s_k s_k^T, mode k's ratio
  shifted by exactly zeta_a in the model. Dense in C, so every integrator treats it explicitly in part.
* **The wind** is one motor `wind` on the tendon `wind_load` (coefficient 1 on every node) with gear dx: control
  p [N/m] puts the force p dx on every node, a load uniform along the span. A control is held over each step
  (the held noise springlab.exact.random_vibration discretizes exactly).

No gravity, no contact, no sag: the string is straight between its anchors and moves in one transverse plane
(docs/scenes/stay_cable.md says why, and when sag, bending stiffness and the second plane would matter).
"""

from __future__ import annotations

import math
from xml.etree import ElementTree

import mujoco

from springlab.errors import ParameterError
from springlab.exact.cable import TautCable, mode_shape, whole_elements

#: the cable is drawn this long [m] (the note on every frame says how much shorter than it is)
DRAWN_LENGTH = 6.0
#: node spheres' drawn radius [m]
DRAWN_RADIUS = 0.025
#: physical values the compiler cannot derive, kept as <numeric> in the model (SI)
NUMERICS = (
    "length",
    "tension",
    "mass_per_length",
    "damper_position",
    "damper_coefficient",
    "structural_damping_ratio",
    "aero_damping_ratio",
    "aero_modes",
    "wind_intensity",
)


def scaffold() -> mujoco.MjSpec:
    """The stay cable's model without a cable: options, look, camera, numerics.

    implicitfast at 5 ms: a damper on a light node is a fast decay (rate c_d / (m dx), 1500 1/s for the default
    damper on N = 99) that an explicit integrator must resolve (RK4 below 2.8 / rate) and implicitfast
    integrates implicitly (joint damping); the springs limit it to omega_max dt < 2 (1.0 at N = 99).
    No gravity, no contact.
    """
    spec = mujoco.MjSpec()
    spec.modelname = "stay_cable"
    spec.compiler.degree = False
    spec.option.timestep = 0.005
    spec.option.integrator = int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    spec.visual.global_.offwidth = 1920
    spec.visual.global_.offheight = 1080
    spec.visual.quality.shadowsize = 0
    # the node beads are 3 px across in the demo's 480 x 360 view, 14 px at 1920 x 1080: a sphere's facets at
    # MuJoCo's default 28 x 16 made a 480 x 360 frame cost 8.2 ms on llvmpipe, 3.6 ms at 16 x 8, whose chords stay
    # within 0.13 px of the sphere at 1080p (r (1 - cos(pi / 16)), r = 7 px)
    spec.visual.quality.numslices = 16
    spec.visual.quality.numstacks = 8
    for name, rgba in (
        ("cable", [0.15, 0.2, 0.3, 1]),
        ("damper", [0.85, 0.33, 0.18, 1]),
        ("anchor", [0.4, 0.4, 0.42, 1]),
    ):
        spec.add_material(name=name, rgba=rgba)
    spec.worldbody.add_light(
        name="key", pos=[0, -4, 4], dir=[0, 0.6, -0.8], type=int(mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    )
    spec.worldbody.add_camera(name="side", pos=[DRAWN_LENGTH / 2, -7.5, 0.4], xyaxes=[1, 0, 0, 0, 0.05, 1], fovy=45)
    for name, x in (("anchor_deck", 0.0), ("anchor_pylon", DRAWN_LENGTH)):
        anchor = spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=[x, 0, 0], size=[0.06] * 3)
        anchor.material = "anchor"
        anchor.contype = anchor.conaffinity = 0
    for name in NUMERICS:
        spec.add_numeric(name=name, data=[0.0])
    spec.add_text(name="note:length", data="")
    return spec


def remove_cable(spec: mujoco.MjSpec) -> None:
    """Remove a previous cable (its bodies, tendons and actuators) from `spec` (nothing if it has none)."""
    for actuator in list(spec.actuators):
        spec.delete(actuator)
    for tendon in list(spec.tendons):
        spec.delete(tendon)
    for body in list(spec.worldbody.bodies):
        spec.delete(body)


def _check(params: dict[str, float], n: int) -> None:
    """ParameterError for a damper, damping or load no cable has."""
    coefficient = float(params["damper_coefficient"])
    if not (math.isfinite(coefficient) and coefficient >= 0):
        raise ParameterError(f"damper_coefficient must be a finite number >= 0 N s/m, got {coefficient!r}")
    for name in ("structural_damping_ratio", "aero_damping_ratio"):
        if not math.isfinite(float(params[name])):
            raise ParameterError(f"{name} must be a finite number, got {params[name]!r}")
    modes = params["aero_modes"]
    if int(modes) != modes or not 0 <= modes <= n:
        raise ParameterError(f"aero_modes must be a whole number from 0 to n_elements ({n}), got {modes!r}")
    intensity = float(params["wind_intensity"])
    if not (math.isfinite(intensity) and intensity >= 0):
        raise ParameterError(f"wind_intensity must be a finite number >= 0 N^2 s/m^2, got {intensity!r}")


def generate(spec: mujoco.MjSpec, params: dict[str, float]) -> None:
    """Write the cable of `params` into `spec` (a `scaffold()` or a model it made), replacing any cable there.

    Parameters
    ----------
    spec
        the scaffold (or a generated model).
    params
        SI: n_elements (N moving nodes), length [m], tension [N], mass_per_length [kg/m], damper_position [m from
        the anchor x = 0], damper_coefficient [N s/m], structural_damping_ratio [-], aero_damping_ratio [-],
        aero_modes [-], wind_intensity [N^2 s/m^2] (kept as a numeric; the load's samples are the run's).

    Raises
    ------
    ParameterError
        N not a whole number >= 2, a length, tension or mass not finite and > 0, a damper outside the cable or
        negative, a ratio or intensity not finite, aero_modes not a whole number in 0 ... N.
    """
    cable = TautCable(params["length"], params["tension"], params["mass_per_length"])
    n = whole_elements(params["n_elements"])
    node_mass = cable.node_mass(n)
    _check(params, n)
    damper = cable.damper_node(n, params["damper_position"])
    background = cable.structural_node_damping(n, params["structural_damping_ratio"])
    for name in NUMERICS:
        spec.numeric(name).data = [float(params[name])]
    scale = DRAWN_LENGTH / cable.length
    # short enough for a 480-pixel frame: drawn 1:50 along, 1:1 across, so the deflection is 50x the length's scale
    spec.text("note:length").data = f"length 1:{1 / scale:.3g}, deflection 1:1 ({1 / scale:.3g}x exaggerated)"
    remove_cable(spec)
    for j in range(1, n + 1):
        body = spec.worldbody.add_body(name=f"n{j}", pos=[j * cable.spacing(n) * scale, 0.0, 0.0])
        body.explicitinertial = True
        body.mass = node_mass
        body.inertia = [node_mass * 1e-3] * 3  # a slide joint sees only the mass; any positive inertia
        body.ipos = [0.0, 0.0, 0.0]
        body.iquat = [1.0, 0.0, 0.0, 0.0]
        joint = body.add_joint(name=f"n{j}", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
        joint.damping = [background + (float(params["damper_coefficient"]) if j == damper else 0.0), 0.0, 0.0]
        geom = body.add_geom(name=f"n{j}", type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[DRAWN_RADIUS, 0, 0])
        geom.material = "damper" if j == damper else "cable"
        geom.contype = geom.conaffinity = 0
    stiffness = cable.segment_stiffness(n)
    for i in range(n + 1):
        segment = spec.add_tendon(name=f"segment_{i}")
        segment.stiffness = [stiffness, 0.0, 0.0]
        segment.springlength = [0.0, 0.0]
        if i >= 1:
            segment.wrap_joint(f"n{i}", -1.0)
        if i < n:
            segment.wrap_joint(f"n{i + 1}", 1.0)
    for k in range(1, int(params["aero_modes"]) + 1):
        aero = spec.add_tendon(name=f"aero_{k}")
        aero.damping = [cable.aero_mode_damping(n, params["aero_damping_ratio"], k), 0.0, 0.0]
        for j, coefficient in enumerate(mode_shape(n, k), start=1):
            aero.wrap_joint(f"n{j}", float(coefficient))
    load = spec.add_tendon(name="wind_load")
    for j in range(1, n + 1):
        load.wrap_joint(f"n{j}", 1.0)
    wind = spec.add_actuator(name="wind", trntype=mujoco.mjtTrn.mjTRN_TENDON, target="wind_load")
    wind.gear = [cable.spacing(n), 0, 0, 0, 0, 0]
    wind.ctrllimited = False


#: the shipped model's defaults (models/stay_cable.xml), with the sources its header gives
DEFAULTS = {
    "n_elements": 99,
    "length": 300.0,
    "tension": 6.1e6,
    "mass_per_length": 70.0,
    "damper_position": 6.0,
    "damper_coefficient": 3.3e5,
    "structural_damping_ratio": 0.001,
    "aero_damping_ratio": -0.005,
    "aero_modes": 0,
    "wind_intensity": 30.0,
}

HEADER = """<!--
  stay_cable: a long bridge stay (the Erasmus bridge's, Rotterdam), its damper near the deck anchor, the wind.

  GENERATED by springlab.scenes.stay_cable.build.model_xml(DEFAULTS): scaffold() + generate(); do not edit by
  hand (tests/scenes/stay_cable/test_stay_cable_scene.py checks that this file is what the generator writes).
  The scene rewrites the cable for any N from the numerics below (MjSpec edits); this file is the cable at the
  defaults, N = 99.

  The physics: N = 99 bodies n1 ... n99 of mass m dx on transverse slide joints, dx = L / (N + 1) = 3 m; the
  string's restoring force as fixed tendons segment_0 ... segment_99 of stiffness T / dx (q_{i+1} - q_i, the
  anchors fixed), so K = (T / dx) tridiag(-1, 2, -1) with a diagonal mass matrix; intrinsic damping and the
  damper as joint damping (the damper's c_d on the node nearest a: n2 at 6 m); rain-wind's modal damping as
  tendons aero_k (none here: aero_modes = 0, fair weather); the wind's load p [N/m] as the motor `wind` on the
  tendon wind_load (coefficient 1 on every node, gear dx). No gravity, no contact, no sag.

  Defaults, and where they come from (SI):
  * length 300 m: the Erasmus bridge's longest stays, "draden van driehonderd meter lengte" (NRC Handelsblad,
    7 November 1996). The only default with a source on the bridge itself; the others are estimates for a stay
    of that length, not the bridge's design values.
  * tension 6.1 MN: estimated, 55 strands of 15.7 mm (EN 10138-3 Y1860S7: 150 mm^2, 279 kN breaking load) at
    40 % of their breaking load (PTI DC45.1 allows 45 % under permanent load; fib Bulletin 30).
  * mass_per_length 70 kg/m: estimated, the 55 strands (1.172 kg/m each: 64.5 kg/m) and their HDPE pipe (about
    5 kg/m).
  * damper_position 6 m: 2 % of L from the deck anchor, where stay dampers sit (a / L of 1 to 3 %).
  * damper_coefficient 330 kN s/m: the universal optimum for mode 1 there, sqrt(T m) L / (pi a) = 329 kN s/m,
    rounded (the exact optimum of the transcendental equation is 329.1 kN s/m).
  * structural_damping_ratio 0.001: the intrinsic damping of long strand stays, of order 0.1 % (FHWA-HRT-05-083).
  * aero_damping_ratio -0.005: a rain-wind deficit the stay's own 0.1 % cannot cover and a damper at 2 % can;
    used by the modes aero_modes names (0 here; the rain_wind scenario sets 1).
  * wind_intensity 30 N^2 s/m^2: the drag fluctuation rho U C_D D u of 20 m/s wind at 15 % turbulence on the
    0.2 m pipe near 0.5 Hz (von Karman spectrum; rho = 1.25 kg/m^3, C_D = 1.2), two-sided.
  docs/scenes/stay_cable.md derives each and says what the model leaves out (sag, bending, the second plane).

  Drawn, not physics: the length is drawn 1:50 (6 m), the deflection 1:1, so it is exaggerated 50 times along
  the cable; the "note:" text says so on every frame.
-->
"""


def _full_precision(xml: str, spec: mujoco.MjSpec) -> str:
    """`xml` (MjSpec.to_xml, which writes 6 significant digits) with every physical value the generator wrote
    rewritten at full precision (repr), so the file compiles to the same model as the spec."""
    root = ElementTree.fromstring(xml)
    exact = repr
    bodies = {b.name: b for b in spec.bodies if b.name}
    for element in root.iter("body"):
        body = bodies[element.get("name")]
        element.set("pos", " ".join(exact(float(v)) for v in body.pos))
        inertial = element.find("inertial")
        assert inertial is not None
        inertial.set("mass", exact(float(body.mass)))
        inertial.set("diaginertia", " ".join(exact(float(v)) for v in body.inertia))
        joint = element.find("joint")
        assert joint is not None
        joint.set("damping", exact(float(spec.joint(joint.get("name")).damping[0])))
    tendons = {t.name: t for t in spec.tendons}
    for element in root.iter("fixed"):
        tendon = tendons[element.get("name")]
        for key, values in (("stiffness", tendon.stiffness), ("damping", tendon.damping)):
            if element.get(key) is not None:
                element.set(key, exact(float(values[0])))
        for wrap, child in zip(tendon.path, element.findall("joint")):
            child.set("coef", exact(float(wrap.coef)))
    for element in root.iter("general"):
        element.set("gear", exact(float(spec.actuator(element.get("name")).gear[0])))
    for element in root.iter("numeric"):
        element.set("data", " ".join(exact(float(v)) for v in spec.numeric(element.get("name")).data))
    ElementTree.indent(root, space="  ")
    return ElementTree.tostring(root, encoding="unicode") + "\n"


def model_xml(params: dict[str, float] | None = None) -> str:
    """The MJCF text of the cable of `params` (default DEFAULTS, the shipped models/stay_cable.xml), header first.

    Raises
    ------
    ParameterError
        see `generate`.
    """
    spec = scaffold()
    generate(spec, dict(DEFAULTS if params is None else params))
    spec.compile()  # to_xml writes a compiled spec
    return HEADER + _full_precision(spec.to_xml(), spec)
