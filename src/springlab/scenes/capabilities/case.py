"""What a capability hook reads of the case it is given (springlab.scenes.base.Case), as a Protocol."""

from __future__ import annotations

from collections.abc import Callable, Hashable
from typing import Protocol, TypeVar

import mujoco

from ..declarations import Scenario

T = TypeVar("T")


class CaseView(Protocol):
    """What a capability hook reads of the case it is given: a springlab.scenes.base.Case.

    A Protocol, not the class: springlab.scenes.base declares the capabilities on its `Scene` with the types
    of this package, so the package cannot import the base back.
    """

    @property
    def scenario(self) -> Scenario:
        """The scenario."""
        ...

    @property
    def params(self) -> dict[str, float]:
        """Parameter name -> value (SI), resolved."""
        ...

    @property
    def model(self) -> mujoco.MjModel:
        """The compiled model."""
        ...

    def memo(self, key: Hashable, compute: Callable[[], T]) -> T:
        """`compute()` once per case (Case.memo)."""
        ...
