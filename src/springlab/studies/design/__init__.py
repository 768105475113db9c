"""The design study (`springlab design`): a scene's declared design question (`Scene.design`) over a
grid of its properties (`study`), the batched runs in chunks (`moves`) and variance-based
sensitivities (`sobol`).

>>> import springlab
>>> study = springlab.design("printer_head", levels=3, plane_levels=0)  # doctest: +SKIP
>>> study.ranking[0], study.to_dict()["default"]["positioning_time_s"]  # doctest: +SKIP
"""

from .moves import design_scenes
from .sobol import SobolStudy, run_sobol
from .study import Plane, Study, design, run_study

__all__ = ["Plane", "SobolStudy", "Study", "design", "design_scenes", "run_sobol", "run_study"]
