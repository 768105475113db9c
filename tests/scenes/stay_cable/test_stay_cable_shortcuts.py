"""The stay cable's shortcuts are the long way's answers.

* A case compiled from the model without its cable (`StayCable.editable_spec`, kept per process) is the model the
  shipped file gives once its cable is generated over it: byte for byte (mj_saveModel), at the defaults and at
  another N with rain-wind's modal tendons.
* The modal filter taken FILTER_ROWS rows at a time is the product of the whole record with the left eigenvector,
  within the round-off bound of a dot product (either summation order: 2n eps sum |x_j| |w_j|).
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from springlab.scenes import get
from springlab.scenes.stay_cable import build, modal

SCENE = get("stay_cable")
EPS = float(np.finfo(float).eps)


def _saved(model: mujoco.MjModel) -> np.ndarray:
    out = np.zeros(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, out)
    return out


@pytest.mark.parametrize(
    "scenario, overrides",
    [("damper", {}), ("rain_wind", {"n_elements": 9.0, "aero_modes": 2.0}), ("wind", {"n_elements": 30.0})],
)
def test_a_case_compiled_without_the_shipped_cable_is_the_shipped_models_byte_for_byte(scenario, overrides):
    chosen = SCENE.scenarios[scenario]
    params = SCENE.resolve(chosen, overrides)
    spec = SCENE.model_spec()  # the shipped file, its 99-node cable in it
    build.generate(spec, params)  # removes that cable, writes this one
    assert np.array_equal(_saved(SCENE.build(params, chosen)), _saved(spec.compile()))


def test_the_modal_filter_in_blocks_is_the_whole_records_product():
    rng = np.random.default_rng(7)
    rows, n = 2 * modal.FILTER_ROWS + 123, 11  # two whole blocks and a part
    qpos, qvel = rng.standard_normal((rows, n)), rng.standard_normal((rows, n))
    weights = rng.standard_normal(2 * n) + 1j * rng.standard_normal(2 * n)
    whole = np.concatenate([qpos, qvel], axis=1) @ weights
    blocks = modal._modal_filter(weights, qpos, qvel)
    bound = 2 * (2 * n) * EPS * (np.abs(np.concatenate([qpos, qvel], axis=1)) @ np.abs(weights))
    assert np.all(np.abs(blocks - whole) <= 2 * bound)  # each within its bound of the exact sum
