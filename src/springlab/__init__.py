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
from springlab.studies.design import SobolStudy, Study, design
from springlab.studies.fit.fit import fit
from springlab.studies.fit.results import FitResult
from springlab.studies.frequency import FrequencyResponse, frequency
from springlab.studies.friction_hold import friction_settings
from springlab.studies.friction_results import FrictionSettings
from springlab.studies.random_load import Ensemble
from springlab.studies.random_load import ensemble as rms
from springlab.studies.refine import Refinement, refine
from springlab.studies.rms_settings import RmsSettings, rms_settings
from springlab.studies.stability import StabilityReport
from springlab.studies.stability import stability_report as stability
from springlab.studies.sweeps import Sweep, sweep
from springlab.studies.tradeoff import Tradeoff, tradeoff

from . import errors
from .errors import BadInputError, ClusterError, DivergedError, SpringlabError, UnknownNameError
from .scenes import SCENES

#: the studies, each `study(model, [scenario,] *, options..., **scene_parameters)` (stability takes no model)
STUDIES = (
    "run",
    "validate",
    "sweep",
    "tradeoff",
    "stability",
    "design",
    "fit",
    "refine",
    "friction_settings",
    "rms",
    "rms_settings",
    "frequency",
    "audit",
)

__all__ = [
    "analytic",
    "errors",
    # the studies and what they return
    "run",
    "Result",
    "validate",
    "ValidationRow",
    "sweep",
    "Sweep",
    "tradeoff",
    "Tradeoff",
    "stability",
    "StabilityReport",
    "design",
    "Study",
    "SobolStudy",
    "fit",
    "FitResult",
    "refine",
    "Refinement",
    "friction_settings",
    "FrictionSettings",
    "rms",
    "Ensemble",
    "rms_settings",
    "RmsSettings",
    "frequency",
    "FrequencyResponse",
    "audit",
    "Audit",
    "ModelRun",
    "Verdict",
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
