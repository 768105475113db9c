"""stay_cable: the bridge in the wind (chapter 5's closing question), a 300 m stay, its damper and the wind.

"How much does the Erasmus bridge vibrate under the influence of the wind?" Two months after it opened in
1996 its stays swung in wind and rain; the fix was dampers between the stays and the deck. The stay is a taut
string (tension T, mass per length m, length L); the MuJoCo model lumps it into N moving nodes on transverse
slide joints joined by springs T / dx (models/stay_cable.xml, generated for any N by
springlab.scenes.stay_cable.build), a viscous damper at distance a from the deck anchor, a uniform random wind
load through one motor, and rain-wind's negative aerodynamic damping on the first modes. Three gaps are
measured apart, as in the drill string:

* integration: the MuJoCo run against the N-element model solved exactly (M, C, K read back from the compiled
  model, springlab.scenes.stay_cable.readback): the `_exact` quantities;
* discretization: the N-element model's exact answer against the continuum's (`_continuum`), O(N^-2);
* statistics (the wind): a finite record's RMS against the exact stationary one, within the record's own
  confidence interval (springlab.exact.random_vibration), the hold and the integrator's bias reported apart.

Scenarios:

* `modes`: released in mode 1 (no damping at all): the frequencies against their closed form and the continuum.
* `damper` (default): the free decay of mode 1 with the damper (its complex mode, no intrinsic damping): the
  frequency and damping ratio against the N-element model's quadratic eigenproblem, the continuum's
  transcendental equation and the universal curve; the damper that damps mode 1 most, and how much.
* `wind`: the cable with its damper in a random wind (white in time, uniform along the span, seeded), started
  from its stationary state: the RMS deflection at mid-span against the exact one, within the 600 s record's
  own interval; how much the damper cuts it.
* `rain_wind`: negative aerodynamic damping on mode 1 (zeta_a = aero_damping_ratio, no damper): the run started
  in the fastest-growing mode grows at Re(lambda) of the complex eigenvalue; the smallest damper that stops it.

RK4 for the free scenarios (its step, a polynomial of A dt, keeps a mode a mode: springlab.scenes.stay_cable.modal),
implicitfast for the wind (the damper's fast local decay, c_d / (m dx) = 1600 1/s at the defaults, is joint damping,
which implicitfast integrates implicitly; RK4 would need dt < 1.7 ms).
"""

from __future__ import annotations

import functools
import math
import weakref
from typing import Any

import mujoco
import numpy as np

from springlab.errors import ParameterError
from springlab.exact.cable import whole_elements
from springlab.scenes.base import Case, Check, Parameter, Reference, Scenario, Scene, parsed_spec
from springlab.scenes.capabilities.random_load import RandomLoadSpec
from springlab.sim import model_files
from springlab.sim.simulate import ROUNDOFF_PER_STEP, Setup, Trajectory

from . import answers, build, figures, modal, stationary
from .readback import CableModel, cable_model

#: the most nodes a cable may have (the wind's exact covariances are O(N^3): about 10 s at 1000)
MAX_ELEMENTS = 1000
#: nodes of the shipped model (dx = 3 m: the damper at 6 m is node 2, mid-span node 50)
DEFAULT_ELEMENTS = 99
#: the largest seed (numpy's generators take any; 2^32 - 1 keeps it a plain integer everywhere)
MAX_SEED = 2**32 - 1
#: a free scenario starts with this deflection [m] at the node where its mode is largest
START_AMPLITUDE = {"modes": 0.5, "damper": 0.5, "rain_wind": 0.05}


def _positive(name: str, unit: str, description: str) -> Parameter:
    return Parameter(name, unit, description, minimum=0.0, minimum_inclusive=False)


def _reported(model: mujoco.MjModel) -> tuple[str, str]:
    """(mid-span joint, damper joint) names of a compiled model: the trajectory's columns."""
    cable = CableModel.of(model)
    return f"n{cable.midspan}", f"n{cable.damper_node}"


