"""What the pictures of a run show beyond the model's own geoms (`Scene.drawing`): the videos, the live viewer and the
interactive pages read it (springlab.render), and never recognise a scene by its parts.

What is fixed for every run lives in the scene's MJCF, as the renderer's documented conventions
(springlab.render.drawings): custom texts ``spring:``, ``damper:``, ``belt:`` and ``note:`` name the sites a coil,
a dashpot or a belt is drawn between and the lines written on every frame; world geoms named ``rail`` are stretched
over the travel, and a world plane named ``road`` carries distance marks. What depends on a scenario and its
parameters (the road a quarter car drives over) the scene declares for each case, as a `Drawing`.
"""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class RoadBump:
    """A half-sine bump r(t) = height sin(pi speed t / length) reaching a wheel at t = 0, drawn travelling backwards
    under the car at the driving speed.

    Attributes
    ----------
    height, length
        Bump height and length along the road [m].
    speed
        Driving speed [m/s]: the bump travels backwards under the car at it.
    wheel_geom
        Name of the wheel geom the bump passes under (its centre x is where r(t) is read).
    other_axle_geom
        Optional wheel geom of the other axle: a quarter car models one corner, so the bump is not drawn past
        the middle between the axles.
    exaggeration
        Factor the bump's height is drawn at [-] (the picture's exaggeration; 1 as declared).
    """

    height: float
    length: float
    speed: float
    wheel_geom: str
    other_axle_geom: str | None = None
    exaggeration: float = 1.0


@dataclasses.dataclass(frozen=True)
class Drawing:
    """What a scene adds to the pictures of one case (`Scene.drawing`); nothing by default.

    Attributes
    ----------
    road
        the road profile a wheel drives over (None: no road input to draw).
    """

    road: RoadBump | None = None
