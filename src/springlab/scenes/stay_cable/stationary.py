"""The cable in the wind, exactly: the stationary covariance three ways, a record's interval, a stationary start.

The N-element model under the wind is x' = A x + B w, x = (q, q'), w the load [N/m], white with intensity S
[N^2 s/m^2] (springlab.exact.random_vibration derives each piece):

* `continuous`: P of the model under white noise (A P + P A^T + B S B^T = 0): the physical answer;
* `held`: P at the steps under the load MuJoCo applies, w_k ~ N(0, S / dt) held over each step (the zero-order
  hold, one matrix exponential): held - continuous is the hold's own effect, whatever the integrator;
* `integrator`: P of MuJoCo's own one-step map x_{k+1} = F x_k + G w_k (springlab.exact.linearize, F and G
  differenced from the compiled model): integrator - held is the integrator's bias, solved from its own
  Lyapunov equation so its digits survive.

A run started from the held stationary distribution (`stationary_start`) is stationary from its first step, so
the sample variance of its record of K steps scatters exactly as `record_variance` says, and the interval
(`record_interval`: Satterthwaite's scaled chi-square) is the run's statistical tolerance.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

from springlab.errors import BadInputError
from springlab.exact import random_vibration as rv
from springlab.exact.linearize import one_step_map, step_input_column
from springlab.scenes.capabilities.case import CaseView
from springlab.scenes.capabilities.random_load import RandomExact
from springlab.sim.simulate import Setup

from .readback import WIND_ACTUATOR, CableModel, cable_model
from .wind import wind_controls

#: the confidence level a run's RMS is held to: a correct run falls outside with probability 1 %
CHECK_LEVEL = 0.99
#: the level of the interval a run reports (`rms_displacement_m_ci95`)
REPORT_LEVEL = 0.95


def continuous_covariance(cable: CableModel, intensity: float, damping: np.ndarray | None = None) -> np.ndarray:
    """P (2N, 2N) of the N-element model under white noise of intensity S [N^2 s/m^2] (continuous time).

    The damping C is intrinsic (alpha M) plus the damper and the aerodynamic tendons (low rank), so the
    structured solver (springlab.exact.random_vibration.second_order_covariance) applies; without intrinsic
    damping (alpha = 0), or with another `damping`, Bartels-Stewart on the whole state matrix.

    Raises
    ------
    BadInputError
        a mode of the model does not decay (no stationary state).
    """
    lumped = cable.lumped
    b = cable.input_matrix()
    w = np.array([[float(intensity)]])
    if damping is None and cable.background > 0:
        factors = [np.eye(cable.size)[:, cable.damper_node - 1]] + [row for row, _ in cable.aero]
        weights = [cable.damper_coefficient] + [weight for _, weight in cable.aero]
        alpha = cable.background / float(lumped.mass[0])
        try:
            return rv.second_order_covariance(
                lumped.mass, lumped.stiffness, alpha, np.column_stack(factors), np.array(weights), b, w
            )
        except BadInputError:
            pass  # a critically damped background mode: the general solver below
    a = lumped.state_matrix() if damping is None else _state_matrix(lumped.mass, lumped.stiffness, damping)
    return rv.continuous_covariance(a, b @ w @ b.T)


def _state_matrix(mass: np.ndarray, stiffness: np.ndarray, damping: np.ndarray) -> np.ndarray:
    n = len(mass)
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -stiffness / mass[:, None]
    a[n:, n:] = -damping / mass[:, None]
    return a


@dataclasses.dataclass(frozen=True)
class WindExact:
    """The wind's exact covariances of one case at one setting.

    Attributes
    ----------
    continuous
        P (2N, 2N) under white noise [m^2, m^2/s, m^2/s^2 by block].
    held
        P at the steps under the held load.
    bias
        P_integrator - P_held: MuJoCo's one-step map's own (same units).
    transition
        Phi = e^{A dt} (2N, 2N): the held chain's one-step map (its record's autocovariance).
    integrator
        MuJoCo integrator name.
    dt
        the step [s].
    """

    continuous: np.ndarray
    held: np.ndarray
    bias: np.ndarray
    transition: np.ndarray
    integrator: str
    dt: float
    #: sqrt(Var(s^2)) [m^2] by (state index, record steps): a run's quantities and its check ask for the same
    spreads: dict[tuple[int, int], float] = dataclasses.field(default_factory=dict, compare=False, repr=False)

    @property
    def integrator_covariance(self) -> np.ndarray:
        """P of MuJoCo's one-step map: held + bias."""
        return self.held + self.bias

    def rms(self, index: int, which: str = "continuous") -> float:
        """sqrt(P[i, i]) [m or m/s] of state `index` from 'continuous', 'held' or 'integrator'."""
        matrix = {"continuous": self.continuous, "held": self.held, "integrator": self.integrator_covariance}[which]
        return math.sqrt(max(float(matrix[index, index]), 0.0))


