"""The command line a user expects: --version, options anywhere, early output checks, names that match."""

import json
import os
import pathlib

import pytest

import springlab
from helpers.paths import ROOT
from springlab import scenes
from springlab.cli.main import build_parser
from springlab.demo import steps as demo
from springlab.sim import model_files
from springlab.studies.design import study as design

#: a recorded signal shipped with the docs, for fit's argument parsing
EXAMPLE_CSV = ROOT / "docs" / "examples" / "decay_mm.csv"


def test_version_prints_the_package_version(cli):
    code, out, _ = cli("--version")
    assert code == 0 and out.strip() == f"springlab {springlab.__version__}"


def test_help_speaks_to_users_first():
    first = build_parser().format_help().split("\n\n")[1].splitlines()[0]
    assert "argparse" not in first and "library" not in first
    assert "vibration" in first and "exact solution" in build_parser().format_help()


def test_a_scenario_typed_after_the_options_is_the_scenario(cli):
    code, out, err = cli("run", "slider", "--set", "x0=0.05", "--duration", "0.5", "harmonic", "--json")
    assert code == 0, err
    summary = json.loads(out)
    assert summary["scenario"] == "harmonic" and summary["parameters"]["x0"] == 0.05


def test_an_extra_positional_is_still_refused_in_one_line(cli):
    code, _, err = cli("run", "slider", "free", "extra")
    assert code == 2 and "unrecognized arguments: extra" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "command, module, function",
    [
        (["tradeoff", "slider"], "springlab.studies.tradeoff", "tradeoff"),
        (["stability"], "springlab.studies.stability", "stability_report"),
        (["design", "printer_head"], "springlab.studies.design.study", "run_study"),
        (["sweep", "slider", "--vary", "mass=1:2:3"], "springlab.studies.sweeps", "sweep"),
        (["audit", str(model_files.path("slider"))], "springlab.cli.commands.audit", "run_audit"),
        (["fit", "slider", str(EXAMPLE_CSV)], "springlab.studies.fit.fit", "fit"),
    ],
)
def test_an_unwritable_output_fails_before_any_computing(tmp_path, cli, monkeypatch, command, module, function):
    import importlib

    def must_not_run(*args, **kwargs):
        raise AssertionError("computed before checking --output")

    monkeypatch.setattr(importlib.import_module(module), function, must_not_run)
    blocker = tmp_path / "file"
    blocker.write_text("a file, not a folder")
    code, out, err = cli(*command, "--output", str(blocker / "sub"))
    assert code == 2 and "cannot write into output directory" in err and out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file"]


def test_the_output_check_leaves_no_folder_behind(tmp_path):
    from springlab import files

    files.check_directory(tmp_path / "a" / "b")
    assert list(tmp_path.iterdir()) == []


def test_list_shows_each_scenarios_validated_dt(cli):
    code, out, _ = cli("list", "--json")
    assert code == 0
    catalogue = {entry["scene"]: entry for entry in json.loads(out)}
    for scene in scenes.SCENES.values():
        for scenario in scene.scenarios.values():
            setting = catalogue[scene.name]["scenario_settings"][scenario.name]
            # the dt `run` uses when none is given
            assert setting["dt"] == (scenario.dt or scene.dt)
    # the slider's undamped scenario validates at 2.5 ms, not the scene's 2 ms: the text says so too
    code, out, _ = cli("list")
    line = next(line for line in out.splitlines() if line.strip().startswith("undamped"))
    assert "2.5 ms" in line


def test_list_dt_is_the_dt_run_uses(cli):
    code, out, _ = cli("list", "--json")
    setting = {e["scene"]: e for e in json.loads(out)}["slider"]["scenario_settings"]["undamped"]
    assert springlab.run("slider", "undamped", duration=0.1).to_dict()["dt"] == setting["dt"]


