"""printer_head's instruments and its plant for control: encoders, an accelerometer, the belt model's matrices.

The printer's sensors as MuJoCo sensors, added by an MjSpec edit (the shipped model has none, so plain runs
pay nothing for them):

* `motor_encoder`: the drive point's position q_m [m] (jointpos on `motor`: an encoder on the motor shaft
  read through the pulley radius), the collocated measurement;
* `carriage_encoder`: the carriage's position q_c [m] (jointpos on `carriage`: a linear encoder strip along
  the rail), across the belt from the force: non-collocated;
* `carriage_accelerometer`: the carriage's acceleration [m/s^2] along the rail and the two axes across
  (accelerometer at the site `accelerometer`, on the carriage; the rail is horizontal and gravity is off).

The plant for control is the two-mass belt model read back from the compiled model (masses, the belt
tendon's stiffness and damping, the actuator's gear): x = (q_c, q_m, v_c, v_m), x' = A x + B F,
F the motor's control [N].
"""

from __future__ import annotations

import mujoco
import numpy as np

__all__ = ["ENCODERS", "add_instruments", "belt_plant", "output_row"]

#: encoder placement -> (sensor name, state index it reads in x = (q_c, q_m, v_c, v_m))
ENCODERS: dict[str, tuple[str, int]] = {"motor": ("motor_encoder", 1), "carriage": ("carriage_encoder", 0)}
#: the accelerometer's sensor name and its site on the carriage
ACCELEROMETER = "carriage_accelerometer"


def add_instruments(spec: mujoco.MjSpec, *, force_limit: bool = True) -> None:
    """Add the two encoders and the carriage accelerometer (module docstring) to a printer_head spec.

    Parameters
    ----------
    spec
        An MjSpec of models/printer_head.xml (edited in place).
    force_limit
        False lifts the drive's ctrlrange, for linear loop studies whose forces must not saturate.
    """
    spec.body("carriage").add_site(name="accelerometer", pos=[0.0, 0.0, 0.0], size=[0.002, 0.0, 0.0])
    for name, joint in (("motor_encoder", "motor"), ("carriage_encoder", "carriage")):
        spec.add_sensor(
            name=name, type=mujoco.mjtSensor.mjSENS_JOINTPOS, objtype=mujoco.mjtObj.mjOBJ_JOINT, objname=joint
        )
    accelerometer = mujoco.mjtSensor.mjSENS_ACCELEROMETER
    spec.add_sensor(name=ACCELEROMETER, type=accelerometer, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="accelerometer")
    if not force_limit:
        spec.actuator("drive").ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE


def belt_plant(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray]:
    """(A [1/s], B [1/kg]) of x = (q_c, q_m, v_c, v_m) driven by the motor's control F [N], read from `model`.

    m_c q_c'' = k s + c s', m_m q_m'' = gear F - k s - c s', s = q_m - q_c (the tendon `belt`).
    """
    m_c, m_m = float(model.body("carriage").mass[0]), float(model.body("motor").mass[0])
    belt = model.tendon("belt").id
    k, c = float(model.tendon_stiffness[belt]), float(model.tendon_damping[belt])
    gear = float(model.actuator("drive").gear[0])
    inverse_mass = np.diag([1 / m_c, 1 / m_m])
    coupling = np.array([[1.0, -1.0], [-1.0, 1.0]])  # the belt stretches by q_m - q_c
    a = np.zeros((4, 4))
    a[:2, 2:] = np.eye(2)
    a[2:, :2] = -inverse_mass @ (k * coupling)
    a[2:, 2:] = -inverse_mass @ (c * coupling)
    b = np.array([[0.0], [0.0], [0.0], [gear / m_m]])
    return a, b


def output_row(encoder: str) -> np.ndarray:
    """C [-] (1, 4) reading the encoder's position from x = (q_c, q_m, v_c, v_m).

    Raises
    ------
    ValueError
        An encoder other than those of ENCODERS (the message lists them).
    """
    if encoder not in ENCODERS:
        raise ValueError(f"unknown encoder {encoder!r}; valid: {', '.join(ENCODERS)}")
    row = np.zeros((1, 4))
    row[0, ENCODERS[encoder][1]] = 1.0
    return row
