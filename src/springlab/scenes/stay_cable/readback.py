"""The stay cable as the compiled model holds it: the continuum's constants and the N-element matrices, read back.

Every exact answer of the scene starts here, from the compiled MjModel (never from the parameters that built
it): the continuum (L, T, m from the model's numerics), the node masses (body_mass), K from the segment
tendons' stiffness and coefficients, C from the joints' damping and the aerodynamic tendons' damping, the
wind's load vector from the motor's gear and its tendon's coefficients (springlab.scenes.stay_cable.build
says how each is encoded). The case keeps them (`Case.memo`): every hook of a case reads them once.
"""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np

from springlab.exact.cable import LumpedCable, TautCable
from springlab.scenes.capabilities.case import CaseView

#: the motor that carries the wind's load
WIND_ACTUATOR = "wind"
#: prefixes of the tendons: the string's segments and rain-wind's modal damping
SEGMENT_PREFIX, AERO_PREFIX = "segment_", "aero_"


def _numeric(model: mujoco.MjModel, name: str) -> float:
    return float(model.numeric(name).data[0])


def cable_of(model: mujoco.MjModel) -> TautCable:
    """The continuum the model discretizes: length [m], tension [N], mass per length [kg/m] from its numerics."""
    return TautCable(_numeric(model, "length"), _numeric(model, "tension"), _numeric(model, "mass_per_length"))


def _tendon_row(model: mujoco.MjModel, tendon: int) -> np.ndarray:
    """The coefficients (nv,) of a fixed tendon on the joints (its wraps' joint ids and coefficients)."""
    row = np.zeros(model.nv)
    start, count = int(model.tendon_adr[tendon]), int(model.tendon_num[tendon])
    for w in range(start, start + count):
        row[int(model.jnt_dofadr[int(model.wrap_objid[w])])] += float(model.wrap_prm[w])
    return row


def _tendon_rows(model: mujoco.MjModel, prefix: str) -> list[tuple[int, np.ndarray]]:
    """[(tendon id, its coefficients on the nv joints)] of the fixed tendons whose names start with `prefix`."""
    return [(t, _tendon_row(model, t)) for t in range(model.ntendon) if model.tendon(t).name.startswith(prefix)]


@dataclasses.dataclass(frozen=True)
class CableModel:
    """What the compiled model says, SI.

    Attributes
    ----------
    cable
        the continuum (TautCable).
    lumped
        M, C, K of the N-element model (LumpedCable): read back, so a run is compared with the model it ran.
    load
        (N,) the force [N] on each node per unit of the wind's control [N/m] (the motor's gear times its
        tendon's coefficients: dx on every node).
    damper_node
        the node (1 ... N) that carries the damper: the one nearest its position (numeric `damper_position`).
    damper_coefficient
        c_d [N s/m]: that joint's damping less the intrinsic damping every node has.
    background
        the intrinsic damping of one node [N s/m] (the least joint damping).
    aero
        [(coefficients (N,), damping [N s/m])] of rain-wind's modal tendons.
    damper_position
        the damper's asked position a [m] (the node it sits on is at damper_node dx).
    """

    cable: TautCable
    lumped: LumpedCable
    load: np.ndarray
    damper_node: int
    damper_coefficient: float
    background: float
    aero: tuple[tuple[np.ndarray, float], ...]
    damper_position: float

    @classmethod
    def of(cls, model: mujoco.MjModel) -> CableModel:
        """Read the cable back from a compiled stay-cable model."""
        n = model.nv
        mass = np.array([float(model.body_mass[model.jnt_bodyid[model.dof_jntid[i]]]) for i in range(n)])
        stiffness = np.zeros((n, n))
        for t, row in _tendon_rows(model, SEGMENT_PREFIX):
            stiffness += float(model.tendon_stiffness[t]) * np.outer(row, row)
        joint_damping = np.array(model.dof_damping, float)
        damping = np.diag(joint_damping)
        aero = []
        for t, row in _tendon_rows(model, AERO_PREFIX):
            weight = float(model.tendon_damping[t])
            damping += weight * np.outer(row, row)
            aero.append((row, weight))
        background = float(np.min(joint_damping))
        cable = cable_of(model)
        position = _numeric(model, "damper_position")
        node = cable.damper_node(n, position)
        actuator = model.actuator(WIND_ACTUATOR)
        load = float(actuator.gear[0]) * _tendon_row(model, int(actuator.trnid[0]))
        return cls(
            cable,
            LumpedCable(mass, stiffness, damping),
            load,
            node,
            float(joint_damping[node - 1]) - background,
            background,
            tuple(aero),
            position,
        )

    @property
    def size(self) -> int:
        """N, the moving nodes."""
        return self.lumped.size

    @property
    def positions(self) -> np.ndarray:
        """x_j = j dx [m] of the nodes, j = 1 ... N."""
        return self.cable.node_positions(self.size)

    @property
    def midspan(self) -> int:
        """The node (1 ... N) nearest mid-span, where mode 1 and the wind's RMS are largest."""
        return self.cable.damper_node(self.size, self.cable.length / 2.0)

    def without_damper(self) -> LumpedCable:
        """The same N-element model with the damper taken off (the cable as it was before the fix)."""
        return self.lumped.with_damper(self.damper_node, -self.damper_coefficient)

    def input_matrix(self) -> np.ndarray:
        """B (2N, 1) [m/s^2 per N/m]: how the wind's load enters the state (q, q')."""
        n = self.size
        b = np.zeros((2 * n, 1))
        b[n:, 0] = self.load / self.lumped.mass
        return b


def cable_model(case: CaseView) -> CableModel:
    """The case's cable, read back once (`Case.memo`)."""
    return case.memo("cable_model", lambda: CableModel.of(case.model))
