"""The slider scene: its Scene (the registry reads `SCENE`)."""

from .scene import SCENE, Slider

__all__ = ["SCENE", "Slider"]
