"""The off-screen OpenGL side of a video: backend choice, one GL context per video, the MjvScene.

* **GL backend.** Headless machines have no X server, so :func:`ensure_gl_backend`
  selects EGL (``MUJOCO_GL=egl``) unless the user chose a backend. With Mesa
  this renders on the CPU (llvmpipe); no GPU is needed. It is called by the
  code that renders (:class:`OffscreenScene`), never at import, so importing
  springlab changes no environment variable. The GL context class is picked from
  the environment at render time (``mujoco.egl.GLContext`` for ``egl``), so it
  does not matter whether :mod:`mujoco` was imported before.
* **One GL context per video.** A single GL context, ``MjrContext`` and
  ``MjvScene`` are created per call and reused for every frame. Shadows,
  reflections, skybox, haze and fog are switched off (they cost extra render
  passes on a CPU rasteriser); tendons (the visible spring) stay on.
* **No multisampling unless asked.** MuJoCo's default 4x multisample
  anti-aliasing (``vis.quality.offsamples``) tripled the frame time on
  llvmpipe (slider, 640x480: 62 against about 21 frames/s measured side by
  side, ``python benchmarks/bench_render.py``), while after H.264 the edges
  differ by a pixel's stair step. ``multisample=True`` keeps the model's own
  setting.
* **Readable picture.** MuJoCo clears to black; a flat white backdrop quad is
  added to the scene behind everything, so the background is light and the
  model's own colours contrast with it.
"""

from __future__ import annotations

import os

import mujoco
import numpy as np

__all__ = ["ensure_gl_backend", "OffscreenScene"]

_BACKGROUND_RGBA = np.array([1.0, 1.0, 1.0, 1.0])  # backdrop colour (white)


def ensure_gl_backend() -> None:
    """Select the EGL OpenGL backend for MuJoCo unless the user chose one.

    Sets ``MUJOCO_GL=egl`` when ``MUJOCO_GL`` is unset or empty; an existing
    value (``egl``, ``osmesa``, ``glfw``, ...) is respected. Call it before
    importing :mod:`mujoco` or creating any renderer. (:class:`OffscreenScene`
    calls it.)
    """
    if not os.environ.get("MUJOCO_GL", "").strip():
        os.environ["MUJOCO_GL"] = "egl"


def _gl_context_class():
    """GL context class for the backend selected in MUJOCO_GL *now*.

    ``mujoco.GLContext`` is fixed when :mod:`mujoco` is first imported; if that
    happened before MUJOCO_GL was set, it would be the GLFW context, which
    needs a display. Importing the backend module directly avoids that.
    """
    backend = os.environ.get("MUJOCO_GL", "").strip().lower()
    try:
        if backend == "egl":
            from mujoco.egl import GLContext
        elif backend == "osmesa":
            from mujoco.osmesa import GLContext
        elif backend == "glfw":
            from mujoco.glfw import GLContext
        else:
            GLContext = getattr(mujoco, "GLContext", None)
    except Exception as err:  # ImportError, or PyOpenGL platform errors
        raise RuntimeError(f"cannot load the OpenGL backend MUJOCO_GL={backend!r}: {err}") from err
    if GLContext is None:
        raise RuntimeError(f"no OpenGL context available for MUJOCO_GL={backend!r}")
    return GLContext