def held_exact(case: CaseView, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(continuous P, held P, Phi = e^{A dt}) of the case at the step dt [s], once per case and dt (`Case.memo`).

    Raises
    ------
    BadInputError
        a mode does not decay (no stationary state).
    """

    def compute() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        cable = cable_model(case)
        intensity = float(case.params["wind_intensity"])
        a, b, w = cable.lumped.state_matrix(), cable.input_matrix(), np.array([[intensity]])
        continuous = case.memo("wind_continuous", lambda: continuous_covariance(cable, intensity))
        hold = rv.zero_order_hold(a, b, dt)
        return continuous, rv.held_covariance(a, b, w, dt, hold), hold[0]

    return case.memo(("wind_held", float(dt)), compute)


def wind_exact(case: CaseView, integrator: str, dt: float) -> WindExact:
    """The case's WindExact at (integrator, dt [s]), computed once per case and setting (`Case.memo`).

    Raises
    ------
    BadInputError
        a mode does not decay, or MuJoCo's map at this setting has no stationary state (beyond its stability limit).
    """

    def compute() -> WindExact:
        continuous, held, phi = held_exact(case, dt)
        intensity = float(case.params["wind_intensity"])
        actuator = int(case.model.actuator(WIND_ACTUATOR).id)
        transition = one_step_map(case.model, integrator, dt)
        column = step_input_column(case.model, integrator, "ctrl", actuator, dt)[:, None]
        bias = rv.map_bias(held, transition, column, np.array([[intensity / dt]]))
        return WindExact(continuous, held, bias, phi, integrator, float(dt))

    return case.memo(("wind_exact", integrator, float(dt)), compute)


def record_interval(exact: WindExact, index: int, steps: int, level: float) -> rv.VarianceInterval:
    """Where the sample variance of state `index` over a record of `steps` steps falls, at `level`, around the
    held exact variance (the run's load is the held one; its scatter from the held chain's autocovariance)."""
    output = np.zeros(exact.held.shape[0])
    output[index] = 1.0
    variance = float(exact.held[index, index])
    key = (int(index), int(steps))
    if key not in exact.spreads:  # two discrete Lyapunov solves of the whole state: once per case and setting
        exact.spreads[key] = math.sqrt(max(rv.record_variance(exact.held, exact.transition, output, steps), 0.0))
    spread = exact.spreads[key]
    return rv.variance_interval(variance, spread, level)


def stationary_start(covariance: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(q0 [m], q0' [m/s]): a draw from N(0, covariance), D^(1/2) C^(1/2) z with C the correlation matrix, C^(1/2)
    its symmetric square root and z standard normal from the seed's own stream (PCG64 seeded by (seed, 1), apart
    from the wind's, seeded by the seed alone).

    The symmetric square root V sqrt(Lambda) V^T, not V sqrt(Lambda) or a Cholesky factor: the held covariance is
    singular to working precision (the uniform load barely reaches the antisymmetric modes; condition 1e17 at the
    defaults), so its eigenbasis within clusters of eigenvalues, and a Cholesky factor's later columns, follow the
    round-off of the solver (another BLAS or thread count gave another start); the symmetric root does not depend
    on the basis of a cluster and moves only as much as the covariance does.
    """
    symmetric = 0.5 * (covariance + covariance.T)
    scale = np.sqrt(np.clip(np.diag(symmetric), 0.0, None))
    scale[scale == 0.0] = 1.0
    values, vectors = np.linalg.eigh(symmetric / np.outer(scale, scale))
    normal = np.random.default_rng([int(seed), 1]).standard_normal(len(symmetric))
    state = scale * (vectors @ (np.sqrt(np.clip(values, 0.0, None)) * (vectors.T @ normal)))
    n = len(state) // 2
    return state[:n], state[n:]


def sample_variance(series: np.ndarray) -> float:
    """(1/K) sum y_k^2 over the record's K steps after the start (zero mean: the wind's is) [unit^2]."""
    record = np.asarray(series, float)[1:]
    return float(np.mean(record * record))


# -- the hooks springlab.studies.random_load reads (springlab.scenes.capabilities.random_load.RandomLoadSpec) --------------------


def midspan_output(case: CaseView) -> np.ndarray:
    """c (nq + nv,): the deflection of the node nearest mid-span [m], y = c . (qpos, qvel)."""
    cable = cable_model(case)
    row = np.zeros(2 * cable.size)
    row[cable.midspan - 1] = 1.0
    return row


def midspan_exact(case: CaseView, integrator: str, dt: float) -> RandomExact:
    """The mid-span deflection's exact variances [m^2] at (integrator, dt [s]) and a record's scatter."""
    exact = wind_exact(case, integrator, dt)
    mid = cable_model(case).midspan - 1
    row = midspan_output(case)

    def spreads(samples: Sequence[int]) -> np.ndarray:
        return np.sqrt(np.clip(rv.record_variances(exact.held, exact.transition, row, samples), 0.0, None))

    return RandomExact(
        float(exact.continuous[mid, mid]),
        float(exact.held[mid, mid]),
        float(exact.integrator_covariance[mid, mid]),
        spreads,
    )


def midspan_continuous(case: CaseView) -> float:
    """The mid-span deflection's variance [m^2] under white noise (continuous time)."""
    cable = cable_model(case)
    intensity = float(case.params["wind_intensity"])
    covariance = case.memo("wind_continuous", lambda: continuous_covariance(cable, intensity))
    mid = cable.midspan - 1
    return float(covariance[mid, mid])


def seeded_setup(case: CaseView, steps: int, dt: float, seed: int) -> Setup:
    """The wind run of `seed`: started from the held stationary distribution, the held white load for `steps` steps
    of dt [s] (springlab.scenes.stay_cable.wind.wind_controls): the same for a seed in any batch or worker."""
    _, held, _ = held_exact(case, dt)
    q0, v0 = stationary_start(held, seed)
    control = wind_controls(float(case.params["wind_intensity"]), dt, steps, [seed])[0]
    return Setup(qpos=q0, qvel=v0, control=control)
