"""The friction-settings study's contract (springlab.studies.friction_settings): MuJoCo's regularised dry friction
against exact Coulomb answers (`Scene.dry_friction`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

#: dry friction of a joint (MuJoCo's `frictionloss`): a force bounded by F whatever the load
JOINT_FRICTION = "joint"
#: contact friction: mu times the normal force, inside MuJoCo's friction cone
CONTACT_FRICTION = "contact"


@dataclasses.dataclass(frozen=True)
class SolverSetting:
    """A MuJoCo setting a scene takes as a parameter, and the values the friction-settings study tries.

    Attributes
    ----------
    name
        the scene parameter that sets it (e.g. a solref time constant [s]).
    values
        the values swept, in order; MuJoCo's default among them.
    mujoco_default
        MuJoCo's own default value.
    acts_on
        the kinds of dry friction it changes (JOINT_FRICTION, CONTACT_FRICTION), from MuJoCo's
        documentation and source; the declaring scene's tests check each claim on MuJoCo itself.
        The study sweeps a setting only in the cases whose friction it acts on.
    label
        the setting in words with its unit, e.g. 'solref time constant [s]'.
    names
        value -> word, for a setting that is a choice (e.g. 0: 'pyramidal', 1: 'elliptic').
    floor_in_dt
        MuJoCo raises a value below this many timesteps to it (solref's `refsafe`: 2); the study
        skips such values, which would repeat the run at the raised value (None: no such rule).
    """

    name: str
    values: tuple[float, ...]
    mujoco_default: float
    acts_on: tuple[str, ...]
    label: str
    names: Mapping[float, str] = dataclasses.field(default_factory=dict)
    floor_in_dt: float | None = None

    def __post_init__(self) -> None:
        unknown = set(self.acts_on) - {JOINT_FRICTION, CONTACT_FRICTION}
        if unknown or not self.acts_on:
            raise ValueError(f"a SolverSetting acts on {JOINT_FRICTION!r} and/or {CONTACT_FRICTION!r}")
        if self.mujoco_default not in self.values:
            raise ValueError(f"the values of {self.name} must include MuJoCo's default {self.mujoco_default:g}")

    def word(self, value: float) -> str:
        """The value as the study prints it: its name for a choice, else the number."""
        return self.names.get(value, f"{value:g}")


@dataclasses.dataclass(frozen=True)
class FrictionMeasure:
    """An error the study reports for a case: a quantity of the scenario against its exact value.

    The run's quantities carry both (DESIGN: each with its exact value beside it, `<quantity>_exact`).

    Attributes
    ----------
    quantity
        its name in the run's quantities, ending in its unit (e.g. 'stop_position_m').
    label
        what it is in words.
    scale
        None: the error is |value - exact| / |exact|; a name: the error is |value - exact| / |scale|,
        the scale being that quantity (or parameter) of the run (e.g. the initial amplitude);
        '' : the error is |value - exact| in the quantity's unit (an exact value of 0: a creep velocity).
    """

    quantity: str
    label: str
    scale: str | None = None

    @property
    def exact(self) -> str:
        """The name of its exact value in the quantities."""
        return f"{self.quantity}_exact"


@dataclasses.dataclass(frozen=True)
class FrictionCase:
    """A scenario of the declaring scene with an exact answer under dry friction.

    Attributes
    ----------
    scenario
        the scenario's name.
    friction
        JOINT_FRICTION or CONTACT_FRICTION: which of MuJoCo's friction models it exercises.
    question
        what it asks, in words.
    measures
        the errors reported beside the trajectory's (FrictionMeasure).
    """

    scenario: str
    friction: str
    question: str
    measures: tuple[FrictionMeasure, ...] = ()

    def __post_init__(self) -> None:
        if self.friction not in (JOINT_FRICTION, CONTACT_FRICTION):
            raise ValueError(f"a FrictionCase's friction is {JOINT_FRICTION!r} or {CONTACT_FRICTION!r}")


@dataclasses.dataclass(frozen=True)
class DryFrictionSpec:
    """A scene whose dry friction MuJoCo regularises, with exact Coulomb answers (`Scene.dry_friction`).

    springlab.studies.friction_settings sweeps the declared MuJoCo settings, integrators and timesteps
    over each case, against the exact answers the scene's runs carry: error vs cost, the Pareto front,
    the cheapest setting meeting a tolerance (verified by a run), and the model error of each setting,
    what is left as dt -> 0 (read at the smallest timestep, where it must have converged).

    Attributes
    ----------
    cases
        the scenarios, in order.
    settings
        the MuJoCo settings a user can change, each a scene parameter.
    dts
        the timesteps swept [s], at least two, largest first (a measured convergence).
    integrators
        the integrators swept (default: MuJoCo's five).
    """

    cases: tuple[FrictionCase, ...]
    settings: tuple[SolverSetting, ...]
    dts: tuple[float, ...]
    integrators: tuple[str, ...] = ("euler", "implicit", "implicitfast", "rk4", "discrete")

    def __post_init__(self) -> None:
        if len(self.dts) < 2 or any(b >= a for a, b in zip(self.dts, self.dts[1:])):
            raise ValueError("a DryFrictionSpec sweeps at least two timesteps, largest first")

    def case(self, scenario: str) -> FrictionCase:
        """The declared case of `scenario`.

        Raises
        ------
        KeyError
            no case of that scenario is declared.
        """
        for case in self.cases:
            if case.scenario == scenario:
                return case
        raise KeyError(scenario)

    def settings_of(self, friction: str) -> tuple[SolverSetting, ...]:
        """The settings that act on `friction` (JOINT_FRICTION or CONTACT_FRICTION)."""
        return tuple(s for s in self.settings if friction in s.acts_on)
