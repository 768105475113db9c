"""printer_head's resonance test, as a 3D printer's firmware runs one: a swept force, an accelerometer, a fit.

The variant `ResonanceTest` of the scenario `resonance_test`. The motor pushes a linear chirp of `sweep_force`
[N] from `sweep_low_hz` to `sweep_high_hz` over the whole run (springlab.exact.resonance.chirp, held over each
step: the record's input is exactly what the plant received); the carriage accelerometer (MuJoCo's
`accelerometer` sensor at a site on the carriage, control.add_instruments) is read every
1 / `accelerometer_rate_hz` (a whole number of steps) along the rail, with Gaussian noise of standard
deviation `accelerometer_noise` [m/s^2] per reading from numpy's generator seeded with `seed` (the sensor's
noise does not act on the physics). The belt mode is fitted to that record (resonance.fit_resonance: the
exact zero-order-hold accelerance, an output-error least-squares fit, its covariance and 95 % intervals).

Then, as a firmware engineer would: the measured frequency and damping choose the shaper
(positioning.fastest_shaper: each candidate designed at the estimate, judged by its worst exact positioning
time of the bang-bang move over the interval's ends and middle), and the chosen shaped move is run in
MuJoCo on the true model (the `move_<shaper>` scenario at the measured design point) to verify it.

Quantities: `belt_frequency_hz_measured` with `belt_frequency_hz_ci95` [low, high] and its width,
`belt_damping_ratio_measured` with `belt_damping_ratio_ci95`, `accelerometer_noise_fitted_m_s2` (the residuals'
standard deviation), `accelerometer_samples`, `chosen_shaper` with `chosen_shaper_positioning_time_s` (MuJoCo's
verifying run) and `_exact` (on the true belt), and `belt_frequency_error` (measured / true - 1) against the
model's own `natural_frequency_hz`. The carriage's and motor's motion is compared with the exact held run
(held.py). A band that misses the resonance is refused (ParameterError, nothing written).
Forces [N], frequencies [Hz], accelerations [m/s^2], times [s].
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from springlab.errors import ParameterError
from springlab.exact import positioning, resonance, sampled_loop, shaping
from springlab.scenes.declarations import Reference
from springlab.sim.sampled import steps_per_sample
from springlab.sim.simulate import Setup

from .control import ACCELEROMETER, belt_plant
from .held import held_reference, initial_vector
from .moves import BeltRun, Variant, initial_qpos_qvel, move_profile

if TYPE_CHECKING:
    from springlab.scenes.base import Case

__all__ = ["RESONANCE_PARAMETERS", "ResonanceTest"]

#: the resonance test's own parameters
RESONANCE_PARAMETERS = frozenset(
    {"sweep_low_hz", "sweep_high_hz", "sweep_force", "accelerometer_rate_hz", "accelerometer_noise", "seed"}
)


class ResonanceTest(Variant):
    """resonance_test's variant (module docstring)."""

    parameters = RESONANCE_PARAMETERS
    instruments = True

    def check(self, params: dict[str, float]) -> None:
        """The band must be ordered and the sweep within the motor's force limit."""
        low, high = params["sweep_low_hz"], params["sweep_high_hz"]
        if not low < high:
            raise ParameterError(f"the sweep needs sweep_low_hz < sweep_high_hz, got {low:g} and {high:g} Hz")
        if params["sweep_force"] > params["drive_force"]:
            raise ParameterError(
                f"sweep_force = {params['sweep_force']:g} N exceeds drive_force = {params['drive_force']:g} N"
                " (the motor's limit would clip the sweep)"
            )
        if not float(params["seed"]).is_integer():
            raise ParameterError(f"seed must be a whole number, got {params['seed']:g}")

    @staticmethod
    def every(params: dict[str, float], dt: float) -> int:
        """Steps per accelerometer reading (ParameterError: faster than the step, or not a whole number)."""
        try:
            return steps_per_sample(params["accelerometer_rate_hz"], dt)
        except ValueError as error:
            raise ParameterError(str(error).replace("control rate", "accelerometer rate")) from None

    @staticmethod
    def sweep(params: dict[str, float], steps: int, dt: float) -> np.ndarray:
        """The chirp's force per step [N] over the run (none for a run of less than two steps: no sweep at all)."""
        if steps < 2:
            return np.zeros(steps)
        return resonance.chirp(params["sweep_force"], params["sweep_low_hz"], params["sweep_high_hz"], steps * dt, dt)

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        """Rest (or the deflected belt), the chirp as per-step controls."""
        self.every(case.params, dt)
        qpos, qvel = initial_qpos_qvel(case)
        return Setup(qpos=qpos, qvel=qvel, control=self.sweep(case.params, steps, dt)[:, None])

    def reference(self, case: Case, time: np.ndarray, dt: float) -> Reference:
        """The exact held run of the chirp (held.held_reference, open loop)."""
        steps = len(time) - 1
        force = self.sweep(case.params, steps, dt)
        a, b = belt_plant(case.model)
        states, forces = case.memo(
            ("resonance_exact", dt, steps),
            lambda: sampled_loop.held_open_run(a, b, dt, initial_vector(case), force[:steps]),
        )
        return held_reference(case, time, dt, states, forces)

    def quantities(self, out: dict, run: BeltRun) -> dict:
        """The fit, its intervals, the shaper it chooses and MuJoCo's verifying move (module docstring)."""
        assert run.case is not None and run.trajectory is not None, "the scene passes the case and the run"
        case, params, dt = run.case, run.params, run.dt
        sensors = run.trajectory.sensordata
        assert sensors is not None, "simulate records the sensors"
        every = self.every(params, dt)
        steps = len(run.time) - 1
        force = self.sweep(params, steps, dt)
        address = int(case.model.sensor(ACCELEROMETER).adr[0])  # its first axis: along the rail
        readings = sensors[:steps:every, address]
        rng = np.random.default_rng(int(params["seed"]))
        noisy = readings + params["accelerometer_noise"] * rng.standard_normal(readings.size)
        band = (params["sweep_low_hz"], params["sweep_high_hz"])
        try:
            fit = resonance.fit_resonance(force, noisy, dt, every, band)
        except ValueError as error:
            raise ParameterError(str(error)) from None
        low, high = fit.frequency_ci95
        out["accelerometer_samples"] = fit.samples
        out["accelerometer_noise_fitted_m_s2"] = fit.noise
        out["belt_frequency_hz_measured"] = fit.frequency_hz
        out["belt_frequency_hz_ci95"] = [low, high]
        out["belt_frequency_ci95_width_hz"] = high - low
        out["belt_frequency_error"] = fit.frequency_hz / out["natural_frequency_hz"] - 1
        out["belt_damping_ratio_measured"] = fit.damping_ratio
        out["belt_damping_ratio_ci95"] = list(fit.damping_ci95)
        out.update(self._choose_and_verify(case, fit, dt))
        return out

    def _choose_and_verify(self, case: Case, fit: resonance.ResonanceFit, dt: float) -> dict:
        """The shaper the measured values choose, and its move run in MuJoCo on the true model."""
        params = case.params
        low, high = fit.frequency_ci95
        n, _ = move_profile(params, dt)
        duration, distance, band = 2 * n * dt, params["move_distance"], params["positioning_band"]
        candidates = [
            shaping.on_grid(shaping.make_shaper(name, fit.frequency_hz, fit.damping_ratio), dt)
            for name in shaping.SHAPERS
        ]
        chosen, worst = positioning.fastest_shaper(
            candidates, (low, fit.frequency_hz, high), fit.damping_ratio, distance, duration, band
        )
        # the true model (this case's physical parameters), the shaper at the measured design point
        physical = {name: value for name, value in params.items() if name not in RESONANCE_PARAMETERS}
        design = {"shaper_frequency_hz": fit.frequency_hz, "shaper_damping_ratio": fit.damping_ratio}
        verifying = case.scene.case(f"move_{chosen.name}", physical | design)
        verified = verifying.quantities(verifying.simulate(case.scene.integrator, dt, verifying.scenario.duration))
        return {
            "chosen_shaper": chosen.name,
            "shaper_worst_positioning_time_s": worst,
            "chosen_shaper_positioning_time_s": verified["positioning_time_s"],
            "chosen_shaper_positioning_time_s_exact": verified["positioning_time_s_exact"],
            "chosen_shaper_residual_amplitude_m": verified["residual_amplitude_m"],
        }
