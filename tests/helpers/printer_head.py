"""The printer head's belt and its sampled loop as the tests build them, apart from springlab's code: the
constants read once from the shipped MJCF (tests/scenes/printer_head/test_printer_shaping.py and
test_printer_control_scene.py), the controller's setting, and the closed loop written out with its RK4 error
bound (tests/scenes/printer_head/test_printer_feedback.py's docstring derives it; test_printer_control_scene.py
holds the scene's loop to the same)."""

import math

import mujoco
import numpy as np
import scipy.integrate
import scipy.linalg

import springlab.sim.model_files
from springlab.exact import sampled_loop


def _defaults():
    """(m_c, m_m, k, c, drive force, move distance, band) read from the shipped MJCF."""
    model = mujoco.MjModel.from_xml_path(str(springlab.sim.model_files.path("printer_head")))
    belt = model.tendon("belt").id
    return (
        float(model.body("carriage").mass[0]),
        float(model.body("motor").mass[0]),
        float(model.tendon_stiffness[belt]),
        float(model.tendon_damping[belt]),
        float(model.actuator("drive").ctrlrange[1]),
        float(model.numeric("move_distance").data[0]),
        float(model.numeric("positioning_band").data[0]),
    )


M_C, M_M, K, C, FORCE, DISTANCE, BAND = _defaults()
TOTAL, MU = M_C + M_M, M_C * M_M / (M_C + M_M)
OMEGA = math.sqrt(K / MU)
ZETA = C / (2 * math.sqrt(K * MU))
F_N = OMEGA / (2 * math.pi)

RATE = 5000.0  # controller rate [Hz]
PERIOD = 1 / RATE
SUBSTEPS = 2  # MuJoCo steps per sample
REFERENCE = 1e-3  # a 1 mm step of the set point [m]


def feedback_plant():
    """(A, B) written out from the shipped model's masses, belt and gear (not control.belt_plant)."""
    model = mujoco.MjModel.from_xml_path(str(springlab.sim.model_files.path("printer_head")))
    m_c, m_m = model.body("carriage").mass[0], model.body("motor").mass[0]
    k, c = model.tendon_stiffness[0], model.tendon_damping[0]
    a = np.array(
        [
            [0, 0, 1, 0],
            [0, 0, 0, 1],
            [-k / m_c, k / m_c, -c / m_c, c / m_c],
            [k / m_m, -k / m_m, c / m_m, -c / m_m],
        ]
    )
    return a, np.array([[0.0], [0.0], [0.0], [model.actuator("drive").gear[0] / m_m]])


def reference_loop(gains, row, samples, gain=1.0):
    """The sampled loop from rest, written out: Phi by expm, Gamma by quadrature, the law's difference equation."""
    a, b = feedback_plant()
    phi = scipy.linalg.expm(a * PERIOD)
    gamma = scipy.integrate.quad_vec(lambda t: scipy.linalg.expm(a * t) @ b[:, 0], 0.0, PERIOD, epsabs=0, epsrel=1e-14)[
        0
    ]
    kp, kd, ki = (gain * g for g in gains)
    x, previous, integral = np.zeros(4), 0.0, 0.0
    ys, us = [], []
    for _ in range(samples):
        y = x[row]
        error = REFERENCE - y
        integral += PERIOD * error
        u = kp * error - kd * (y - previous) / PERIOD + ki * integral
        previous = y
        ys.append(y)
        us.append(u)
        x = phi @ x + gamma * u
    ys.append(x[row])
    return np.array(ys), np.array(us), phi, gamma


def rk4_loop_bound(phi, gamma, output, pid, states, forces):
    """Bound [m] per sample on |y_MuJoCo - y_exact| from RK4's order (module docstring)."""
    a, b = feedback_plant()
    eigenvalues, right = np.linalg.eig(a)
    belt = int(np.argmax(eigenvalues.imag))  # the belt mode's root with omega_d > 0
    lam = eigenvalues[belt]
    left = np.linalg.inv(right)[belt]  # eta = left @ x, x_belt = 2 Re(right[:, belt] eta)
    z = abs(lam) * PERIOD / SUBSTEPS
    per_step = z**5 / 120 / (1 - z / 6)
    eta = states @ left
    equilibrium = -(left @ b[:, 0]) * forces / lam
    local = SUBSTEPS * per_step * np.abs(eta[:-1] - equilibrium)
    a_cl = sampled_loop.closed_loop(phi, gamma, output, pid)[0]
    w = np.column_stack([2 * right[:, belt].real, -2 * right[:, belt].imag])
    row = np.zeros(len(a_cl))
    row[:4] = output.reshape(-1)
    gains = []
    for _ in range(len(local)):
        gains.append(np.linalg.norm(row[:4] @ w))
        row = row @ a_cl
    return np.concatenate([[0.0], np.convolve(local, gains)[: len(local)]])
