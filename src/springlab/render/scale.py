"""Time scale and amplitude scale of a video, as vibration tools show them: drawing only, never physics.

Two factors change what a video shows, never what was simulated (the
trajectory, CSV and summary are untouched):

* **slow motion** S: frame k shows simulation time k / (fps S), so a 0.3 s move
  filmed at 1/50 speed lasts 15 s of video;
* **exaggeration** E: every coordinate is drawn at ``centre + E (q - centre)``,
  where ``centre`` is its mean over the filmed frames, so a 2.5 mm heave of a
  4 m car is drawn as 12 cm at E = 50 and the picture stays consistent (a wheel
  on an exaggerated road stays on it: all coordinates scale together).

Both are written on every frame (:func:`labels`). The defaults make each run's
motion visible without naming any scene:

* :func:`default_slow_motion`: a run shorter than ``MIN_FRAMES`` frames is
  slowed until it fills them, and then until its fastest vibration mode gets
  ``FRAMES_PER_PERIOD`` frames per period (the printer head's 195 Hz belt at
  30 fps: 1/50 speed); longer runs play at real speed (the car's road bump).
* :func:`default_exaggeration`: when the largest displacement of any moving
  geom over the run is below ``VISIBLE_MOTION`` of the largest moving geom's
  size, it is magnified to about ``TARGET_MOTION`` of it (the 4.2 m car's
  4.9 mm push-and-release: x30, 15 cm of apparent motion).

Factors are rounded up to "nice" values (1, 2, 3, 5 x 10^n) so labels read well.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import mujoco
import numpy as np

from springlab.errors import BadInputError

__all__ = [
    "MIN_FRAMES",
    "FRAMES_PER_PERIOD",
    "VISIBLE_MOTION",
    "TARGET_MOTION",
    "nice_at_least",
    "check_factor",
    "default_slow_motion",
    "default_exaggeration",
    "exaggerated",
    "labels",
]

#: fewest frames a default video has [frames] (3 s at 30 fps)
MIN_FRAMES = 90
#: frames per period of the fastest mode once a short run is slowed down [frames]
FRAMES_PER_PERIOD = 6
#: below this displacement / size ratio [-] the motion is exaggerated by default
VISIBLE_MOTION = 0.01
#: the displacement / size ratio [-] the default exaggeration aims for
TARGET_MOTION = 0.03
#: the mantissas of nice factors
_NICE = (1.0, 2.0, 3.0, 5.0)


def nice_at_least(value: float) -> float:
    """The smallest factor of the form m x 10^n (m in 1, 2, 3, 5; n >= 0) that is >= ``value`` [-]."""
    if not value > 1.0:
        return 1.0
    decade = 10.0 ** math.floor(math.log10(value))
    for mantissa in (*_NICE, 10.0):
        if mantissa * decade >= value * (1 - 1e-12):
            return mantissa * decade
    return 10.0 * decade  # pragma: no cover - the loop always returns


def check_factor(name: str, value: float | str) -> float:
    """``value`` as a float >= 1, or BadInputError naming the option and what is valid."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise BadInputError(f"{name} must be a number >= 1, got {value!r}") from None
    if not math.isfinite(number) or number < 1.0:
        raise BadInputError(f"{name} must be a finite number >= 1 (1 = as simulated), got {value!r}")
    return number


def default_slow_motion(duration: float, fps: float, frequencies_hz: Iterable[float] = ()) -> float:
    """Slow-motion factor [-] for a run of ``duration`` [s] filmed at ``fps`` [1/s].

    Runs of at least ``MIN_FRAMES`` frames play at real speed (1). Shorter ones
    are slowed to fill ``MIN_FRAMES`` frames and to give the fastest of
    ``frequencies_hz`` (the scene's vibration modes [Hz]) ``FRAMES_PER_PERIOD``
    frames per period, so a ringing belt is seen ringing rather than aliased.
    """
    frames = float(duration) * float(fps)
    if round(frames) >= MIN_FRAMES:  # the frames the video will have (a 3 s run may end at 2.99999 s)
        return 1.0
    need = MIN_FRAMES / max(frames, 1e-9)
    fastest = max([float(f) for f in frequencies_hz if math.isfinite(f) and f > 0], default=0.0)
    need = max(need, FRAMES_PER_PERIOD * fastest / float(fps))
    return nice_at_least(need)


