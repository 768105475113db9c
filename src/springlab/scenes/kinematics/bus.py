"""The tachograph's touring bus: pictures only, swapped in for the car of models/kinematics.xml.

The chapter's kinematics examples (section 5.2) are about a car, except the
tachograph, which is the v-t record of a touring bus. The vehicle's physics is
one slide joint and the exact mass of its ``<inertial>``; its geoms are
visual only (the model's default sets contype = conaffinity = 0, and an
explicit ``<inertial>`` means geoms add no mass), so swapping them changes no
number of a run, only the picture.

Sizes are a 12 m two-axle-plus-tag touring coach: 12 m long, 2.5 m wide,
3.4 m tall, wheels of radius 0.5 m on three axles.
"""

from __future__ import annotations

import mujoco

__all__ = ["BUS_LENGTH", "CAR_GEOMS", "dress_as_bus"]

#: length of the drawn bus [m]
BUS_LENGTH = 12.0
#: half width [m], floor and roof heights above the road [m] of the bus body
_HALF_WIDTH = 1.25
_FLOOR = 0.45
_ROOF = 3.4
#: wheel radius [m] and the axles' positions along the bus [m] (front axle, tandem rear axles)
_WHEEL_RADIUS = 0.5
_AXLES = (3.3, -2.7, -4.1)
#: the car's geoms in models/kinematics.xml that the bus replaces
CAR_GEOMS = ("body", "cabin", "wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")
#: where the chase camera stands relative to the bus [m], far enough back that 12 m fill half the view,
#: and its tilt: it looks down by atan(_CHASE_TILT) (about 6 degrees) at the middle of the bus's side
_CHASE_TILT = 0.1
_CHASE_POS = (0.0, -24.0, 0.5 * (_FLOOR + _ROOF) + 24.0 * _CHASE_TILT)


def _box(body: mujoco.MjsBody, name: str, centre, half_sizes, material: str) -> None:
    body.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX, pos=list(centre), size=list(half_sizes), material=material)


def dress_as_bus(spec: mujoco.MjSpec) -> None:
    """Replace the car's geoms of body ``vehicle`` in ``spec`` by a bus; move the chase camera back.

    Visual only: the new geoms inherit the model's default (no contact) and the
    body's explicit ``<inertial>`` keeps its mass and inertia, so a run's
    numbers are unchanged (tests/render/test_render_physics.py checks the picture).
    """
    vehicle = spec.body("vehicle")
    for name in CAR_GEOMS:
        spec.delete(spec.geom(name))
    half_length = 0.5 * BUS_LENGTH
    height = _ROOF - _FLOOR
    _box(vehicle, "bus_body", (0.0, 0.0, _FLOOR + 0.5 * height), (half_length, _HALF_WIDTH, 0.5 * height), "body")
    # a row of side windows on each side, and the windscreen at the front (+x, the direction of travel)
    panes = 7
    pane = (BUS_LENGTH - 1.6) / panes  # pitch of the side windows along the bus [m]
    for side, y in (("r", -_HALF_WIDTH - 0.01), ("l", _HALF_WIDTH + 0.01)):
        for k in range(panes):
            x = -half_length + 0.6 + pane * (k + 0.5)
            _box(vehicle, f"bus_window_{side}{k}", (x, y, 2.45), (0.42 * pane, 0.01, 0.55), "glass")
    _box(vehicle, "bus_windscreen", (half_length + 0.01, 0.0, 2.3), (0.01, _HALF_WIDTH - 0.15, 0.8), "glass")
    for i, x in enumerate(_AXLES):
        for side, y in (("r", -_HALF_WIDTH + 0.1), ("l", _HALF_WIDTH - 0.1)):
            vehicle.add_geom(
                name=f"bus_wheel_{side}{i}",
                type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                pos=[x, y, _WHEEL_RADIUS],
                quat=[0.7071067811865476, 0.7071067811865476, 0.0, 0.0],  # axis along y
                size=[_WHEEL_RADIUS, 0.15, 0.0],
                material="wheel",
            )
    chase = spec.camera("chase")
    chase.pos = list(_CHASE_POS)
    chase.alt.xyaxes = [1.0, 0.0, 0.0, 0.0, _CHASE_TILT, 1.0]  # the MJCF gives xyaxes, which win over quat
