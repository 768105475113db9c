"""The fit's result as an object, and the scene's declaration as all the fit study reads.

`FitResult` is built once and frozen; `to_dict()` is exactly what `springlab fit --json` prints and what
fit.json holds; `to_pandas()` has one row per estimate. What can be fitted is declared by each scene
(`Scene.fit`, springlab.scenes.capabilities): the command line lists those scenes, and changing a
declaration changes what the study does, with no other edit. Records are written from their own closed
forms here (not springlab.analytic, not MuJoCo).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import re

import numpy as np
import pytest

from springlab import scenes
from springlab.cli.main import build_parser
from springlab.errors import BadInputError
from springlab.scenes.capabilities.fit import OscillatorFit, PolynomialFit
from springlab.studies.fit import fit as fit_module
from springlab.studies.fit.models import fittable

OMEGA, ZETA, X0 = 20.0, 0.05, 0.05


def _decay(path, n=600, dt=2e-3):
    """x(t) = X0 e^(-zeta w t) (cos wd t + zeta w / wd sin wd t) [m] with 1 mm of noise: released from rest at X0."""
    t = np.arange(n) * dt
    wd = OMEGA * math.sqrt(1 - ZETA**2)
    x = X0 * np.exp(-ZETA * OMEGA * t) * (np.cos(wd * t) + ZETA * OMEGA / wd * np.sin(wd * t))
    x = x + 1e-3 * np.random.default_rng(4).standard_normal(n)
    path.write_text("time,slider_pos\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(t, x)))
    return path


def _polynomial(path):
    """x(t) = 3 + 1.2 t + 0.2 t^2 + 0.03 t^3 [m] (section 5.2) with 5 cm of noise."""
    t = np.linspace(0, 10, 101)
    x = 3.0 + 1.2 * t + 0.2 * t**2 + 0.03 * t**3 + np.random.default_rng(5).normal(0, 0.05, t.size)
    path.write_text("time,vehicle_pos\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(t, x)))
    return path


def _cli_fit(monkeypatch, cli, *argv):
    """Run `springlab fit ARGV`; return (exit code, stdout, stderr, the FitResult the command printed)."""
    made = []
    original = fit_module.fit

    def keep(*args, **kwargs):
        made.append(original(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(fit_module, "fit", keep)
    code, out, err = cli("fit", *argv)
    return code, out, err, made[-1] if made else None


@pytest.fixture(scope="module")
def slider_fit(tmp_path_factory):
    """One fit of the noisy slider decay (mass given), shared by the tests that only read it."""
    return fit_module.fit("slider", _decay(tmp_path_factory.mktemp("fit") / "d.csv"), mass=2.0, run_scene=False)


# -- FitResult as an object -------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["oscillator", "polynomial"])
def test_to_dict_is_what_fit_json_prints_and_fit_json_holds(tmp_path, monkeypatch, cli, kind):
    if kind == "oscillator":
        argv = ["slider", _decay(tmp_path / "d.csv"), "--set", "mass=2"]
    else:
        argv = ["kinematics", _polynomial(tmp_path / "d.csv")]
    code, out, err, result = _cli_fit(monkeypatch, cli, *argv, "--json", "--output", tmp_path / "out")
    assert code == 0 and err == ""
    assert result.kind == kind
    printed = json.loads(out)
    assert printed == result.to_dict()
    assert json.loads((tmp_path / "out" / "fit.json").read_text()) == printed
    # the keys docs/fit.md promises, in its order
    assert list(printed)[:9] == [
        *("question", "answer", "answer_numbers"),
        *("scene", "scenario", "signal", "signal_unit", "column", "free"),
    ]
    assert printed["verdict"] == result.verdict and printed["converged"] is result.converged


def test_facts_are_attributes_scipy_style(slider_fit):
    result = slider_fit
    assert result.success is result.converged is True
    assert result.message == result.optimizer["status"] in ("norm(dx) < tol", "norm(gradient) < tol")
    assert result.free == ("omega_n", "zeta", "x0", "v0", "offset")  # the slider's declared default
    low, high = result.estimates["omega_n"]["ci95"]
    assert low < OMEGA < high
    assert result.residual_rms == pytest.approx(1e-3, rel=0.15)  # the noise written into the record
    assert result.verdict.startswith("ω_n = ") and "underdamped" in result.verdict


def test_to_pandas_has_one_row_per_estimate(slider_fit):
    result = slider_fit
    frame = result.to_pandas()
    assert list(frame.columns) == ["name", "value", "ci95_low", "ci95_high", "unit"]
    assert list(frame["name"]) == list(result.free) == list(result.estimates)
    for row in frame.itertuples(index=False):
        q = result.estimates[row.name]
        assert (row.value, row.ci95_low, row.ci95_high, row.unit) == (q["value"], *q["ci95"], q["unit"])


def test_the_result_and_its_record_are_frozen(slider_fit):
    result = slider_fit
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.converged = False  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.record.notes = ()  # type: ignore[misc]
    with pytest.raises(AttributeError):
        result.verdict = "anything"  # type: ignore[misc]
    for array in (result.fitted, result.covariance, result.correlation, result.record.time, result.record.values):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 0.0
    assert isinstance(result.free, tuple) and isinstance(result.record.notes, tuple)


# -- the scene's declaration is all the study reads ---------------------------------------------


def _fit_subparser() -> argparse.ArgumentParser:
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return commands.choices["fit"]


def test_the_cli_lists_the_scenes_that_declare_a_fit(tmp_path, cli):
    declared = {name for name, scene in scenes.SCENES.items() if scene.fit}
    assert declared and declared != set(scenes.SCENES)  # some scenes can be fitted and some cannot
    assert set(fittable()) == declared
    scene_help = next(a.help for a in _fit_subparser()._actions if a.dest == "scene")
    assert set(re.split(r", | or ", scene_help)) == declared
    unfit = next(name for name, scene in scenes.SCENES.items() if scene.fit is None)
    code, _, err = cli("fit", unfit, str(_decay(tmp_path / "d.csv")))
    listed = re.search(r"valid: (.*) \(", err)
    assert code == 2 and listed is not None and set(listed.group(1).split(", ")) == declared


def test_every_declaration_names_its_scenes_own_joint_scenarios_and_parameters():
    for name, scene in scenes.SCENES.items():
        declared = scene.fit
        if declared is None:
            continue
        assert declared.joint in scene.joints, name
        assert set(declared.scenarios) <= set(scene.scenarios), name
        if isinstance(declared, OscillatorFit):
            named = [n for n in (declared.mass, declared.stiffness, declared.damping, declared.rest) if n]
            named += list(declared.step_forces.values())
            assert set(declared.step_forces) <= set(declared.scenarios), name
        else:
            assert isinstance(declared, PolynomialFit)
            named = list(declared.coefficients)
        assert set(named) <= set(scene.parameters), name


def test_withdrawing_a_declaration_withdraws_the_fit_everywhere(tmp_path, monkeypatch):
    car = scenes.get("car")
    monkeypatch.setattr(car, "fit", None)
    assert "car" not in fittable()
    assert "car" not in next(a.help for a in _fit_subparser()._actions if a.dest == "scene")
    with pytest.raises(BadInputError, match="scene 'car' cannot be fitted"):
        fit_module.fit("car", _decay(tmp_path / "d.csv"))


def test_the_study_follows_a_changed_declaration(tmp_path, monkeypatch):
    # the slider declared to be fitted from its 'free' scenario only, in physical form by default
    slider = scenes.get("slider")
    declared = dataclasses.replace(
        slider.fit, scenarios=("free",), default_free=("stiffness", "damping", "x0", "v0", "offset")
    )
    monkeypatch.setattr(slider, "fit", declared)
    data = _decay(tmp_path / "d.csv")
    result = fit_module.fit("slider", data, mass=2.0, run_scene=False)
    assert result.free == declared.default_free
    assert result.derived["omega_n_rad_s"]["ci95"][0] < OMEGA < result.derived["omega_n_rad_s"]["ci95"][1]
    with pytest.raises(BadInputError, match="a fit takes one of: free$"):
        fit_module.fit("slider", data, "step", mass=2.0, run_scene=False)


def test_a_declaration_is_checked_when_made():
    with pytest.raises(ValueError, match="mode_mass"):
        OscillatorFit("slider", ("free",), mass=None)
    with pytest.raises(ValueError, match="x0, v0"):
        PolynomialFit("vehicle", ("polynomial_position",), ("a0", "jerk"))
