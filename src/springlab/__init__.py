"""springlab: MuJoCo scenes of the textbook vibration problems, checked against exact solutions.

>>> import springlab
>>> result = springlab.run(
...     "slider", "free", integrator="rk4", dt=1e-3, duration=5.0, mass=2.0, stiffness=800.0, damping=4.0, x0=0.05
... )
>>> result.summary["passed"]
True
"""

from . import analytic, errors
from .api import Result
from .audit import Audit, audit
from .auto import run, validate
from .errors import BadInputError, DivergedError, SpringlabError, UnknownNameError
from .fit import fit
from .scenes import SCENES
from .sweeps import sweep

__all__ = [
    "analytic",
    "errors",
    "run",
    "validate",
    "sweep",
    "audit",
    "Audit",
    "fit",
    "Result",
    "SCENES",
    "SpringlabError",
    "BadInputError",
    "UnknownNameError",
    "DivergedError",
]
__version__ = "0.1.0"
