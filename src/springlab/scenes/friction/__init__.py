"""The friction scene: its Scene (the registry reads `SCENE`)."""

from .scene import SCENE, Friction

__all__ = ["SCENE", "Friction"]
