"""What the renderer draws on top of the model's own geoms: springs, dampers, belts, roads and marks.

Pictures only, never physics: the spring of a scene is a joint's or a tendon's
stiffness, so the MJCF declares *what to draw* as custom texts, read once per
video, and MuJoCo computes nothing for them at each physics step:

* ``<text name="spring:NAME" data="SITE1 SITE2 WIDTH R G B A [DX DY DZ]"/>``:
  a coil spring, a helix (GL lines, cheap to draw) whose coil radius is
  ``COIL_RADIUS`` x WIDTH [m], wound between the two sites (offset by DX DY DZ
  [m] in the world) with a number of turns fixed from the first frame, so it
  stretches and compresses with the motion;
* ``<text name="damper:NAME" data="SITE1 SITE2 RADIUS R G B A [DX DY DZ]"/>``:
  a dashpot, a cylinder of radius RADIUS [m] fixed at SITE1 and a rod from
  SITE2 sliding into it; drawn only when the model has damping (a damper with
  zero damping would be a false picture);
* ``<text name="note:NAME" data="ANY TEXT"/>``: a line written on every frame under the label, for
  what the picture changes (e.g. "length drawn 1:250"; :func:`drawn_notes`);
* ``<text name="belt:NAME" data="DRIVE CLAMP WIDTH R G B A"/>``: a toothed
  belt loop around two pulleys at the ends of the travel, its upper span
  clamped at CLAMP (the carriage), its lower span driven at DRIVE (the motor's
  drive point); each pulley carries a spoke turning with its span, so the
  belt's stretch shows as the two spokes disagreeing.

Besides the declared pictures (:class:`Drawings`):

* a road bump (``RoadBump``), declared by the scene for a case (``Scene.drawing``,
  springlab.scenes.capabilities.drawing): the road profile under a wheel, a half-sine
  bump travelling backwards under it at the driving speed;
* distance marks every few metres, labelled, along a world plane named
  ``road`` (the kinematics scene's vehicle on its road);
* :func:`covering_guides`: world geoms named ``rail`` are stretched along
  their length to cover the whole range of motion.
"""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np

from springlab.scenes.capabilities.drawing import RoadBump

__all__ = [
    "SPRING_PREFIX",
    "DAMPER_PREFIX",
    "BELT_PREFIX",
    "NOTE_PREFIX",
    "drawn_notes",
    "COIL_RADIUS",
    "drawn_springs",
    "covering_guides",
    "RoadBump",
    "Drawings",
]

#: prefixes of the MJCF custom texts that declare drawn springs, dampers and belts
SPRING_PREFIX = "spring:"
DAMPER_PREFIX = "damper:"
BELT_PREFIX = "belt:"
NOTE_PREFIX = "note:"
#: coil radius of a drawn spring, in units of its declared width [-]
COIL_RADIUS = 3.5
#: capsule segments per helix turn
SEGMENTS_PER_TURN = 10
#: distance marks along a road: spacing [m] and how far ahead and behind of the body they are drawn [m]
MARK_SPACING = 5.0
MARK_REACH = 40.0
#: colour of a drawn road bump (asphalt patch, warmer than the road so it reads)
BUMP_RGBA = (0.55, 0.38, 0.22, 1.0)

_DECOR = mujoco.mjtCatBit.mjCAT_DECOR


def drawn_notes(model: mujoco.MjModel) -> list[str]:
    """The lines the model asks to be written on every frame (its ``note:`` custom texts), in file order."""
    return [" ".join(fields) for _, fields in _texts(model, NOTE_PREFIX)]


def _texts(model: mujoco.MjModel, prefix: str) -> list[tuple[str, list[str]]]:
    """[(name without prefix, data fields)] of the model's custom texts starting with ``prefix``."""
    out = []
    for i in range(model.ntext):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TEXT, i) or ""
        if name.startswith(prefix):
            start = model.text_adr[i]
            text = bytes(model.text_data[start : start + model.text_size[i] - 1]).decode()  # drop the NUL
            out.append((name[len(prefix) :], text.split()))
    return out


def _declared(model: mujoco.MjModel, prefix: str) -> list[tuple[int, int, float, np.ndarray, np.ndarray]]:
    """[(site id, site id, size [m], rgba, world offset [m])] of one kind of declared picture."""
    out = []
    for _, fields in _texts(model, prefix):
        first, second, size, *rest = fields
        rgba = np.array([float(c) for c in rest[:4]], dtype=np.float32)
        offset = np.array([float(c) for c in rest[4:7]] if len(rest) >= 7 else [0.0, 0.0, 0.0])
        out.append((model.site(first).id, model.site(second).id, float(size), rgba, offset))
    return out


