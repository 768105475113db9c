"""Every shipped model compiles and steps with zero MuJoCo warnings, and is lean."""

import mujoco
import numpy as np
import pytest

from springlab import scenes
from springlab.sim import model_files
from springlab.sim.simulate import quiet_mujoco

MODEL_FILES = sorted(model_files.directory().glob("*.xml"))


def test_every_scene_has_its_model_and_every_model_its_scene():
    assert {p.stem for p in MODEL_FILES} == set(scenes.SCENES)


@pytest.mark.parametrize("path", MODEL_FILES, ids=lambda p: p.stem)
def test_model_compiles_and_steps_without_warnings(path):
    with quiet_mujoco() as messages:
        model = mujoco.MjModel.from_xml_path(str(path))
        data = mujoco.MjData(model)
        for _ in range(1000):
            mujoco.mj_step(model, data)
    assert messages == []
    assert all(w.number == 0 for w in data.warning)
    assert np.isfinite(data.qpos).all()


@pytest.mark.parametrize("name", sorted(scenes.SCENES))
def test_every_scenario_model_compiles_without_warnings(name):
    scene = scenes.get(name)
    for scenario in scene.scenarios.values():
        params = scene.resolve(scenario, {})
        with quiet_mujoco() as messages:
            model = scene.build(params, scenario)
        assert messages == [], scenario.name
        assert model.nv >= 1


def test_slider_has_nothing_the_textbook_does_not():
    model = mujoco.MjModel.from_xml_path(str(model_files.path("slider")))
    assert np.all(model.opt.gravity == 0)
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert model.dof_armature[0] == 0 and model.dof_frictionloss[0] == 0
    assert model.ntendon == 0  # the drawn spring is a render-time picture, not a tendon computed every step
    assert model.camera("side").id >= 0
