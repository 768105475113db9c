"""drill_string: Fig. 5.2's drill rod, N lumped rotors against the exact torsional continuum."""

from .scene import SCENE

__all__ = ["SCENE"]