class StayCable(Scene):
    name = "stay_cable"
    title = "The bridge in the wind: a 300 m stay, its damper, and how much it vibrates under random wind"
    #: the shipped model's reported joints (mid-span, the damper's node); other N report their own two
    joints = (f"n{(DEFAULT_ELEMENTS + 1) // 2}", "n2")
    camera = "side"
    integrator = "rk4"
    dt = 1e-3
    default_scenario = "damper"
    parameters = {
        p.name: p
        for p in (
            Parameter(
                "n_elements",
                "-",
                "moving nodes N the stay is cut into (dx = L / (N + 1); a whole number)",
                minimum=2,
                maximum=MAX_ELEMENTS,
                reason=f"a whole number of nodes, at least 2 and at most {MAX_ELEMENTS} (the wind's exact"
                " covariances cost O(N^3))",
            ),
            _positive("length", "m", "length L of the stay between its anchors"),
            _positive("tension", "N", "tension T of the stay"),
            _positive("mass_per_length", "kg/m", "mass per length m of the stay (strands and pipe)"),
            _positive("damper_position", "m", "distance a of the damper from the deck anchor (0 < a < L)"),
            Parameter("damper_coefficient", "N s/m", "viscous coefficient c_d of the damper", minimum=0.0),
            Parameter(
                "structural_damping_ratio",
                "-",
                "the stay's own damping ratio of mode 1 (viscous, proportional to mass)",
                minimum=0.0,
                maximum=1.0,
            ),
            Parameter(
                "aero_damping_ratio",
                "-",
                "rain-wind's aerodynamic damping ratio on the first aero_modes modes (negative: rain-wind)",
                minimum=-1.0,
                maximum=1.0,
            ),
            Parameter(
                "aero_modes",
                "-",
                "how many of the first modes carry aero_damping_ratio (a whole number <= N)",
                minimum=0.0,
            ),
            Parameter(
                "wind_intensity",
                "N^2 s/m^2",
                "spectral density S of the wind's load per length (white, two-sided: E[p(t) p(t+s)] = S delta(s))",
                minimum=0.0,
            ),
            Parameter(
                "seed",
                "-",
                "the wind's random stream (and the stationary start's): the same seed, the same wind",
                minimum=0.0,
                maximum=float(MAX_SEED),
                default=0.0,
            ),
        )
    }
    scenarios = {
        s.name: s
        for s in (
            Scenario(
                "modes",
                "released in mode 1, no damping: the N-element frequencies against the closed form and the continuum",
                20.0,
                presets={"damper_coefficient": 0.0, "structural_damping_ratio": 0.0},
                dt=0.01,
            ),
            Scenario(
                "damper",
                "free decay of mode 1 with the damper: its complex mode against the exact and the continuum",
                20.0,
                presets={"structural_damping_ratio": 0.0},
                dt=1e-3,
            ),
            Scenario(
                "wind",
                "random wind on the stay with its damper: the RMS deflection against the exact, within the record's"
                " interval",
                600.0,
                dt=5e-3,
                integrator="implicitfast",
            ),
            Scenario(
                "rain_wind",
                "negative aerodynamic damping on mode 1, no damper: the growth rate and the damper that stops it",
                120.0,
                presets={"damper_coefficient": 0.0, "aero_modes": 1.0},
                dt=5e-3,
            ),
        )
    }
    questions = {
        "modes": (
            "What are the stay's natural frequencies, and how close is the N-element model to the cable?",
            "f1 = {mode_1_frequency_hz_continuum:.6g} Hz for the cable (period {mode_1_period_s_continuum:.5g} s;"
            " f_n = n f1); the {n_elements:.0f}-node model's is exactly {mode_1_frequency_hz_exact:.7g} Hz (low by"
            " {mode_1_discretization_error:.2g}, (π / (N + 1))² / 24) and the run measures {mode_1_frequency_hz:.7g}"
            " Hz.",
        ),
        "damper": (
            "Which damper coefficient damps the stay's first mode most at this position, and how much damping does"
            " it buy?",
            "At a = {damper_node_position_m:.3g} m the best damper is {optimal_damper_n_s_m_continuum:.4g ~N s/m}"
            " (the rule sqrt(T m) L / (π a): {optimal_damper_n_s_m_universal:.4g ~N s/m}); it gives mode 1 a damping"
            " ratio of {max_damping_ratio_continuum:.4g %} (rule a / 2L: {max_damping_ratio_universal:.4g %}). This"
            " damper ({damper_coefficient:.4g ~N s/m}) gives {mode_1_damping_ratio_continuum:.6g %} on the cable,"
            " exactly {mode_1_damping_ratio_exact:.6g %} on the {n_elements:.0f}-node model; the run measures"
            " {mode_1_damping_ratio:.6g %}.",
        ),
        "wind": (
            "How much does the stay vibrate in the wind, and how much does its damper help?",
            "Mid-span RMS deflection {rms_displacement_m_exact:.3g ~m} exactly with the damper"
            " ({damper_coefficient:.3g ~N s/m} at {damper_position:.3g} m), {rms_displacement_m_no_damper:.3g ~m}"
            " without it: the damper cuts it {rms_reduction_factor:.3g} times. This {duration_s:.4g} s record"
            " measured {rms_displacement_m:.3g ~m} (95 % of such records fall within {rms_low_m:.3g ~m} to"
            " {rms_high_m:.3g ~m}; hold {variance_hold_error:+.1e}, integrator {variance_integrator_error:+.1e} of the"
            " variance).",
        ),
        "rain_wind": (
            "How fast does rain-wind vibration grow, and what is the smallest damper that stops it?",
            "Without a damper mode {growing_mode:.0f} grows at {growth_rate_1_s_exact:.7g} 1/s exactly (doubling every"
            " {doubling_time_s:.3g} s; the run measures {growth_rate_1_s:.7g} 1/s); a damper of at least"
            " {stabilising_damper_n_s_m:.4g ~N s/m} at {damper_node_position_m:.3g} m stops it (the universal curve"
            " says {stabilising_damper_n_s_m_universal:.4g ~N s/m}).",
        ),
    }
    figure = staticmethod(figures.panels)
    #: `springlab rms`: the wind's RMS at mid-span from many seeds, and what an accurate one costs
    random_load = RandomLoadSpec(
        scenario="wind",
        seed="seed",
        quantity="rms_displacement_m",
        description="the RMS deflection at mid-span",
        unit="m",
        output=stationary.midspan_output,
        exact=stationary.midspan_exact,
        continuous=stationary.midspan_continuous,
        setup=stationary.seeded_setup,
        size="n_elements",
        sizes=(49, 99, 199, 399),
        order=2.0,
    )

    # -- parameters and model ----------------------------------------------------

    def model_defaults(self, model: mujoco.MjModel) -> dict[str, float]:
        values = {name: float(model.numeric(name).data[0]) for name in build.NUMERICS}
        values["n_elements"] = float(model.nv)
        return values

    def check_consistency(self, params: dict[str, float], scenario: Scenario) -> None:
        n = whole_elements(params["n_elements"])
        if not params["damper_position"] < params["length"]:
            raise ParameterError(
                f"damper_position must lie inside the cable, 0 < a < {params['length']:g} m,"
                f" got {params['damper_position']:g} m"
            )
        modes = params["aero_modes"]
        if modes != round(modes) or modes > n:
            raise ParameterError(f"aero_modes must be a whole number from 0 to n_elements ({n}), got {modes:g}")
        if params["seed"] != round(params["seed"]):
            raise ParameterError(f"seed must be a whole number from 0 to {MAX_SEED}, got {params['seed']:g}")

    def edit(self, spec: mujoco.MjSpec, params: dict[str, float], scenario: Scenario) -> None:
        build.generate(spec, params)

    def editable_spec(self) -> mujoco.MjSpec:
        """The shipped model without its cable (kept per process, `_without_cable`): `generate` writes every cable
        anew, and removing the shipped one element by element cost 70 ms of a 74 ms compile."""
        return _without_cable(str(model_files.path(self.name))).copy()

    @staticmethod
    def physical(model: mujoco.MjModel) -> tuple[float, ...]:
        """(L [m], T [N], m [kg/m], N [-], a of the damper's node [m], c_d [N s/m]) read back from the model."""
        cable = CableModel.of(model)
        return (
            cable.cable.length,
            cable.cable.tension,
            cable.cable.mass_per_length,
            float(cable.size),
            cable.damper_node * cable.cable.spacing(cable.size),
            cable.damper_coefficient,
        )

    def modes(self, case: Case) -> list[tuple[float, float]]:
        found = cable_model(case).lumped.complex_modes()
        out = [(float(abs(v)), float(-v.real / abs(v))) for v in found.oscillatory]
        return out + [(float(abs(v)), 1.0) for v in found.overdamped if v != 0]

    def stability_limit(self, case: Case, integrator: str, omega: float, zeta: float) -> float:
        """The default limit, except the overdamped modes (`modes` reports them with zeta = 1): a node held by the
        damper decays without ringing, and every integrator but RK4 treats joint damping implicitly."""
        if zeta >= 1.0 and integrator != "rk4":
            return math.inf
        return super().stability_limit(case, integrator, omega, zeta)

    def joint_columns(self, model: mujoco.MjModel, trajectory: Trajectory) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        columns = {}
        for joint in dict.fromkeys(_reported(model)):
            j = model.joint(joint)
            columns[joint] = (trajectory.qpos[:, j.qposadr[0]], trajectory.qvel[:, j.dofadr[0]])
        return columns

    # -- a run ------------------------------------------------------------------------

    def setup(self, case: Case, steps: int, dt: float) -> Setup:
        model = case.model
        if case.scenario.name == "wind":
            return stationary.seeded_setup(case, steps, dt, int(case.params["seed"]))
        mode, node = _free_mode(case)
        q0, v0, _ = mode.start(node, START_AMPLITUDE[case.scenario.name])
        return Setup(qpos=q0, qvel=v0, control=np.zeros((steps, model.nu)))

    def reference(self, case: Case, time: np.ndarray, *, dt: float) -> Reference | None:
        if case.scenario.name == "wind":
            return None  # random: held to its interval (checks)
        mode, node = _free_mode(case)
        _, _, scale = mode.start(node, START_AMPLITUDE[case.scenario.name])
        joints = list(dict.fromkeys(_reported(case.model)))
        pos, vel, rows, blocks = {}, {}, {}, []
        for i, joint in enumerate(joints):
            pos[joint], vel[joint] = mode.motion(scale, int(joint[1:]), time)
            rows[joint] = (2 * i, 2 * i + 1)
            blocks.append(mode.system())
        system = np.zeros((2 * len(joints), 2 * len(joints)))
        for i, block in enumerate(blocks):
            system[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = block
        states = np.column_stack([series for joint in joints for series in (pos[joint], vel[joint])])
        return Reference(pos=pos, vel=vel, system=system, states=states, rows=rows, roundoff=_roundoff(case, pos, dt))

    # -- results ----------------------------------------------------------------------

    def quantities(self, case: Case, trajectory: Trajectory) -> dict[str, Any]:
        cable = cable_model(case)
        out: dict[str, Any] = {
            "n_elements": cable.size,
            "wave_speed_m_s": cable.cable.wave_speed,
            "impedance_n_s_m": cable.cable.impedance,
            "damper_node_position_m": cable.damper_node * cable.cable.spacing(cable.size),
            "mode_1_frequency_hz_continuum": float(cable.cable.frequencies_hz(1)[0]),
            "mode_1_period_s_continuum": float(1.0 / cable.cable.frequencies_hz(1)[0]),
        }
        name = case.scenario.name
        if name == "wind":
            out.update(_wind_quantities(case, trajectory))
            return out
        mode, _ = _free_mode(case)
        measured = _measured(case, mode, trajectory)
        if name == "rain_wind":
            out.update(_rain_wind_quantities(case, mode, measured))
            return out
        out["mode_1_frequency_hz"] = abs(measured) / (2 * math.pi)
        out["mode_1_frequency_hz_exact"] = mode.frequency_hz
        if name == "modes":
            reported = min(3, cable.size)
            found = modal.modes(cable.lumped)
            for k in range(1, reported + 1):
                out[f"mode_{k}_frequency_hz_exact"] = found[k - 1].frequency_hz
                out[f"mode_{k}_frequency_hz_continuum"] = float(cable.cable.frequencies_hz(k)[k - 1])
            out["mode_1_discretization_error"] = abs(mode.frequency_hz / out["mode_1_frequency_hz_continuum"] - 1)
            return out
        out.update(_damper_quantities(case, mode, measured))
        return out

    def checks(self, case: Case, trajectory: Trajectory) -> list[Check]:
        if case.scenario.name == "wind":
            return [_rms_check(case, trajectory)]
        mode, _ = _free_mode(case)
        measured = _measured(case, mode, trajectory)
        bound = modal.value_error_bound(mode, trajectory.integrator, trajectory.dt)
        basis = modal.error_basis(trajectory.integrator)
        if case.scenario.name == "rain_wind":
            rate = mode.growth_rate
            return [Check("growth_rate_1_s", measured.real, rate, bound / abs(rate), basis)]
        size = abs(mode.value)
        checks = [Check("mode_1_frequency_hz", abs(measured) / (2 * math.pi), mode.frequency_hz, bound / size, basis)]
        if case.scenario.name == "damper" and mode.damping_ratio > 0:
            # zeta = -Re(lambda) / |lambda| moves by at most |d lambda| (1 + zeta) / |lambda|
            tolerance = bound * (1 + mode.damping_ratio) / size / mode.damping_ratio
            ratio = -measured.real / abs(measured)
            checks.append(Check("mode_1_damping_ratio", ratio, mode.damping_ratio, tolerance, basis))
        return checks


# -- helpers ----------------------------------------------------------------------------------------


def _roundoff(case: Case, pos: dict[str, np.ndarray], dt: float) -> dict[str, float]:
    """Round-off [m/s] one step may add to a reported node's velocity (`Reference.roundoff`).

    A node's acceleration is the sum of its springs' forces, (T / dx) (q[i-1] - 2 q[i] + q[i+1]) / (m dx):
    terms up to 4 T / (m dx^2) max|q| [m/s^2] that nearly cancel in a smooth mode, so each step's velocity carries
    ROUNDOFF_PER_STEP of their absolute sum times dt, whatever the velocity's own size (a short run from rest,
    whose velocities are still small, sees it first). The largest node's max|q| stands for every node's.
    """
    lumped = cable_model(case).lumped
    force_rate = float(np.max(np.abs(lumped.stiffness).sum(axis=1) / lumped.mass))  # [1/s^2]
    largest = max(float(np.max(np.abs(series))) for series in pos.values())
    per_step = ROUNDOFF_PER_STEP * force_rate * largest * dt
    return {f"{joint}_vel": per_step for joint in pos}


@functools.cache
def _without_cable(path: str) -> mujoco.MjSpec:
    """The model file at `path` without its cable (`StayCable.editable_spec`); callers copy it.

    The file is `build.scaffold()` with a cable generated into it (tests/scenes/stay_cable), its camera's orientation
    written as a rounded quaternion: so the scaffold with the file's camera orientation is the file without its
    cable, the compiled models byte for byte the same (tests/scenes/stay_cable/test_stay_cable_shortcuts.py), and
    nothing is deleted (removing the file's 200 cable elements one by one cost 70 ms).
    """
    spec = build.scaffold()
    for camera in parsed_spec(path).cameras:
        scaffolded = spec.camera(camera.name)
        scaffolded.alt.type, scaffolded.quat = camera.alt.type, camera.quat
    return spec


def _free_mode(case: Case) -> tuple[modal.Mode, int]:
    """(the mode a free scenario starts in, the node (1 ... N) where it is largest), once per case: mode 1, or
    in `rain_wind` the fastest-growing mode."""

    def compute() -> tuple[modal.Mode, int]:
        found = modal.modes(cable_model(case).lumped)
        mode = modal.fastest_growing(found) if case.scenario.name == "rain_wind" else found[0]
        n = len(mode.right) // 2
        return mode, int(np.argmax(np.abs(mode.right[:n]))) + 1

    return case.memo("free_mode", compute)


def _measured(case: Case, mode: modal.Mode, trajectory: Trajectory) -> complex:
    """lambda [1/s] the run measures (modal.measured_value), once per run: its quantities and its checks both ask,
    and the modal filter over the whole record (24,000 x 198 complex at rain_wind's) costs a tenth of a second.

    Kept on the case for the last run only, by identity (a weak reference: the case never keeps a record alive).
    """
    kept: list = case.memo("measured_run", lambda: [None])
    last = kept[0]
    if last is not None and last[0]() is trajectory and last[1] is mode:
        return last[2]
    value = modal.measured_value(mode, trajectory.qpos, trajectory.qvel, trajectory.steps * trajectory.dt)
    kept[0] = (weakref.ref(trajectory), mode, value)
    return value


def _damper_quantities(case: Case, mode: modal.Mode, measured: complex) -> dict[str, Any]:
    cable = cable_model(case)
    continuum = answers.continuum_mode_1(cable)
    best = case.memo("damper_optimum", lambda: answers.damper_optimum(cable))
    return {
        "mode_1_frequency_hz_continuum": abs(continuum) / (2 * math.pi),
        "mode_1_damping_ratio": -measured.real / abs(measured),
        "mode_1_damping_ratio_exact": mode.damping_ratio,
        "mode_1_damping_ratio_continuum": -continuum.real / abs(continuum),
        "mode_1_damping_ratio_universal": answers.universal_mode_1_ratio(cable),
        "optimal_damper_n_s_m_continuum": best.coefficient_continuum,
        "optimal_damper_n_s_m_exact": best.coefficient_exact,
        "optimal_damper_n_s_m_universal": best.coefficient_universal,
        "max_damping_ratio_continuum": best.ratio_continuum,
        "max_damping_ratio_exact": best.ratio_exact,
        "max_damping_ratio_universal": best.ratio_universal,
    }


def _rain_wind_quantities(case: Case, mode: modal.Mode, measured: complex) -> dict[str, Any]:
    cable = cable_model(case)
    stop = case.memo("stabilising", lambda: answers.stabilising(cable))
    rate = mode.growth_rate
    return {
        "growing_mode": mode.number,
        "growth_rate_1_s": measured.real,
        "growth_rate_1_s_exact": rate,
        "doubling_time_s": math.log(2) / rate if rate > 0 else math.inf,
        "mode_frequency_hz_exact": mode.frequency_hz,
        "growth_rate_1_s_no_damper": stop.growth_without,
        "stabilising_damper_n_s_m": stop.coefficient,
        "stabilising_damper_n_s_m_universal": stop.universal,
    }


def _wind_quantities(case: Case, trajectory: Trajectory) -> dict[str, Any]:
    cable = cable_model(case)
    exact = stationary.wind_exact(case, trajectory.integrator, trajectory.dt)
    mid = cable.midspan - 1
    n = cable.size
    interval = stationary.record_interval(exact, mid, trajectory.steps, stationary.REPORT_LEVEL)
    low, high = interval.rms_interval()
    intensity = float(case.params["wind_intensity"])
    bare = case.memo(
        "wind_no_damper",
        lambda: stationary.continuous_covariance(cable, intensity, damping=cable.without_damper().damping),
    )
    measured = math.sqrt(stationary.sample_variance(trajectory.qpos[:, mid]))
    exact_rms = exact.rms(mid)
    return {
        "duration_s": trajectory.steps * trajectory.dt,
        "midspan_node": cable.midspan,
        "rms_displacement_m": measured,
        "rms_displacement_m_exact": exact_rms,
        "rms_displacement_m_held": exact.rms(mid, "held"),
        "rms_displacement_m_integrator": exact.rms(mid, "integrator"),
        "rms_displacement_m_ci95": [low, high],
        "rms_low_m": low,
        "rms_high_m": high,
        "rms_displacement_m_no_damper": math.sqrt(float(bare[mid, mid])),
        "rms_reduction_factor": math.sqrt(float(bare[mid, mid])) / exact_rms,
        "rms_velocity_m_s": math.sqrt(stationary.sample_variance(trajectory.qvel[:, mid])),
        "rms_velocity_m_s_exact": exact.rms(n + mid),
        "rms_velocity_m_s_held": exact.rms(n + mid, "held"),
        "variance_hold_error": float(exact.held[mid, mid] / exact.continuous[mid, mid] - 1),
        "variance_integrator_error": float(exact.bias[mid, mid] / exact.held[mid, mid]),
        "variance_record_spread": interval.spread / interval.variance,
        "record_degrees_of_freedom": interval.degrees_of_freedom,
    }


def _rms_check(case: Case, trajectory: Trajectory) -> Check:
    """The mid-span RMS inside its record's CHECK_LEVEL interval around the exact held value (the tolerance
    the side it falls on: the interval is a scaled chi-square's, not symmetric)."""
    cable = cable_model(case)
    mid = cable.midspan - 1
    exact = stationary.wind_exact(case, trajectory.integrator, trajectory.dt)
    interval = stationary.record_interval(exact, mid, trajectory.steps, stationary.CHECK_LEVEL)
    low, high = interval.rms_interval()
    reference = exact.rms(mid, "held")
    measured = math.sqrt(stationary.sample_variance(trajectory.qpos[:, mid]))
    tolerance = (high / reference - 1) if measured >= reference else (1 - low / reference)
    basis = (
        f"the {stationary.CHECK_LEVEL:.0%} interval {low:.4g} to {high:.4g} m of a {trajectory.steps}-step record's"
        f" RMS around the exact held value (a scaled chi-square with {interval.degrees_of_freedom:.3g} degrees of"
        " freedom, from the record's exact autocovariance; a correct run falls outside with probability 1 %)"
    )
    return Check("rms_displacement_m", measured, reference, tolerance, basis, certifies_error=False)


SCENE = StayCable()
