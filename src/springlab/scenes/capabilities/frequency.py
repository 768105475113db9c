"""The frequency study's contract (springlab.studies.frequency): the frequency response a scene answers by default
(`Scene.frequency`)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any, TypeAlias

import mujoco
import numpy as np

#: hook: (the scenario's MjSpec after the scene's own edits, its parameters) -> None; edits the spec so the
#: declared input exists as an actuator (e.g. a road height as a control), the physics otherwise unchanged
FrequencyEdit: TypeAlias = Callable[[mujoco.MjSpec, Mapping[str, float]], None]


#: hook: (the compiled model, the scenario's parameters, H: f [Hz] -> the exact complex response, the resonances
#: found in the band as dicts {"frequency_hz", "magnitude", "damping_ratio", "natural_frequency_hz",
#: "pole_damping_ratio"}, the band (fmin, fmax) [Hz]) -> (named answers, SI, names ending in their unit;
#: verdict lines): what the response means for the scene's own question (e.g. where a suspension isolates)
FrequencyInterpret: TypeAlias = Callable[
    [
        mujoco.MjModel,
        Mapping[str, float],
        Callable[[np.ndarray], np.ndarray],
        tuple[Mapping[str, Any], ...],
        tuple[float, float],
    ],
    tuple[dict[str, Any], tuple[str, ...]],
]


@dataclasses.dataclass(frozen=True)
class FrequencySpec:
    """The frequency response a scene answers by default (`springlab frequency SCENE`).

    Attributes
    ----------
    scenario
        the scenario whose model is analysed when the user names none.
    input
        the default input: an actuator or joint name of that model (after `edit`).
    response
        the default response: a joint name ('JOINT' position, 'JOINT:vel', 'JOINT:acc').
    description
        the question in words, e.g. 'road height to body heave: the transmissibility'.
    edit
        MjSpec edit applied after the scene's own (None: none), e.g. the car's road height as a control.
    interpret
        what the default input -> response means for the scene's question (None: nothing beyond the
        resonances), e.g. the single-mass car's isolation frequency or the printer head's shortest move.
    input_unit
        the declared input's unit where it is an actuator ('' : MuJoCo's actuator unit, unknown), e.g. 'm'
        for the car's road height, so the plot's |H| reads in physical units.

    A scene answering several frequency questions declares a tuple of specs, one per scenario, the first
    the default (`Scene.frequency`).
    """

    scenario: str
    input: str
    response: str
    description: str
    edit: FrequencyEdit | None = None
    interpret: FrequencyInterpret | None = None
    input_unit: str = ""
