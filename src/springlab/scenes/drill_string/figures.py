"""The drill string's own figure of a run (`Scene.figure`): speeds with the exact events, twist, mode shapes.

Each scenario gets two panels (springlab.scenes.capabilities.figure.Panel), drawn by springlab.plots.run.scene_figure:

* `modes`: the first three mode shapes of the N-element model (dashed) beside the continuum's sin(beta_n x)
  (dotted), each scaled to 1 at its largest; the twist along the string at a few instants of the run.
* `spin_up`, `breakaway`: the top drive's and the bit's speed against time, the bit's exact (N elements,
  dashed) and continuum (dotted) speed on top, the exact breakaway and re-stick marked (the events the run reports, answers.RESTICK_FRACTION); the twist along
  the string (each node's angle minus the top drive's, in turns) at chosen instants.
"""

from __future__ import annotations

import math

import numpy as np

from springlab.scenes.capabilities.case import CaseView
from springlab.scenes.capabilities.figure import Curve, Panel
from springlab.sim.simulate import Trajectory

from . import answers
from .lumped import ModalFlow

#: mode shapes drawn by the `modes` panel
SHAPES = 3
#: the speed curves are drawn at most at this many instants
SAMPLES = 1500


def panels(case: CaseView, trajectory: Trajectory) -> tuple[Panel, ...]:
    """The panels of a run of the case's scenario (see the module docstring).

    Parameters
    ----------
    case
        the case that ran.
    trajectory
        the run.

    Returns
    -------
    tuple[Panel, ...]
        two panels.
    """
    model, scenario = case.model, case.scenario.name
    rod = answers.rod_of_case(case)
    lumped = answers.lumped_of(case)
    depth = np.linspace(0.0, rod.length, lumped.size)
    if scenario == "modes":
        _, shapes = answers.modes_of(case)
        continuum_shapes = rod.shapes(SHAPES, depth)
        curves = []
        for k in range(min(SHAPES, shapes.shape[1])):
            discrete = shapes[:, k] / np.max(np.abs(shapes[:, k]))
            exact = continuum_shapes[k] / np.max(np.abs(continuum_shapes[k]))
            exact *= math.copysign(1.0, float(exact[-1] * discrete[-1])) if exact[-1] * discrete[-1] != 0 else 1.0
            curves.append(Curve(f"mode {k + 1}: {lumped.size - 1} elements", depth, discrete, "exact"))
            curves.append(Curve(f"mode {k + 1}: continuum", depth, exact, "continuum"))
        omega, _ = answers.modes_of(case)
        period = 2 * math.pi / float(omega[0])
        instants = [0.0, period / 8, period / 4 * 0.9, period / 2]
        return (
            Panel("mode shapes: N elements vs the continuum", "depth x [m]", "twist, scaled to 1 [-]", tuple(curves)),
            _twist_panel(trajectory, depth, instants),
        )
    time = trajectory.time
    every = max(1, len(time) // SAMPLES)
    sample = time[::every]
    top_speed = trajectory.qvel[::every, 0]
    bit_speed = trajectory.qvel[::every, -1]
    drive = answers.drive_of(model, trajectory.dt)
    curves = [
        Curve("top drive (MuJoCo)", sample, top_speed / answers.RPM),
        Curve("bit (MuJoCo)", sample, bit_speed / answers.RPM),
    ]
    marks: list[tuple[float, str]] = []
    duration = float(time[-1])
    if scenario == "spin_up":
        flow = ModalFlow.of(np.diag(lumped.mass), lumped.stiffness)
        _, exact_v = answers.linear_samples(lumped, flow, drive, sample)
        continuum_v = rod.modal_spin_up_speed(
            sample, rod.length, drive.acceleration, drive.ramp_time, answers.CONTINUUM_MODES
        )
        curves.append(Curve(f"bit, {lumped.size - 1} elements exact", sample, exact_v[:, -1] / answers.RPM, "exact"))
        curves.append(Curve("bit, continuum (modal series)", sample, continuum_v / answers.RPM, "continuum"))
        instants = [0.25 * drive.ramp_time, 0.5 * drive.ramp_time, drive.ramp_time, duration / 2, duration]
    else:
        exact = answers.stick_slip(lumped, duration, drive)
        _, exact_v = lumped.solution_at(exact, sample, lumped.drive_control(drive.acceleration), drive.ramp_time)
        solver, wave = answers.wave_solution(rod, lumped.friction, drive.acceleration, drive.ramp_time, duration)
        continuum_v = np.array([solver.speed(t) for t in sample])
        curves.append(Curve(f"bit, {lumped.size - 1} elements exact", sample, exact_v[:, -1] / answers.RPM, "exact"))
        curves.append(Curve("bit, continuum (travelling waves)", sample, continuum_v / answers.RPM, "continuum"))
        breakaway = exact.first("slip")
        # the run's own events (answers.RESTICK_FRACTION), at their exact N-element instants
        restick = answers.restick_exact(lumped, exact, drive)
        marks.append((breakaway, f"breakaway (exact) {breakaway:.5g} s"))
        if math.isfinite(restick):
            level = answers.RESTICK_FRACTION * drive.speed / answers.RPM
            marks.append((restick, f"re-stick (exact, below {level:.2g} rpm) {restick:.4g} s"))
        instants = [t for t in (0.5 * breakaway, breakaway, exact.peak_time, restick) if math.isfinite(t)]
    speeds = Panel(
        "top drive and bit speed",
        "time t [s]",
        "speed [rpm]",
        tuple(curves),
        tuple((t, label) for t, label in marks if math.isfinite(t)),
    )
    return speeds, _twist_panel(trajectory, depth, instants)


def _twist_panel(trajectory: Trajectory, depth: np.ndarray, instants: list[float]) -> Panel:
    """Each node's angle behind the top drive [turns] against depth, at the run's steps nearest `instants`."""
    curves = []
    for t in instants:
        i = int(np.argmin(np.abs(trajectory.time - t)))
        angles = trajectory.qpos[i]
        curves.append(Curve(f"t = {trajectory.time[i]:.3g} s", depth, (angles - angles[0]) / (2 * math.pi)))
    return Panel("twist along the string", "depth x [m]", "angle - top drive's [turns]", tuple(curves))
