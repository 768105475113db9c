"""A capability a scene declares for springlab.studies.random_load: a scenario driven by a seeded stationary
random load, whose RMS response has an exact value and an exact scatter (`Scene.random_load`).

The study reads only this: which scenario, which parameter is the seed (and which, if any, the model's size),
which quantity the RMS is, and two hooks of the scene's physics: the output whose RMS it is (a row over the
state) and the exact variances (continuous, held, MuJoCo's integrator) with the scatter of a record's estimate.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from typing import TypeAlias

import numpy as np

from springlab.sim.simulate import Setup

from .case import CaseView


@dataclasses.dataclass(frozen=True)
class RandomExact:
    """The exact stationary variances of the output of one case at one setting, and a record's scatter.

    Attributes
    ----------
    continuous
        the variance [unit^2] of the model under the white load in continuous time: the physical answer.
    held
        the variance [unit^2] at the steps under the load MuJoCo applies (held over each step of dt).
    integrator
        the variance [unit^2] of MuJoCo's own one-step map at the setting (held plus the integrator's bias).
    spreads
        record lengths K (steps) -> the standard deviation [unit^2] of the sample variance of one stationary
        record of K steps (of the held chain), for each K.
    """

    continuous: float
    held: float
    integrator: float
    spreads: Callable[[Sequence[int]], np.ndarray]


#: hook: (case) -> the output row c (nq + nv,): y = c . (qpos, qvel), the quantity whose RMS is asked
OutputHook: TypeAlias = Callable[[CaseView], np.ndarray]
#: hook: (case, integrator, dt [s]) -> RandomExact
RandomExactHook: TypeAlias = Callable[[CaseView, str, float], RandomExact]
#: hook: (case) -> the continuous-time variance [unit^2] alone (cheaper: no setting), for the size's convergence
ContinuousHook: TypeAlias = Callable[[CaseView], float]
#: hook: (case, steps, dt [s], seed) -> the run's initial state and load (the scenario's setup for that seed)
SeededSetupHook: TypeAlias = Callable[[CaseView, int, float, int], Setup]


@dataclasses.dataclass(frozen=True)
class RandomLoadSpec:
    """The scene has a scenario under a seeded stationary random load (`Scene.random_load`).

    Attributes
    ----------
    scenario
        the scenario.
    seed
        the parameter that seeds the load (a whole number; seed k's load is the same in any batch).
    quantity
        the run's quantity that is the RMS (e.g. 'rms_displacement_m').
    description
        the RMS in words (e.g. 'the RMS deflection at mid-span').
    unit
        its unit (e.g. 'm').
    output
        the output row hook (`OutputHook`).
    exact
        the exact variances hook (`RandomExactHook`).
    continuous
        the continuous variance hook (`ContinuousHook`).
    setup
        the seeded setup hook (`SeededSetupHook`).
    size
        the parameter that sets the model's size ('' for none).
    sizes
        the sizes the settings study compares, ascending, each a refinement of the last by a factor 2 in the
        size's spacing (so the variance's limit is Richardson's from the last two).
    order
        the order of the discretization error in the spacing.
    """

    scenario: str
    seed: str
    quantity: str
    description: str
    unit: str
    output: OutputHook
    exact: RandomExactHook
    continuous: ContinuousHook
    setup: SeededSetupHook
    size: str = ""
    sizes: tuple[int, ...] = ()
    order: float = 2.0
