"""`springlab frequency MODEL|SCENE`: the frequency response of any model's linearization, and the band an
integrator at a timestep reproduces it in.

1. Exact: the linearization at the operating point (springlab.exact.model_at_point holds the model there once:
   A from MuJoCo's `mjd_inverseFD`, the input column b and the response row c by centred differences of
   `mj_forward`) as a python-control state-space system, evaluated per frequency (`StateSpace.horner`);
   resonances (local maxima of |H|, the peak refined by `scipy.optimize.minimize_scalar`, the damping ratio
   from the half-power width, zeta = (f2 - f1) / (2 f_peak), the textbook estimate, good to O(zeta^2)) and
   anti-resonances (lightly damped zeros).
2. Discrete: MuJoCo's own one-step map of the chosen integrator at dt (Phi from `one_step_map`, gamma from
   `step_input_column`: the input held over the step, as MuJoCo applies a control; each setting differenced
   once) as a discrete-time state-space system; its response to a sine sampled at mid-step and held, against
   the exact one: relative magnitude and phase errors, the band from FMIN within tol, and for each of MuJoCo's
   integrators the largest dt whose band covers the whole requested band (bisection in log dt below Nyquist,
   every returned dt checked).

The hold itself costs accuracy: a sine held over each step reaches the model as sinc(omega dt / 2) times
the sine, a relative error (omega dt)^2 / 24 even for an exact integrator. `hold_error` is that floor (the
exact zero-order-hold discretization, `scipy.signal.cont2discrete`, compared the same way), so a user sees
which part of the error is the integrator's.

`frequency(model, ...)` returns a `FrequencyResponse` (immutable): `to_dict()` is frequency.json,
`to_pandas()` its rows (frequency.csv).

The package, one question per module: `results` (what it returns), `inputs` (the model, its input and its
response), `linear` (the exact and discrete responses, resonances, the band), `sinestream` (the response
estimated by simulating sines), `sweep` (continuation in frequency and the harmonic balance), `study` (the
orchestrator). The function `sinestream` is not handed on here: it would hide its module of the same name
(`springlab.studies.frequency.sinestream`, where the executor's chunk function lives).
"""

from .inputs import declared_scenarios, resolve_input, resolve_response
from .results import FrequencyResponse, IntegratorBand, Resonance, Sinestream, SweepBranch
from .sinestream import default_amplitude
from .study import DEFAULT_POINTS, DEFAULT_TOL, frequency

__all__ = [
    "DEFAULT_POINTS",
    "DEFAULT_TOL",
    "FrequencyResponse",
    "IntegratorBand",
    "Resonance",
    "Sinestream",
    "SweepBranch",
    "declared_scenarios",
    "default_amplitude",
    "frequency",
    "resolve_input",
    "resolve_response",
]