def drawn_springs(model: mujoco.MjModel) -> list[tuple[int, int, float, np.ndarray]]:
    """Springs to draw: [(site id, site id, width [m], rgba)] from the model's ``spring:`` texts."""
    return [(a, b, size, rgba) for a, b, size, rgba, _ in _declared(model, SPRING_PREFIX)]


def covering_guides(model: mujoco.MjModel, states: np.ndarray, margin: float = 0.1) -> mujoco.MjModel:
    """The model, or a copy whose world geoms named ``rail`` reach over the whole range of motion.

    A rail (box or cylinder) is lengthened along its longest axis until it
    covers the bounding-box centres of every moving geom at every frame, plus
    ``margin`` [m]; it is never shortened. ``model`` is not modified.
    """
    rails = [g for g in range(model.ngeom) if model.geom_bodyid[g] == 0 and (model.geom(g).name or "") == "rail"]
    moving = np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)
    if not rails or moving.size == 0:
        return model
    data = mujoco.MjData(model)
    positions = []
    for q in states:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        positions.append(data.geom_xpos[moving].copy())
    centres = np.concatenate(positions)
    covered = model
    for g in rails:
        kind = model.geom_type[g]
        rot = data.geom_xmat[g].reshape(3, 3)
        if kind == mujoco.mjtGeom.mjGEOM_BOX:
            axis = int(np.argmax(model.geom_size[g]))
        elif kind in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE):
            axis = 2
        else:
            continue
        half = 1 if axis == 2 and kind != mujoco.mjtGeom.mjGEOM_BOX else axis
        direction = rot[:, axis]
        along = (centres - data.geom_xpos[g]) @ direction
        length = float(model.geom_size[g][half])
        low, high = min(-length, float(along.min()) - margin), max(length, float(along.max()) + margin)
        if low >= -length and high <= length:
            continue
        if covered is model:
            covered = copy.copy(model)
        covered.geom_size[g][half] = 0.5 * (high - low)
        covered.geom_pos[g] = model.geom_pos[g] + direction * 0.5 * (high + low)  # rails hang on the world body
        covered.geom_rbound[g] = float(np.linalg.norm(covered.geom_size[g]))
        covered.geom_aabb[g][3 + axis] = covered.geom_size[g][half]
    return covered


def _nice_spacing(length: float) -> float:
    """The smallest of 1, 2, 5 x 10^n [m] that is >= ``length`` [m]."""
    decade = 10.0 ** math.floor(math.log10(length))
    return next(m * decade for m in (1.0, 2.0, 5.0, 10.0) if m * decade >= length * (1 - 1e-12))


def _init(scene: mujoco.MjvScene, kind, size, pos, mat, rgba) -> mujoco.MjvGeom | None:
    if scene.ngeom >= scene.maxgeom:
        return None
    geom = scene.geoms[scene.ngeom]
    mujoco.mjv_initGeom(geom, kind, np.asarray(size, float), np.asarray(pos, float), np.asarray(mat, float), rgba)
    geom.category = _DECOR
    scene.ngeom += 1
    return geom


#: the placeholder size, position and frame a connector starts from (mjv_connector sets all three); read-only,
#: made once: a spring is some 80 connectors per frame, and new arrays for each were a third of their cost
_NOWHERE = np.zeros(3)
_NOWHERE.flags.writeable = False
_UNROTATED = np.eye(3).ravel()
_UNROTATED.flags.writeable = False


def _connector(scene: mujoco.MjvScene, kind, width: float, start, end, rgba) -> mujoco.MjvGeom | None:
    geom = _init(scene, kind, _NOWHERE, _NOWHERE, _UNROTATED, rgba)  # np.asarray passes the float arrays through
    if geom is not None:
        mujoco.mjv_connector(geom, kind, width, np.asarray(start, float), np.asarray(end, float))
    return geom


