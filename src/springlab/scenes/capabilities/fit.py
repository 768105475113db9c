"""The fit's contract (springlab.studies.fit): how a scene is identified from a recorded signal (`Scene.fit`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import ClassVar, TypeAlias

import numpy as np

from .case import CaseView

#: the fit's names of the observed coordinate's state at the record's start
INITIAL_STATE_NAMES = ("x0", "v0")


@dataclasses.dataclass(frozen=True)
class OscillatorFit:
    """A scene one coordinate x of which rings as one mode: m x'' + d x' + k (x - x_eq) = F.

    `springlab fit` identifies the mode's k, d (and m where the scene has it as a parameter), or
    its omega_n, zeta, from a record of x, x' or x''; the identifiability rules, the start, the
    optimization and the cross-check against the closed form are the study's.

    Attributes
    ----------
    joint
        the measured joint, the coordinate x (records carry `<joint>_pos` [m], `_vel` [m/s] or `_acc` [m/s^2]).
    scenarios
        the scenarios a record can be fitted with; the first is the default.
    mass, stiffness, damping
        the scene's parameter names of the mode's m [kg], k [N/m], d [N s/m]; `mass` None: the mode's
        mass is derived from other parameters by `mode_mass` and cannot be freed.
    default_free
        the free names when the user names none.
    signals
        the signal kinds it fits: 'pos', 'vel', 'acc'.
    rest
        the scene parameter holding x_eq [m], the coordinate's unforced rest position (None: 0).
    step_forces
        scenario -> the scene parameter holding the constant force F [N] it applies from t = 0 (a step
        response); every other scenario is a free decay (F = 0).
    mode_mass
        hook: the scene's parameters -> the mode's mass m [kg] (None: the parameter `mass`).
    initial_state
        hook: (the candidate's Case, x0 [m], v0 [m/s]) -> (qpos, qvel) with the coordinate at x0, v0
        (None: the joint set, the rest of the scene at qpos0 and at rest).
    release
        hook for a scene whose initial state is not its parameters x0, v0 (its runs start at rest):
        (the identified scene's run parameters, x0 [m]) -> the run parameters that start it at rest at
        x0 (None: x0 and v0 are parameters of the scene).
    """

    kind: ClassVar[str] = "oscillator"

    joint: str
    scenarios: tuple[str, ...]
    mass: str | None = "mass"
    stiffness: str = "stiffness"
    damping: str = "damping"
    default_free: tuple[str, ...] = ("omega_n", "zeta", "x0", "v0", "offset")
    signals: tuple[str, ...] = ("pos", "vel", "acc")
    rest: str | None = None
    step_forces: Mapping[str, str] = dataclasses.field(default_factory=dict)
    mode_mass: Callable[[Mapping[str, float]], float] | None = None
    initial_state: Callable[[CaseView, float, float], tuple[np.ndarray, np.ndarray]] | None = None
    release: Callable[[Mapping[str, float], float], dict[str, float]] | None = None

    def __post_init__(self) -> None:
        if self.mass is None and self.mode_mass is None:
            raise ValueError("an OscillatorFit without a mass parameter needs a mode_mass hook")


@dataclasses.dataclass(frozen=True)
class PolynomialFit:
    """A scene that drives one coordinate along x(t) = sum_n c_n t^n / n! (n <= 3), c_n its n-th derivative at t = 0.

    `springlab fit` identifies the coefficients (the scene's parameters) from a record of x, x' or x'',
    choosing the degree or taking `--degree`; differentiation loses c_0 from velocity data and c_0, c_1
    from acceleration data.

    Attributes
    ----------
    joint
        the measured joint, the coordinate x.
    scenarios
        the scenarios a record can be fitted with; the first is the default.
    coefficients
        the scene's parameter names of c_0 [m], c_1 [m/s], ... in ascending power: two to four of
        them, the first two x0 and v0 (the fit's names of the initial state).
    signals
        the signal kinds it fits: 'pos', 'vel', 'acc'.
    """

    kind: ClassVar[str] = "polynomial"

    joint: str
    scenarios: tuple[str, ...]
    coefficients: tuple[str, ...]
    signals: tuple[str, ...] = ("pos", "vel", "acc")

    def __post_init__(self) -> None:
        names = self.coefficients
        if not 2 <= len(names) <= 4 or names[:2] != INITIAL_STATE_NAMES:
            raise ValueError(f"a PolynomialFit has 2 to 4 coefficients starting with x0, v0; got {', '.join(names)}")


#: what `Scene.fit` may declare (None: the scene cannot be fitted)
FitSpec: TypeAlias = OscillatorFit | PolynomialFit
