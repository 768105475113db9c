"""Linear models written out as MJCF, with their closed-form answers: a fixed-free chain of masses and springs,
a pendulum (shared by the linearization, operating-point and audit tests)."""

from __future__ import annotations

import math

import numpy as np

FD_RELATIVE = 1e-7  # tests/exact/test_linearize.py's docstring: ~1e-10 expected, 1000x margin for conditioning


def chain_xml(n: int, k: float = 100.0, m: float = 1.0, d: float = 0.0) -> str:
    """n equal masses in a fixed-free chain: joint i is the stretch of spring i (nested slide joints)."""
    opening = "".join(
        f'<body name="b{i}"><joint name="j{i}" type="slide" axis="1 0 0" stiffness="{k}" damping="{d}"/>'
        f'<inertial pos="0 0 0" mass="{m}" diaginertia="1 1 1"/>'
        for i in range(n)
    )
    return f'<mujoco><option gravity="0 0 0"/><worldbody>{opening}{"</body>" * n}</worldbody></mujoco>'


def chain_frequencies(n: int, k: float, m: float) -> np.ndarray:
    """Fixed-free chain of n equal masses and springs: omega_j = 2 sqrt(k/m) sin((2j - 1) pi / (2 (2n + 1)))."""
    j = np.arange(1, n + 1)
    return 2 * math.sqrt(k / m) * np.sin((2 * j - 1) * math.pi / (2 * (2 * n + 1)))


def pendulum_xml(length: float = 0.5, mass: float = 2.0) -> str:
    """A point mass on a massless rod (inertial at the tip): I = m l^2, K = m g l at the bottom."""
    return (
        '<mujoco><option gravity="0 0 -9.81"/><worldbody><body><joint name="swing" type="hinge" axis="0 1 0"/>'
        f'<inertial pos="0 0 {-length}" mass="{mass}" diaginertia="1e-9 1e-9 1e-9"/></body></worldbody>'
        '<keyframe><key name="bottom" qpos="0"/><key name="top" qpos="3.141592653589793"/></keyframe></mujoco>'
    )
