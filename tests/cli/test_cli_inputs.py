"""Inputs at the edges get one clean answer: MuJoCo's own limits on masses and on values, no warning text."""

import re
import subprocess
import sys
import warnings

import mujoco
import pytest

import springlab
from springlab import scenes
from springlab.errors import DivergedError, ParameterError, SpringlabError
from springlab.runs.run import prepare

MASS_UNITS = ("kg", "kg m^2")


def _mass_like():
    """(scene, scenario, parameter) for every mass or inertia parameter of every scenario it applies to."""
    cases = []
    for scene in scenes.SCENES.values():
        for name, parameter in scene.parameters.items():
            if parameter.unit not in MASS_UNITS or name == "push_mass":  # push_mass is a load, not a body
                continue
            for scenario in scene.scenarios:
                cases.append((scene.name, scenario, name))
    return cases


def _build(scene_name, scenario, overrides):
    scene, chosen, params = prepare(scene_name, scenario, overrides)
    return scene.build(params, chosen)


@pytest.mark.parametrize("scene_name, scenario, name", _mass_like())
def test_a_mass_below_mujocos_minimum_is_a_parameter_error_naming_its_range(scene_name, scenario, name):
    with pytest.raises(SpringlabError) as caught:
        _build(scene_name, scenario, {name: 1e-30})
    message = str(caught.value)
    assert isinstance(caught.value, ParameterError), message
    if "does not apply" in message:
        return
    floor = scenes.get(scene_name).parameters[name]
    if floor.minimum is not None and floor.minimum > mujoco.mjMINVAL:
        # a scene's own floor above MuJoCo's (the drill string's BHA: the exact solution's time constant J_b / Z):
        # the message names the range and says why
        assert message.startswith(f"{name} must be") and floor.reason in message and "\n" not in message
        return
    assert message.startswith(f"{name} must be") and "mjMINVAL" in message and "\n" not in message
    # the stated bound is MuJoCo's: compile accepts it, half of it is refused by springlab, not by MuJoCo
    # (a scenario may then state a tighter one of its own, e.g. road_bump's mass/4 per corner: follow it)
    for _ in range(3):
        bound = float(re.search(r">= ([0-9.e+-]+)", message).group(1))
        assert bound >= mujoco.mjMINVAL
        with pytest.raises(ParameterError):
            _build(scene_name, scenario, {name: bound * 0.5})
        try:
            _build(scene_name, scenario, {name: bound * (1 + 1e-12)})
            return
        except ParameterError as other:
            message = str(other)
            if message.startswith(f"{name} must be") and "mjMINVAL" in message:
                continue  # a tighter bound of this scenario
            # another physical limit (a car rebounding off its springs) may bite first: not MuJoCo's compile
            assert "cannot compile" not in message
            return
    pytest.fail(f"no bound of {name} compiles: {message}")


def test_pitch_inertia_outside_the_mjcf_triangle_runs_as_the_two_dof_reference_says():
    # 1000 kg m^2 violated MuJoCo's A + B >= C with the MJCF's roll/yaw inertias (400, 1650): a crash before
    result = springlab.run("car", "pitch_heave", pitch_inertia=1000.0, duration=1.0)
    assert result.to_dict()["passed"] is True


def _cli(*argv):
    return subprocess.run(
        [sys.executable, "-m", "springlab", *argv], capture_output=True, text=True, timeout=120, check=False
    )


@pytest.mark.parametrize(
    "argv, name",
    [
        (("run", "slider", "--set", "mass=1e-30"), "mass"),
        (("run", "printer_head", "--set", "carriage_mass=1e-20"), "carriage_mass"),
        (("run", "car", "pitch_heave", "--set", "pitch_inertia=1e-20"), "pitch_inertia"),
        (("run", "nonlinear", "--set", "mass=1e-20"), "mass"),
        (("run", "kinematics", "--set", "mass=1e-20"), "mass"),
    ],
)
def test_the_cli_says_which_mass_and_its_range_in_one_line_exit_2(cli, argv, name):
    # every scene's refusal through the command's one error path, in this process; the first also in a process
    # of its own (the interpreter's warnings would be lines on its stderr)
    done = cli(*argv)
    assert done.code == 2, done.err
    lines = done.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"springlab: error: {name} must be a finite number >=")
    if argv[1] == "slider":
        proc = _cli(*argv)
        assert proc.returncode == 2 and proc.stderr.strip().splitlines() == lines, proc.stderr