class OffscreenScene:
    """One GL context + MjrContext + MjvScene, reused for every frame."""

    def __init__(
        self,
        model: mujoco.MjModel,
        width: int,
        height: int,
        camera_id: int,
        drawings=None,
        *,
        multisample: bool = False,
    ):
        self.model = model
        self.width = width
        self.height = height
        self._gl = None
        self._con = None
        ensure_gl_backend()  # the user's MUJOCO_GL wins; EGL otherwise
        GLContext = _gl_context_class()
        try:
            self._gl = GLContext(width, height)
            self._gl.make_current()
        except Exception as err:
            self.close()
            raise RuntimeError(
                f"could not create an off-screen OpenGL context (MUJOCO_GL={os.environ.get('MUJOCO_GL')!r}): {err}"
            ) from err

        # The offscreen framebuffer's size and samples are read from the model
        # when the MjrContext is made. Set them for this context only, then
        # restore the caller's values, so the model passed in is left unchanged.
        vis, quality = model.vis.global_, model.vis.quality
        saved = (int(vis.offwidth), int(vis.offheight), int(quality.offsamples))
        try:
            vis.offwidth = max(saved[0], width)
            vis.offheight = max(saved[1], height)
            quality.offsamples = saved[2] if multisample else 0
            self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        except Exception:
            self.close()
            raise
        finally:
            vis.offwidth, vis.offheight, quality.offsamples = saved
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        if self._con.currentBuffer != mujoco.mjtFramebuffer.mjFB_OFFSCREEN:
            self.close()
            raise RuntimeError("the OpenGL context has no off-screen framebuffer")

        self.scene = mujoco.MjvScene(model, maxgeom=max(1000, 4 * model.ngeom + 500))
        flags = self.scene.flags
        for flag in (
            mujoco.mjtRndFlag.mjRND_SHADOW,
            mujoco.mjtRndFlag.mjRND_REFLECTION,
            mujoco.mjtRndFlag.mjRND_SKYBOX,
            mujoco.mjtRndFlag.mjRND_HAZE,
            mujoco.mjtRndFlag.mjRND_FOG,
        ):
            flags[flag] = 0
        self.option = mujoco.MjvOption()
        self.option.flags[mujoco.mjtVisFlag.mjVIS_TENDON] = 1  # the spring

        self.camera = mujoco.MjvCamera()
        if camera_id < 0:
            self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
            mujoco.mjv_defaultFreeCamera(model, self.camera)
        else:
            self.camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
            self.camera.fixedcamid = camera_id

        self._drawings = drawings  # drawings.Drawings or None: springs, dampers, belt, road
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._pixels = np.empty((height, width, 3), dtype=np.uint8)
        self._eye = np.eye(3)

    def _add_backdrop(self) -> None:
        """Append a flat white quad just inside the far clipping plane."""
        scn = self.scene
        if scn.ngeom >= scn.maxgeom:
            return
        c0, c1 = scn.camera[0], scn.camera[1]
        pos = 0.5 * (np.asarray(c0.pos) + np.asarray(c1.pos))
        fwd = 0.5 * (np.asarray(c0.forward) + np.asarray(c1.forward))
        up = 0.5 * (np.asarray(c0.up) + np.asarray(c1.up))
        fwd /= np.linalg.norm(fwd)
        up -= fwd * (up @ fwd)
        up /= np.linalg.norm(up)
        right = np.cross(fwd, up)
        near, far = float(c0.frustum_near), float(c0.frustum_far)
        dist = 0.95 * far
        half_h = max(abs(c0.frustum_top), abs(c0.frustum_bottom)) + abs(c0.frustum_center)
        if not c0.orthographic:
            half_h *= dist / near
        half = 2.0 * half_h * max(1.0, self.width / self.height)
        mat = np.column_stack([right, up, fwd]).ravel()
        geom = scn.geoms[scn.ngeom]
        mujoco.mjv_initGeom(
            geom,
            mujoco.mjtGeom.mjGEOM_BOX,
            np.array([half, half, 1e-3 * dist]),
            pos + dist * fwd,
            mat,
            _BACKGROUND_RGBA.astype(np.float32),
        )
        geom.emission = 1.0  # rgba * emission = white, whatever the lights
        geom.specular = 0.0
        geom.shininess = 0.0
        geom.reflectance = 0.0
        geom.category = mujoco.mjtCatBit.mjCAT_DECOR
        geom.segid = -1
        scn.ngeom += 1

    def render(self, data: mujoco.MjData, out: np.ndarray) -> None:
        """Render ``data`` (kinematics already computed) into ``out`` (H x W x 3)."""
        mujoco.mjv_updateScene(self.model, data, self.option, None, self.camera, mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        if self._drawings is not None:
            self._drawings.add(self.scene, data)
        self._add_backdrop()
        mujoco.mjr_render(self._rect, self.scene, self._con)
        mujoco.mjr_readPixels(self._pixels, None, self._rect, self._con)
        out[...] = self._pixels[::-1]  # OpenGL rows are bottom-up

    def close(self) -> None:
        if self._con is not None:
            if self._gl is not None:
                self._gl.make_current()
            self._con.free()
            self._con = None
        if self._gl is not None:
            self._gl.free()
            self._gl = None