def test_design_accepts_the_damping_ratio_its_table_shows():
    # zeta = c / (2 sqrt(k m_r)), m_r = m_c m_m / (m_c + m_m): the design table's definition, inverted
    base = design.base_parameters("printer_head", {"damping_ratio": 0.1})
    reduced = base["carriage_mass"] * base["motor_mass"] / (base["carriage_mass"] + base["motor_mass"])
    assert base["belt_damping"] == pytest.approx(2 * 0.1 * (base["belt_stiffness"] * reduced) ** 0.5, rel=1e-15)
    assert scenes.get("printer_head").design.hooks.defaults(base)["damping_ratio"] == pytest.approx(0.1, rel=1e-14)


def test_design_refuses_both_names_for_the_damping(cli):
    code, _, err = cli("design", "printer_head", "--set", "damping_ratio=0.1", "--set", "belt_damping=3")
    assert code == 2 and "damping_ratio or belt_damping" in err


def test_zeta_plot_of_a_two_mode_scene_says_it_needs_one_mode(tmp_path, cli):
    code, _, err = cli("plot", "car", "pitch_heave", "--kind", "zeta", "--output", str(tmp_path / "z.png"))
    assert code == 2 and "needs a one-mode scene" in err and "2 modes" in err
    assert "does not apply" not in err


@pytest.mark.parametrize("module", ["demo/steps", "cli/main"])
def test_importing_the_front_end_runs_nothing(module):
    # no side effects at import: only definitions at module level (demo appended its steps there)
    import ast

    source = pathlib.Path(springlab.__file__).parent / f"{module}.py"
    calls = [
        ast.unparse(node)
        for node in ast.parse(source.read_text()).body
        if isinstance(node, ast.Expr) and not isinstance(node.value, ast.Constant)
    ]
    assert calls == [], calls
    assert isinstance(demo.STEPS, tuple) and len({step.__name__ for step in demo.STEPS}) == len(demo.STEPS)


def test_the_rk4_limit_costs_a_vectorised_scan_not_thousands_of_calls(monkeypatch):
    # the stability chart's theory curve asks for 201 damping ratios per integrator; each rk4 limit was a
    # Python loop of up to 3000 scalar amplification calls + 60 bisection steps (605k calls, ~22 s)
    from springlab.exact import limits

    calls = []
    original = limits._rk4_amplification
    monkeypatch.setattr(limits, "_rk4_amplification", lambda z: calls.append(1) or original(z))
    for zeta in (0.0, 0.3, 1.0, 5.0, 100.0):
        limits.stability_limit("rk4", zeta)
    assert len(calls) <= 5 * (1 + 60)


def test_stability_output_writes_its_three_files(stability_command, cli, monkeypatch, stability_report):
    from springlab.studies import stability

    # what the command writes, not the study (tests/studies/test_stability.py): the session's run of
    # `springlab stability --json --output DIR` (tests/conftest.py: `stability_command`, from the session's
    # report); --output writes the same files with or without --json (cli/commands/stability.py), and drawing
    # the two charts again into a second folder cost 2 s of CPU
    printed, folder = stability_command
    assert printed.code == 0, printed.err
    assert sorted(p.name for p in folder.iterdir()) == ["energy.png", "stability.json", "stability.png"]
    # without --json the command answers in words, from the session's report too
    monkeypatch.setattr(stability, "stability_report", lambda **options: stability_report)
    code, out, err = cli("stability")
    assert code == 0 and out.strip(), err


def test_no_stray_files_in_the_working_directory(tmp_path, monkeypatch, cli):
    monkeypatch.chdir(tmp_path)
    cli("run", "slider", "--set", "damping=1e300")
    assert os.listdir(tmp_path) == [] and not pathlib.Path("MUJOCO_LOG.TXT").exists()


def test_starting_the_command_line_leaves_the_heavy_libraries_for_the_commands_that_draw_or_fit():
    # every command pays the front end's imports: matplotlib (~0.8 s) and scipy.stats/optimize (~0.5 s) load
    # only when a plot is drawn or a fit is reported, so a plain video starts rendering a second sooner
    import subprocess
    import sys

    probe = "import sys, springlab.cli.main; print(sorted(m for m in ('matplotlib', 'scipy.stats', 'scipy.optimize') if m in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == "[]"