def _moving_geom_corners(model: mujoco.MjModel, states: np.ndarray) -> tuple[np.ndarray, float]:
    """((frames, corners, 3) world bounding-box corners [m] of every moving geom, largest geom size [m])."""
    moving = np.flatnonzero(model.body_weldid[model.geom_bodyid] != 0)
    if moving.size == 0:
        return np.zeros((len(states), 0, 3)), 0.0
    signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], dtype=float)
    aabb = model.geom_aabb[moving]
    local = aabb[:, None, :3] + signs[None] * aabb[:, None, 3:]  # (g, 8, 3)
    data = mujoco.MjData(model)
    corners = []
    for q in states:
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        rot = data.geom_xmat[moving].reshape(-1, 3, 3)
        corners.append((data.geom_xpos[moving][:, None] + np.einsum("gij,gcj->gci", rot, local)).reshape(-1, 3))
    return np.array(corners), float(2.0 * np.max(aabb[:, 3:]))


def default_exaggeration(model: mujoco.MjModel, states: np.ndarray) -> float:
    """Exaggeration factor [-] that makes the motion of ``states`` (frames x nq) visible.

    The displacement is the largest peak-to-peak excursion of any corner of any
    moving geom's bounding box over the frames [m] (so rotations count too);
    the size is the largest moving geom's largest dimension [m]. At or above
    ``VISIBLE_MOTION`` of the size the motion is drawn as simulated (1).
    """
    corners, size = _moving_geom_corners(model, np.asarray(states, dtype=float))
    if corners.shape[1] == 0 or size <= 0:
        return 1.0
    displacement = float(np.max(np.linalg.norm(np.ptp(corners, axis=0), axis=-1)))
    ratio = displacement / size
    if ratio >= VISIBLE_MOTION or displacement == 0.0:
        return 1.0
    return nice_at_least(TARGET_MOTION / ratio)


def exaggerated(
    model: mujoco.MjModel, states: np.ndarray, factor: float, centre: np.ndarray | None = None
) -> np.ndarray:
    """States drawn at ``centre + factor (q - centre)`` per coordinate (centre: the mean over frames).

    Quaternion coordinates (free and ball joints) are left as simulated: a
    rotation cannot be magnified by scaling its components. ``centre`` (nq,)
    gives the centre instead (the live viewer draws one state at a time around
    the mean of the run it replays).
    """
    states = np.asarray(states, dtype=float)
    if factor == 1.0:
        return states
    scaled = np.ones(model.nq, dtype=bool)
    for j in range(model.njnt):
        adr = model.jnt_qposadr[j]
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            scaled[adr + 3 : adr + 7] = False
        elif model.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:
            scaled[adr : adr + 4] = False
    centre = states.mean(axis=0) if centre is None else np.asarray(centre, dtype=float)
    out = states.copy()
    out[:, scaled] = centre[scaled] + factor * (states[:, scaled] - centre[scaled])
    return out


def _factor_text(factor: float) -> str:
    return f"{factor:.0f}" if float(factor).is_integer() else f"{factor:.3g}"


def labels(slow_motion: float, exaggeration: float) -> list[str]:
    """The on-frame lines that say how the drawing differs from the simulation (none at 1 and 1)."""
    out = []
    if exaggeration != 1.0:
        out.append(f"motion ×{_factor_text(exaggeration)}")
    if slow_motion != 1.0:
        out.append(f"1/{_factor_text(slow_motion)} speed")
    return out
