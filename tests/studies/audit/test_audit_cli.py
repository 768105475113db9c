"""`springlab audit` on the command line: outputs, exit codes, one-line errors and nothing partial on bad input."""

from __future__ import annotations

import json

import pytest

from helpers.linear_models import chain_xml, pendulum_xml
from springlab.cli.main import main


def test_audit_writes_json_and_png_and_says_the_verdict(tmp_path, capsys, untimed):
    model = tmp_path / "chain.xml"
    model.write_text(chain_xml(2, 100.0, 1.0, 0.2).replace('gravity="0 0 0"', 'gravity="0 0 0" integrator="RK4"'))
    out = tmp_path / "out"
    code = main(["audit", str(model), "--output", str(out), "--integrators", "euler,rk4"])
    lines = capsys.readouterr().out.splitlines()
    assert code == 0  # rk4 at MuJoCo's default 2 ms: stable, error ~1e-8 (omega dt = 0.03, 4th order)
    data = json.loads((out / "audit.json").read_text())
    for key in ("model", "operating_point", "linear", "modes", "stability", "own_setting", "sweep", "recommendation"):
        assert key in data
    assert set(data["stability"]["rk4"]) >= {"limit_dt_predicted_s", "limit_dt_measured_s", "confirmed", "margin"}
    assert data["recommendation"]["verified"] is True
    assert (out / "audit.png").stat().st_size > 0
    assert any(line.startswith("your setting, rk4 at 2 ms, is stable with margin") for line in lines)
    assert sorted(p.name for p in out.iterdir()) == ["audit.json", "audit.png"]


def test_a_setting_that_misses_tol_is_a_finding_exit_1_with_outputs(tmp_path, capsys, untimed):
    model = tmp_path / "chain.xml"
    model.write_text(chain_xml(2, 100.0, 1.0, 0.2))
    out = tmp_path / "out"
    # euler at 2 ms is first order: its error over 1 s is ~1e-2, far above 1e-9
    assert main(["audit", str(model), "--tol", "1e-9", "--integrators", "euler", "--output", str(out)]) == 1
    assert (out / "audit.json").exists() and (out / "audit.png").exists()
    assert "misses tol" in capsys.readouterr().out


@pytest.mark.slow  # 4-5 s: a second full slider audit, by the command (the quick loop runs the command above)
def test_the_same_audit_command_twice_gives_the_same_recommendation_and_front(tmp_path, capsys, shipped_audit):
    # a real audit, real timers: in the slider's sweep euler, implicit and implicitfast are equal in error
    # and in counted work at every dt, so only their measured times told them apart when the front read them.
    # The first of the two runs is the session's `audit("slider", tol=1e-3)` (tests/conftest.py), which is
    # what `springlab audit slider` runs (its default tol); the second is the command, with its own timers
    first = shipped_audit("slider")
    out = tmp_path / "second"
    assert main(["audit", "slider", "--output", str(out)]) == 0
    data = json.loads((out / "audit.json").read_text())
    words = capsys.readouterr().out.splitlines()
    picks = []
    for found, lines in ((first.to_dict(), first.message.splitlines()), (data, words)):
        picks.append(
            (
                {k: v for k, v in found["recommendation"].items() if k != "wall_time_s"},
                [(r["integrator"], r["dt"], r["cost"]) for r in found["pareto"]],
                [line for line in lines if line.startswith("cheapest meeting tol")],  # the pick in words
            )
        )
    assert picks[0][0]["verified"] and picks[0][1] and len(picks[0][2]) == 1
    assert picks[0] == picks[1]


@pytest.mark.parametrize(
    "args, message",
    [
        (["missing.xml"], "no such model file or scene 'missing.xml'"),
        (["BROKEN"], "cannot load"),
        (["PENDULUM", "--keyframe", "side"], "unknown keyframe 'side'"),
        (["PENDULUM", "--integrators", "rk5"], "unknown integrator 'rk5'"),
        (["PENDULUM", "--tol", "0"], "tol must be"),
        (["PENDULUM", "--dt", "fast"], "--dt must be"),
        (["PENDULUM", "--dt", "1e-2:1e-3:4"], "--dt must be seconds 'a,b,c' or a range 'LOW:HIGH:N'"),
        (["PENDULUM", "--dt", "0.01,0"], "every dt must be a finite number > 0 s, got '0.01,0'"),
        (["PENDULUM", "--integrators", ","], "--integrators needs at least one of euler"),
        (["PENDULUM", "--duration", "-1"], "duration must be"),
        (["PENDULUM", "--perturb", "nan"], "perturb must be"),
        (["PENDULUM", "--tol", "2"], "tol must be a relative error in (0, 1)"),
        (["PENDULUM", "--tol", "1"], "tol must be a relative error in (0, 1)"),
        (["PENDULUM", "--perturb", "1e9"], "--perturb 1e+09 rad turns a joint by half a revolution"),
        (["LIMITED", "--perturb", "0.5"], "at least half the range of joint 'swing'"),
        (["PENDULUM", "--settle", "-1"], "settle must be"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, cli, args, message):
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body><joint type='hinge'/></body></worldbody>")
    pendulum = tmp_path / "pendulum.xml"
    pendulum.write_text(pendulum_xml())
    limited = tmp_path / "limited.xml"  # the pendulum with a range of 40 degrees (0.70 rad: half is 0.35)
    limited.write_text(pendulum_xml().replace('axis="0 1 0"', 'axis="0 1 0" range="-20 20"'))
    paths = {"BROKEN": str(broken), "PENDULUM": str(pendulum), "LIMITED": str(limited)}
    out = tmp_path / "out"
    code, _, err = cli("audit", *[paths.get(a, a) for a in args], "--output", str(out))
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_the_demo_report_gains_an_audit_section(tmp_path, monkeypatch, shipped_audit):
    import importlib

    from springlab.demo import report
    from springlab.demo import steps as demo

    # the step audits the car as `springlab audit car` does (default tol 1e-3): the session's car audit, once
    def shared(model, **options):
        assert not options, options  # the fixture's audit is the default one
        return shipped_audit(model)

    monkeypatch.setattr(importlib.import_module("springlab.studies.audit.audit"), "audit", shared)
    state = demo.DemoState(out=tmp_path)
    state.artifacts.extend(demo.audit_step(state))
    page = report.write_report(state).read_text()
    assert sorted(p.name for p in (tmp_path / "audit").iterdir()) == ["audit.json", "audit.png"]
    assert "audit/audit.png" in page and json.loads((tmp_path / "audit" / "audit.json").read_text())["model"]
