"""`springlab fit` on the command line: outputs and verdict, and bad input as one line with exit 2, nothing written."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest


def _decay_csv(path, header="time,slider_pos", n=1000):
    t = np.arange(n) * 2e-3
    omega, zeta = 20.0, 0.05
    wd = omega * math.sqrt(1 - zeta**2)
    x = 0.05 * np.exp(-zeta * omega * t) * (np.cos(wd * t) + zeta * omega / wd * np.sin(wd * t))
    path.write_text(header + "\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(t, x)))
    return path


def test_fit_writes_its_outputs_and_prints_the_verdict(tmp_path, cli):
    data = _decay_csv(tmp_path / "d.csv")
    code, out, err = cli("fit", "slider", data, "--set", "mass=2", "--output", tmp_path / "out")
    assert code == 0, err
    assert err == ""
    assert "ω_n = 20.0" in out and "underdamped" in out
    for name in ("fit.json", "fit.png", "trajectory.csv", "summary.json"):
        assert (tmp_path / "out" / name).stat().st_size > 0
    doc = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert doc["scene"] == "slider" and doc["samples"] == 1000
    assert abs(doc["estimates"]["omega_n"]["value"] / 20.0 - 1) < 1e-6


def test_fit_json_prints_fit_json(tmp_path, cli):
    data = _decay_csv(tmp_path / "d.csv", header="t,x")
    code, out, err = cli("fit", "slider", data, "--map", "t=time", "--map", "x=slider_pos", "--json")
    assert code == 0, err
    assert json.loads(out)["signal"] == "slider_pos"


@pytest.mark.parametrize(
    ("content", "extra", "message"),
    [
        (None, (), "cannot read"),
        ("1,2\n3,4\n", (), "no header"),
        ("time,slider_pos\n0,1\n1,2\n", (), "a fit needs at least"),
        ("time,slider_pos\n" + "".join(f"{5 - i},{i}\n" for i in range(20)), (), "time must increase"),
        ("time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)), ("--map", "q=slider_pos"), "lacks"),
        ("time,speed\n" + "".join(f"{i},{i}\n" for i in range(20)), (), "no signal column"),
        ("time,slider_pos\n" + "".join(f"{i},x{i}\n" for i in range(20)), (), "not a number"),
        (
            "time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)),
            ("--free", "mass,stiffness,damping"),
            "cannot all",
        ),
        ("time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)), ("--scale", "0"), "--scale"),
        ("time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)), ("--starts", "0"), "--starts"),
        ("time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)), ("--starts", "two"), "--starts"),
        ("time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)), ("--starts", "1.5"), "--starts"),
        (
            "time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)),
            ("--free", "x0,v0", "--starts", "3"),
            "linearly",
        ),
        (
            "time,slider_pos\n" + "".join(f"{i},{i}\n" for i in range(20)),
            ("--starts", "3", "--workers", "0"),
            "workers",
        ),
    ],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(tmp_path, cli, content, extra, message):
    data = tmp_path / "d.csv"
    if content is not None:
        data.write_text(content)
    code, out, err = cli("fit", "slider", data, "--output", tmp_path / "out", *extra)
    assert code == 2
    assert err.count("\n") == 1 and message in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_unknown_scene_and_scenario_are_bad_input(tmp_path, cli):
    data = _decay_csv(tmp_path / "d.csv")
    code, _, err = cli("fit", "nonlinear", data)
    assert code == 2 and "cannot be fitted" in err
    code, _, err = cli("fit", "slider", data, "--scenario", "harmonic")
    assert code == 2 and "a fit takes one of" in err
