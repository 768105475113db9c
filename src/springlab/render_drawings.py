"""What the renderer draws on top of the model's own geoms: the pictures of springs.

A spring that is only a picture (its physics is a joint's stiffness) is
declared in the MJCF as a custom text and drawn at render time, so MuJoCo does
not compute a zero-stiffness tendon at every physics step.
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["SPRING_PREFIX", "drawn_springs", "add_springs"]


#: prefix of the MJCF custom texts that declare a drawn spring
SPRING_PREFIX = "spring:"


def drawn_springs(model: mujoco.MjModel) -> list[tuple[int, int, float, np.ndarray]]:
    """Springs to draw: [(site id, site id, width [m], rgba)] from the model's custom texts.

    A spring that is only a picture (its physics is a joint's stiffness) is declared as
    <custom><text name="spring:NAME" data="SITE1 SITE2 WIDTH R G B A"/></custom>
    rather than as a zero-stiffness tendon, which MuJoCo would compute at every step.
    """
    springs = []
    for i in range(model.ntext):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TEXT, i) or ""
        if not name.startswith(SPRING_PREFIX):
            continue
        start = model.text_adr[i]
        text = bytes(model.text_data[start : start + model.text_size[i] - 1]).decode()  # drop the NUL
        first, second, width, *rgba = text.split()
        springs.append(
            (
                model.site(first).id,
                model.site(second).id,
                float(width),
                np.array([float(c) for c in rgba], dtype=np.float32),
            )
        )
    return springs


def add_springs(scene: mujoco.MjvScene, springs: list, data: mujoco.MjData) -> None:
    """Draw each declared spring as a capsule between its two sites (see drawn_springs)."""
    scn = scene
    for first, second, width, rgba in springs:
        if scn.ngeom >= scn.maxgeom:
            return
        geom = scn.geoms[scn.ngeom]
        mujoco.mjv_initGeom(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, np.zeros(3), np.zeros(3), np.eye(3).ravel(), rgba)
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, width, data.site_xpos[first], data.site_xpos[second])
        geom.category = mujoco.mjtCatBit.mjCAT_DECOR
        scn.ngeom += 1
