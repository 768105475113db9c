"""The drill string's outputs: its own figure, the note written on every frame, `springlab refine`'s files.

What is drawn is declared (the scene's `figure` panels, the model's `note:` texts) and read by the generic
plot and render code; these tests check that the declarations reach the outputs and that a scene without
them is refused with exit 2.
"""

from __future__ import annotations

import json

from springlab.cli.main import main
from springlab.render.drawings import drawn_notes
from springlab.runs.run import prepare, run_scenario
from springlab.scenes.drill_string.answers import RPM


def test_the_compressed_length_is_written_on_every_frame_as_the_model_declares():
    scene, chosen, params = prepare("drill_string", "modes", {"n_elements": 8, "length": 2000.0})
    notes = drawn_notes(scene.build(params, chosen))
    assert notes == ["length drawn 1:500 (2000 m as 4 m), diameter 3x"]


def test_the_breakaway_figure_marks_the_exact_breakaway_and_draws_the_three_bit_speeds():
    result = run_scenario("drill_string", "breakaway", duration=4.0, n_elements=8)
    speeds, twist = result.case.scene.figure(result.case, result.trajectory)
    labels = [curve.label for curve in speeds.curves]
    assert any("exact" in label for label in labels) and any("continuum" in label for label in labels)
    (mark, text), *_ = speeds.marks
    assert abs(mark - result.quantities["breakaway_time_s_exact"]) <= 1e-12 and "breakaway" in text
    # the top drive's curve is the ramp to 60 rpm, less what the string's torque (< 2e4 N m) takes from a
    # 1e12 kg m^2 flywheel in 4 s: 8e-8 rad/s; the twist panel runs from the top drive (0) to the bit
    top = speeds.curves[0]
    assert abs(top.y[-1] - result.parameters["top_speed_rpm"]) <= 2e4 * 4.0 / 1e12 / RPM
    assert all(curve.y[0] == 0.0 for curve in twist.curves)


def test_plot_kind_scene_writes_the_figure_and_a_scene_without_one_is_exit_2(tmp_path, capsys):
    assert (
        main(
            [
                "plot",
                "drill_string",
                "modes",
                "--kind",
                "scene",
                "--set",
                "n_elements=8",
                "--output",
                str(tmp_path / "m.png"),
            ]
        )
        == 0
    )
    assert (tmp_path / "m.png").stat().st_size > 10_000
    assert main(["plot", "slider", "--kind", "scene", "--output", str(tmp_path / "s.png")]) == 2
    err = capsys.readouterr().err
    assert "declares no figure" in err and err.count("\n") == 1 and not (tmp_path / "s.png").exists()


def test_refine_writes_its_json_and_chart(tmp_path, capsys):
    out = tmp_path / "refine"
    code = main(
        [
            "refine",
            "drill_string",
            "--sizes",
            "2,4",
            "--integrators",
            "rk4",
            "--tol",
            "1e-2",
            "--output",
            str(out),
            "--json",
        ]
    )
    assert code == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed == json.loads((out / "refine.json").read_text())
    assert printed["recommendation"]["verified"] is True and (out / "refine.png").stat().st_size > 10_000
