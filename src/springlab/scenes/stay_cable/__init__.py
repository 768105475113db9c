"""stay_cable: a long bridge stay, N lumped nodes against the exact taut string, its damper and the random wind."""

from .scene import SCENE

__all__ = ["SCENE"]
