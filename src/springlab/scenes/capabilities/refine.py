"""The refine study's contract (springlab.studies.refine): a scene whose model size is a parameter (`Scene.refinable`)."""

from __future__ import annotations

import dataclasses


@dataclasses.dataclass(frozen=True)
class RefinedQuestion:
    """A quantity a run of the scene measures that converges, as the model is refined, to a continuum value.

    The refine study reads three of the run's quantities: the measured value (`name`), the same quantity
    of the discretized model solved exactly (`exact`: the gap to it is the integration error) and of the
    continuum (`continuum`: the gap between the two exact values is the discretization error).

    Attributes
    ----------
    name
        the measured quantity, e.g. 'mode_1_frequency_hz'.
    scenario
        the scenario whose runs measure it.
    description
        the question in words, e.g. 'the first torsional frequency'.
    exact
        the quantity holding the discretized model's exact value.
    continuum
        the quantity holding the continuum's exact value.
    """

    name: str
    scenario: str
    description: str
    exact: str
    continuum: str


@dataclasses.dataclass(frozen=True)
class RefinableSpec:
    """The scene's model size is a parameter (`Scene.refinable`): how much model does a question need?

    springlab.studies.refine sweeps the size x integrator x timestep, measures each question's error
    against its continuum value and the cost of every run, and finds the cheapest verified setting.

    Attributes
    ----------
    size
        the parameter that sets the model's size (an integer, e.g. 'n_elements').
    description
        what the size counts, in words (e.g. 'lumped elements').
    sizes
        the sizes the study sweeps by default, ascending.
    questions
        the questions, the first the default.
    order
        the expected order of the discretization error in the size (error ~ size^-order).
    switch_time
        a parameter [s] every timestep of the study divides (an input switched on the step grid at that
        time, e.g. the end of a ramp), so all runs of a size solve the same problem; '' for none.
    """

    size: str
    description: str
    sizes: tuple[int, ...]
    questions: tuple[RefinedQuestion, ...]
    order: float
    switch_time: str = ""

    def question(self, name: str | None) -> RefinedQuestion:
        """The question measuring `name` (None: the first).

        Raises
        ------
        KeyError
            no question measures that quantity.
        """
        if name is None:
            return self.questions[0]
        for question in self.questions:
            if question.name == name:
                return question
        raise KeyError(name)
