"""springlab: MuJoCo scenes of the textbook vibration problems, checked against exact solutions.

>>> import springlab
>>> result = springlab.run(
...     "slider", "free", integrator="rk4", dt=1e-3, duration=5.0, mass=2.0, stiffness=800.0, damping=4.0, x0=0.05
... )
>>> result.passed, result.verdict
(True, <Verdict.PASS: 'PASS'>)
"""

from springlab.exact import analytic
from springlab.render.inline import Video, video
from springlab.runs.compare import Verdict
from springlab.runs.model_run import ModelRun
from springlab.runs.run import Result, ValidationRow
from springlab.studies.audit.audit import audit
from springlab.studies.audit.results import Audit
from springlab.studies.auto import run, validate
from springlab.studies.fit.fit import fit
from springlab.studies.frequency import FrequencyResponse, frequency
from springlab.studies.friction_hold import friction_settings
from springlab.studies.friction_results import FrictionSettings
from springlab.studies.sweeps import sweep

from . import errors
from .errors import BadInputError, ClusterError, DivergedError, SpringlabError, UnknownNameError
from .scenes import SCENES

__all__ = [
    "analytic",
    "errors",
    "run",
    "validate",
    "sweep",
    "audit",
    "Audit",
    "frequency",
    "FrequencyResponse",
    "friction_settings",
    "FrictionSettings",
    "fit",
    "Result",
    "ModelRun",
    "Verdict",
    "ValidationRow",
    "SCENES",
    "SpringlabError",
    "BadInputError",
    "UnknownNameError",
    "DivergedError",
    "ClusterError",
    "video",
    "Video",
]
__version__ = "0.1.0"