def _perpendiculars(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to ``axis`` and to each other."""
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


class Drawings:
    """Everything drawn on top of one model's geoms for one video; ``add`` appends a frame's geoms.

    Parameters
    ----------
    model:
        The model being filmed (its custom texts declare the pictures).
    states:
        The drawn ``qpos`` of every frame, shape ``(n, nq)``: spring turns are
        fixed from the first frame's length, the belt's pulleys from the range of travel.
    road_bump:
        Optional :class:`RoadBump` under a quarter car.
    view_height:
        Height of the view [px]: spring wires are GL lines of about 1/160 of it.
    """

    def __init__(
        self, model: mujoco.MjModel, states: np.ndarray, road_bump: RoadBump | None = None, view_height: int = 480
    ):
        self.model = model
        self.line_width = max(2.0, round(view_height / 160))
        self.springs = _declared(model, SPRING_PREFIX)
        damped = float(np.sum(model.dof_damping)) + float(np.sum(model.tendon_damping)) > 0.0
        self.dampers = _declared(model, DAMPER_PREFIX) if damped else []
        data = mujoco.MjData(model)
        data.qpos[:] = states[0]
        mujoco.mj_kinematics(model, data)
        # turns from the first frame: about one coil diameter of length per turn, then fixed so the coil stretches
        self.turns = [
            int(np.clip(round(np.linalg.norm(data.site_xpos[b] - data.site_xpos[a]) / (2 * COIL_RADIUS * w)), 4, 14))
            for a, b, w, _, _ in self.springs
        ]
        self.belts = [
            self._belt_geometry(model, states, a, b, w, rgba) for a, b, w, rgba, _ in _declared(model, BELT_PREFIX)
        ]
        self.road_bump = road_bump
        self._road = self._road_geometry(model, data, road_bump) if road_bump is not None else None
        self._marks = self._mark_geometry(model)
        self._anchors = [
            data.site_xpos[s] + offset
            for prefix in (SPRING_PREFIX, DAMPER_PREFIX)
            for a, b, _, _, offset in _declared(model, prefix)
            for s in (a, b)
            if model.site_bodyid[s] == 0
        ]
        for belt in self.belts:
            zc = 0.5 * (belt["z_upper"] + belt["z_lower"])
            for x in (belt["x_left"], belt["x_right"]):
                self._anchors.extend([[x - belt["radius"], belt["y"], zc], [x + belt["radius"], belt["y"], zc]])
        #: draw distance ticks along the rails (set when the camera follows a long travel)
        self.rail_marks = False
        self._rails = [
            g for g in range(model.ngeom) if model.geom_bodyid[g] == 0 and (model.geom(g).name or "") == "rail"
        ]
        moving = np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)
        largest = float(2.0 * np.max(model.geom_aabb[moving, 3:])) if moving.size else 1.0
        self._rail_spacing = _nice_spacing(largest)

    def anchors(self) -> np.ndarray:
        """(k, 3) world points [m] the camera should keep in view: fixed spring ends, belt pulleys."""
        return np.array(self._anchors, dtype=float).reshape(-1, 3)

    # -- geometry fixed for the whole video

    @staticmethod
    def _belt_geometry(model, states, drive, clamp, width, rgba) -> dict:
        data = mujoco.MjData(model)
        xs = []
        for q in (states[0], *states[1:]):
            data.qpos[:] = q
            mujoco.mj_kinematics(model, data)
            xs.extend([data.site_xpos[drive][0], data.site_xpos[clamp][0]])
        data.qpos[:] = states[0]
        mujoco.mj_kinematics(model, data)
        upper, lower = data.site_xpos[clamp].copy(), data.site_xpos[drive].copy()
        radius = 0.5 * abs(upper[2] - lower[2])
        reach = max(8 * radius, 0.02)
        return dict(
            drive=drive,
            clamp=clamp,
            width=width,
            rgba=rgba,
            radius=radius,
            y=float(upper[1]),
            z_upper=float(upper[2]),
            z_lower=float(lower[2]),
            x_left=float(min(xs)) - reach,
            x_right=float(max(xs)) + reach,
            drive_x0=float(lower[0]),
            clamp_x0=float(upper[0]),
        )

    @staticmethod
    def _road_geometry(model, data, bump: RoadBump) -> dict:
        ground = next(
            (
                g
                for g in range(model.ngeom)
                if model.geom_bodyid[g] == 0 and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_BOX
            ),
            None,
        )
        top = float(model.geom_pos[ground][2] + model.geom_size[ground][2]) if ground is not None else 0.0
        half_width = float(model.geom_size[ground][1]) if ground is not None else 1.0
        fade = None
        if bump.other_axle_geom:  # midway between the bumped wheel and the other axle
            fade = 0.5 * float(
                data.geom_xpos[model.geom(bump.wheel_geom).id][0]
                + data.geom_xpos[model.geom(bump.other_axle_geom).id][0]
            )
        track = float(data.geom_xpos[model.geom(bump.wheel_geom).id][1])  # the wheel's lateral position [m]
        return dict(top=top, half_width=half_width, fade=fade, track=track)

    @staticmethod
    def _mark_geometry(model) -> dict | None:
        for g in range(model.ngeom):
            if model.geom_bodyid[g] == 0 and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE:
                if (model.geom(g).name or "") == "road":
                    return dict(z=float(model.geom_pos[g][2]), half_width=float(model.geom_size[g][1]))
        return None

    # -- per frame

    def add(self, scene: mujoco.MjvScene, data: mujoco.MjData) -> None:
        """Append this frame's pictures (kinematics of ``data`` already computed) to ``scene``."""
        for (a, b, width, rgba, offset), turns in zip(self.springs, self.turns):
            self._helix(
                scene, data.site_xpos[a] + offset, data.site_xpos[b] + offset, width, turns, rgba, self.line_width
            )
        for a, b, radius, rgba, offset in self.dampers:
            self._damper(scene, data.site_xpos[a] + offset, data.site_xpos[b] + offset, radius, rgba)
        for belt in self.belts:
            self._belt(scene, data, belt)
        if self._road is not None:
            self._bump(scene, data)
        if self._marks is not None:
            self._distance_marks(scene, data)
        if self.rail_marks:
            self._rail_ticks(scene, data)

    def _rail_ticks(self, scene, data) -> None:
        """Ticks every ``_rail_spacing`` [m] along the rails near the moving body, labelled with x [m]."""
        moving = np.flatnonzero(self.model.body_weldid != 0)
        x = float(data.xpos[moving[0]][0]) if moving.size else 0.0
        spacing = self._rail_spacing
        dark = np.array([0.1, 0.1, 0.1, 1.0], np.float32)
        for g in self._rails:
            centre, half = data.geom_xpos[g], float(np.max(self.model.geom_size[g]))
            low, high = max(centre[0] - half, x - 8 * spacing), min(centre[0] + half, x + 8 * spacing)
            top = float(centre[2] + self.model.geom_aabb[g][5])
            for at in np.arange(math.ceil(low / spacing) * spacing, high, spacing):
                geom = _init(
                    scene,
                    mujoco.mjtGeom.mjGEOM_BOX,
                    [0.02 * spacing, 0.02, 0.0015],
                    [at, centre[1], top],
                    np.eye(3).ravel(),
                    dark,
                )
                if geom is not None:
                    geom.label = f"{at:.2g} m"

    @staticmethod
    def _helix(scene, start, end, width, turns, rgba, line_width) -> None:
        axis = end - start
        length = float(np.linalg.norm(axis))
        if length <= 0:
            return
        axis = axis / length
        u, v = _perpendiculars(axis)
        radius = COIL_RADIUS * width
        lead = min(0.1 * length, 2 * radius)  # straight ends hooked onto the anchors
        n = turns * SEGMENTS_PER_TURN
        s = np.linspace(0.0, 1.0, n + 1)
        phase = 2 * np.pi * turns * s
        ramp = np.minimum(1.0, np.minimum(s, 1 - s) * n / 2)  # the coil opens over the first half turn
        points = (
            start
            + np.outer(lead + s * (length - 2 * lead), axis)
            + radius * (np.outer(ramp * np.cos(phase), u) + np.outer(ramp * np.sin(phase), v))
        )
        points = np.vstack([start, points, end])
        for p, q in zip(points[:-1], points[1:]):  # GL lines: a tenth of a capsule's cost on a CPU rasteriser
            if _connector(scene, mujoco.mjtGeom.mjGEOM_LINE, line_width, p, q, rgba) is None:
                return

    @staticmethod
    def _damper(scene, start, end, radius, rgba) -> None:
        axis = end - start
        length = float(np.linalg.norm(axis))
        if length <= 0:
            return
        axis = axis / length
        body = 0.55 * length  # the cylinder holds a bit over half the length; the rod slides into it
        _connector(scene, mujoco.mjtGeom.mjGEOM_CYLINDER, radius, start, start + body * axis, rgba)
        rod_rgba = np.array([0.75, 0.75, 0.78, 1.0], np.float32)
        _connector(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, 0.35 * radius, start + 0.8 * body * axis, end, rod_rgba)

    @staticmethod
    def _belt(scene, data, belt) -> None:
        y, r, w, rgba = belt["y"], belt["radius"], belt["width"], belt["rgba"]
        zu, zl = belt["z_upper"], belt["z_lower"]
        left, right = belt["x_left"], belt["x_right"]
        for z in (zu, zl):
            _connector(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, w, [left, y, z], [right, y, z], rgba)
        zc = 0.5 * (zu + zl)
        quarter_turn = np.array([1.0, 0, 0, 0, 0, -1.0, 0, 1.0, 0])  # cylinder axis along y
        pulley_rgba = np.array([0.55, 0.56, 0.6, 1.0], np.float32)
        moved = (
            data.site_xpos[belt["drive"]][0] - belt["drive_x0"],  # the motor pulley turns with the drive point
            data.site_xpos[belt["clamp"]][0] - belt["clamp_x0"],  # the idler turns with the carriage's span
        )
        for x, travel in zip((left, right), moved):
            _init(scene, mujoco.mjtGeom.mjGEOM_CYLINDER, [r - w, 0.6 * r, 0], [x, y, zc], quarter_turn, pulley_rgba)
            angle = -travel / max(r, 1e-9)  # belt travel = radius x angle
            tip = np.array([x + (r - 2 * w) * math.sin(angle), y - 0.65 * r, zc + (r - 2 * w) * math.cos(angle)])
            _connector(scene, mujoco.mjtGeom.mjGEOM_CAPSULE, 0.6 * w, [x, y - 0.65 * r, zc], tip, rgba)

    def _bump(self, scene, data) -> None:
        bump, road = self.road_bump, self._road
        assert bump is not None and road is not None  # the bump is drawn only when the scene has one
        wheel_x = float(data.geom_xpos[self.model.geom(bump.wheel_geom).id][0])
        start = wheel_x - bump.speed * float(data.time)  # where the bump begins (it reached the wheel at t = 0)
        fade = road["fade"]  # quarter car: the bump is not drawn under the other axle, which it does not move
        segments = 16
        edges = start + np.linspace(0.0, bump.length, segments + 1)
        heights = bump.exaggeration * bump.height * np.sin(np.pi * (edges - start) / bump.length)
        rgba = np.array(BUMP_RGBA, np.float32)
        y, half_y = road["track"] - 0.4, 0.25  # a strip along the track, just in front of the tire (not hidden by it)
        for x0, x1, h0, h1 in zip(edges[:-1], edges[1:], heights[:-1], heights[1:]):
            if fade is not None and x1 <= fade:
                continue
            if fade is not None and x0 < fade:
                h0 = h0 + (h1 - h0) * (fade - x0) / (x1 - x0)
                x0 = fade
            p0, p1 = np.array([x0, y, road["top"] + h0]), np.array([x1, y, road["top"] + h1])
            along = p1 - p0
            half_len = 0.5 * float(np.linalg.norm(along))
            if half_len <= 0:
                continue
            tangent = along / (2 * half_len)
            normal = np.array([-tangent[2], 0.0, tangent[0]])
            half_height = 0.5 * max(h0, h1) + 0.003  # down to the road's top (the rest is inside the ground)
            mat = np.column_stack([tangent, [0.0, 1.0, 0.0], normal]).ravel()
            centre = 0.5 * (p0 + p1) - normal * half_height
            _init(scene, mujoco.mjtGeom.mjGEOM_BOX, [half_len, half_y, half_height], centre, mat, rgba)

    def _distance_marks(self, scene, data) -> None:
        marks = self._marks
        assert marks is not None  # the marks are drawn only when the model has a road plane
        moving = np.flatnonzero(self.model.body_weldid != 0)
        x = float(data.xpos[moving[0]][0]) if moving.size else 0.0  # marks around the first moving body
        white = np.array([0.95, 0.95, 0.95, 1.0], np.float32)
        first = math.ceil((x - MARK_REACH) / MARK_SPACING) * MARK_SPACING
        for at in np.arange(first, x + MARK_REACH, MARK_SPACING):
            geom = _init(
                scene,
                mujoco.mjtGeom.mjGEOM_BOX,
                [0.08, marks["half_width"], 0.005],
                [at, 0.0, marks["z"] + 0.005],
                np.eye(3).ravel(),
                white,
            )
            if geom is not None and round(at / MARK_SPACING) % 2 == 0:
                geom.label = f"{at:.0f} m"
