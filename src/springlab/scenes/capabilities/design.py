"""The design study's contract (springlab.studies.design): the design question a scene answers (`Scene.design`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np

from .case import CaseView


@dataclasses.dataclass(frozen=True)
class DesignProperty:
    """A property the design study varies, log-uniformly about its value at the scene's parameters.

    Attributes
    ----------
    name
        the property's name (a scene parameter, or a property derived from several, e.g. a damping ratio).
    unit
        SI unit, '-' for none.
    span
        the study spans default x span^[-1, 1] [-] (> 1).
    label
        axis label with symbol and unit, e.g. 'belt stiffness k [N/m]'.
    parameter
        the scene parameter that sets the property when it is not one itself ('' when it is); then
        `DesignHooks.parameters_for` converts a value of it into that parameter.
    description
        the property in words, e.g. 'damping ratio' (messages).
    minimum
        the lowest value a derived property may be given [its unit] (None: unbounded).
    """

    name: str
    unit: str
    span: float
    label: str
    parameter: str = ""
    description: str = ""
    minimum: float | None = None

    @property
    def derived(self) -> bool:
        """Whether the property is derived from a scene parameter rather than being one."""
        return bool(self.parameter) and self.parameter != self.name

    @property
    def source(self) -> str:
        """The scene parameter that sets the property (its own name when it is one)."""
        return self.parameter or self.name


@dataclasses.dataclass(frozen=True)
class MoveRuns:
    """What a design simulation returns: per configuration, (n,) arrays of a move and its settling.

    Attributes
    ----------
    move_time_s
        realized move time [s].
    settling_time_s
        time after the move until the positioned body stays inside its band for good [s] (inf: never).
    positioning_time_s
        move + settling [s].
    residual_amplitude_m
        largest deviation from the target after the move [m].
    dt_s
        timestep of each simulation [s].
    steps
        physics steps each simulation took.
    nthread
        threads the simulations ran on.
    """

    move_time_s: np.ndarray
    settling_time_s: np.ndarray
    positioning_time_s: np.ndarray
    residual_amplitude_m: np.ndarray
    dt_s: np.ndarray
    steps: np.ndarray
    nthread: int


@dataclasses.dataclass(frozen=True)
class MoveEstimates:
    """The closed-form side of a design study: per configuration, (n,) arrays.

    Attributes
    ----------
    estimate_s
        analytic estimate of the positioning time [s].
    worst_case_estimate_s
        an upper estimate that needs no simulation [s].
    natural_frequency_hz
        the mode that rings after the move [Hz].
    """

    estimate_s: np.ndarray
    worst_case_estimate_s: np.ndarray
    natural_frequency_hz: np.ndarray


class DesignHooks(Protocol):
    """The closed-form and simulation pieces a scene's design question needs (implemented by the scene).

    `base` is the scene's resolved parameters (SI); `values` maps each varied property to its (n,)
    values per configuration (the properties not in it stay at their value in `base`).
    """

    def defaults(self, base: Mapping[str, float]) -> dict[str, float]:
        """Every declared property's value [its unit] at the parameters `base`.

        Parameters
        ----------
        base
            the scene's parameters (SI).

        Returns
        -------
        dict[str, float]
            property name -> value.
        """
        ...

    def parameters_for(self, name: str, value: float, base: Mapping[str, float]) -> dict[str, float]:
        """The scene parameters [SI] that give the derived property `name` the value `value` at `base`.

        Parameters
        ----------
        name
            a derived property (`DesignProperty.derived`).
        value
            its value [its unit].
        base
            the other parameters (SI).

        Returns
        -------
        dict[str, float]
            scene parameter -> value, to resolve the scene with.
        """
        ...

    def simulate(
        self, case: CaseView, values: Mapping[str, np.ndarray], *, omega_dt: float, nthread: int, max_duration: float
    ) -> MoveRuns:
        """Simulate the move of every configuration (a module-level object: it runs on dask workers too).

        Parameters
        ----------
        case
            the scene's design scenario at `base`, the scene's parameters (SI): `case.params`.
        values
            property -> (n,) values.
        omega_dt
            omega_n dt [-] of every simulation.
        nthread
            threads (0: one per CPU).
        max_duration
            simulated time [s] after which an unsettled configuration is given up (settling inf).

        Returns
        -------
        MoveRuns
            per-configuration results, in the order of `values`.
        """
        ...

    def estimates(self, base: Mapping[str, float], values: Mapping[str, np.ndarray], dt: np.ndarray) -> MoveEstimates:
        """The analytic estimates of every configuration, each on its simulation's timestep `dt` [s].

        Parameters
        ----------
        base
            the scene's parameters (SI).
        values
            property -> (n,) values.
        dt
            (n,) timesteps [s] the simulations used.

        Returns
        -------
        MoveEstimates
            per-configuration estimates.
        """
        ...

    def setting(self, base: Mapping[str, float]) -> str:
        """The fixed task in a few words, for a chart's title, e.g. '25.4 mm to +-10 um'.

        Parameters
        ----------
        base
            the scene's parameters (SI).

        Returns
        -------
        str
            the words.
        """
        ...

    def answer(self, summary: Mapping[str, Any]) -> str:
        """The design question answered in words, from the study's `to_dict()`.

        Parameters
        ----------
        summary
            the study's `to_dict()`.

        Returns
        -------
        str
            one paragraph.
        """
        ...


@dataclasses.dataclass(frozen=True)
class DesignSpec:
    """The design question a scene answers: how fast can a move be made, and which properties matter.

    The study (springlab.studies.design) sweeps `properties` on a log grid around their defaults,
    simulates the `scenario`'s move of every configuration through `hooks.simulate`, estimates each
    through `hooks.estimates`, and ranks the properties by their effect on the figure of merit,
    the positioning time (move + settling); the Sobol study varies `sobol`, in that order.

    Attributes
    ----------
    question
        the question in words.
    scenario
        the scene's scenario whose move is studied (its parameters are the study's starting point).
    properties
        the swept properties, in grid order.
    fixed
        scene parameters held at their values and reported beside the results.
    hooks
        the scene's closed-form and simulation pieces (`DesignHooks`).
    merit
        the figure of merit in words (titles and lines).
    extra
        properties only the Sobol study varies.
    sobol
        the Sobol study's inputs, in order (names of `properties` or `extra`).
    """

    question: str
    scenario: str
    properties: tuple[DesignProperty, ...]
    fixed: tuple[str, ...]
    hooks: DesignHooks
    merit: str = "positioning time"
    extra: tuple[DesignProperty, ...] = ()
    sobol: tuple[str, ...] = ()

    def get(self, name: str) -> DesignProperty:
        """The declared property (swept or extra) called `name`.

        Raises
        ------
        KeyError
            no such property is declared.
        """
        for prop in (*self.properties, *self.extra):
            if prop.name == name:
                return prop
        raise KeyError(name)

    @property
    def names(self) -> tuple[str, ...]:
        """The swept properties' names, in grid order."""
        return tuple(p.name for p in self.properties)
