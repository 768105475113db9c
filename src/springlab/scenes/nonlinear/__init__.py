"""The nonlinear scene: its Scene and helper modules (the registry reads `SCENE`)."""

from .scene import SCENE

__all__ = ["SCENE"]