def test_a_state_beyond_mujocos_value_cap_says_no_timestep_helps():
    # |x0| = 1e300 m is past mjMAXVAL = 1e10: MuJoCo resets it at any dt, with any integrator
    with pytest.raises(DivergedError) as caught:
        springlab.run("slider", "free", x0=1e300)
    message = str(caught.value)
    assert "no timestep or integrator" in message and "mjMAXVAL" in message
    assert "use dt" not in message and "within" not in message


def test_an_acceleration_beyond_the_cap_is_caught_at_t0():
    # k x0 / m = 100 * 1e9 = 1e11 m/s^2 > 1e10 at t = 0
    with pytest.raises(DivergedError, match="initial acceleration of -1e\\+11.*no timestep"):
        springlab.run("slider", "free", x0=1e9)


def test_advice_for_a_real_instability_names_a_dt_below_the_limit():
    # omega*dt = 10 * 0.5 = 5 > rk4's 2.9: dt < 0.29 s is advised and does run
    with pytest.raises(DivergedError) as caught:
        springlab.run("slider", "free", dt=0.5)
    advised = float(re.search(r"use dt < ([0-9.e+-]+) s", str(caught.value)).group(1))
    assert "exceeds" in str(caught.value)
    springlab.run("slider", "free", dt=advised * 0.99)


def test_huge_damping_gives_no_warning_and_no_unreachable_dt():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(DivergedError) as caught:
            springlab.run("slider", "free", damping=1e300)
    message = str(caught.value)
    # rk4's limit is 2.785/(2 zeta) ~ 3e-300: not a dt anyone can run in 2e7 steps
    assert "more than" in message and "implicit" in message


def test_huge_damping_on_the_terminal_is_one_line():
    proc = _cli("run", "slider", "--set", "damping=1e300")
    assert proc.returncode == 3
    assert len(proc.stderr.strip().splitlines()) == 1 and "Warning" not in proc.stderr


def test_an_exact_solution_that_overflows_is_bad_input_not_a_divergence():
    # implicit treats the damper implicitly and runs; the closed form overflows at zeta = 5e298
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ParameterError, match="not finite in double precision"):
            springlab.run("slider", "free", damping=1e300, integrator="implicit")


def test_a_divergence_within_the_stability_limit_never_advises_a_smaller_dt():
    # a 1e15 N harmonic force starts at sin(0) = 0, then drives the acceleration past 1e10 within steps;
    # omega*dt = 0.025 is far inside rk4's 2.83: shrinking dt cannot help, and the advice must not say it does
    with pytest.raises(DivergedError) as caught:
        springlab.run("slider", "harmonic", force_amplitude=1e15)
    message = str(caught.value)
    assert "is within the rk4 stability limit" in message and "not the timestep instability" in message
    assert "use dt" not in message


@pytest.mark.parametrize(
    "argv",
    [
        ("run", "printer_head", "--set", "belt_damping=1e300"),
        ("run", "car", "pitch_heave", "--set", "front_damping=1e300"),
        ("run", "slider", "--set", "mass=1e300"),
        ("run", "car", "road_bump", "--set", "speed=1e300"),
        ("run", "slider", "harmonic", "--set", "force_frequency=1e300"),
        ("run", "car", "road_bump", "--set", "bump_length=1e-300"),
        ("run", "kinematics", "--set", "jerk=1e300"),
        ("run", "nonlinear", "--set", "x0=1e300"),
    ],
)
def test_values_at_the_edge_of_double_precision_get_one_line_and_no_warning(argv, cli):
    # each value is inside its stated range; their products leave double precision or MuJoCo's caps
    code, _, err = cli(*argv)
    assert code in (2, 3), err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err and "Warning" not in err
    assert any(why in err for why in ("double precision", "mjMAXVAL", "stability limit"))
