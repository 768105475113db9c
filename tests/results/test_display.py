"""Results show themselves in a notebook, and the CSVs springlab writes read back exactly (issue 24, items 1
and 5).

Every result class (a subclass of springlab.display.Shown) is built once from a cheap real run (the shipped
scenes at short durations, small grids; the stability report and the slider's audit are the suite's shared
session fixtures) and checked for: a short plain repr that leads with its verdict; an HTML summary that a
real browser (Debian's chromium, headless, as tests/demo/test_report.py drives it) renders without an error, all
of them on one page with an inline video; a `.plot()` that draws the result's own arrays.

The CSV writers are read back with `float()` cell by cell and compared bit for bit with the values in
memory, and no cell is longer than Python's shortest round-trip repr of its value.

The tests that read `results` are marked slow: building it takes ~5 s of CPU beyond the shared fixtures.
"""

from __future__ import annotations

import csv
import html
import io
import math
import re
import struct
import subprocess
import sys

import numpy as np
import pytest

import springlab
from helpers.browser import browse_until, find_chromium
from helpers.figures import assert_legends_clear
from helpers.layers import layer_of
from helpers.paths import DATA
from helpers.stay_cable import WINDY
from helpers.timing import constant_time_run
from springlab import display, files, outputs
from springlab.plots import figures
from springlab.runs.run import ValidationRow, run_scenario
from springlab.scenes import get
from springlab.studies import random_load, rms_settings
from springlab.studies import tradeoff as tradeoff_module
from springlab.studies.design import run_study
from springlab.studies.families import run_phase_family, run_zeta_family
from springlab.studies.friction_settings import friction_settings
from springlab.studies.model_sweep import model_sweep
from springlab.studies.model_tradeoff import model_tradeoff
from springlab.studies.refine import refine
from springlab.studies.tradeoff import tradeoff

#: a model file nobody wrote a scene for (tests/data/pinch_gripper.xml): its run, sweep and trade-off
PINCH = DATA / "pinch_gripper.xml"

#: lines of a plain repr at most: the verdict, its reason, the figures
REPR_LINES = 3


def _shown_classes() -> set[type]:
    found, todo = set(), [display.Shown]
    while todo:
        for sub in todo.pop().__subclasses__():
            found.add(sub)
            todo.append(sub)
    return found


def _untimed(study, *args, **options):
    """`study(*args, **options)` with no run timed again alone (helpers/timing.py): nothing here reads a wall
    time (the pick and the front rank counted work), and the timing runs were half of a small trade-off."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(tradeoff_module, "time_run", constant_time_run)
        return study(*args, **options)


@pytest.fixture(scope="module")
def results(stability_report, shipped_audit):
    """One result of every class that shows itself, by class name, each from a cheap real run."""
    result = run_scenario("slider", "free", duration=1.0)
    t = np.arange(0.0, 1.0, 0.01)
    decay = 0.05 * np.exp(-0.5 * t) * np.cos(20.0 * t)  # a damped oscillation [m]: what fit reads
    study = run_study("printer_head", levels=3, plane_levels=0, sobol=4)
    ends = {s.name: (s.mujoco_default, s.values[-1]) for s in get("friction").dry_friction.settings}
    built = {
        "Result": result,
        "ValidationRow": ValidationRow.of(result),
        "Sweep": springlab.sweep("slider", "free", vary={"damping": (0.5, 40.0, 14, "log")}, duration=0.5),
        "Tradeoff": _untimed(tradeoff, "slider", "free", tol=1e-6, duration=0.5),
        "FitResult": springlab.fit("slider", {"time": t, "slider_pos": decay}, mass=2.0),
        "Audit": shipped_audit("slider"),
        "StabilityReport": stability_report,
        "FrequencyResponse": springlab.frequency("slider", points=40),  # a fifth of the default 200 frequencies
        "Study": study,
        "SobolStudy": study.sobol,
        "FrictionSettings": friction_settings(
            "friction", ["incline_hold"], tol=1e-2, integrators=("euler",), dts=(2e-3, 1e-3), values=ends
        ),
        "Refinement": refine("drill_string", tol=1e-2, sizes=(2, 4), integrators=("rk4",), omega_dt=(0.5, 1.0)),
        "ZetaFamily": run_zeta_family("slider", "free", zetas=(0.0, 0.5), duration=1.0),
        "PhaseFamily": run_phase_family(result),
        "Ensemble": random_load.ensemble(
            "stay_cable", seeds=2, record=20.0, **WINDY
        ),  # the stay cable tests' nine-node cable,
        "ModelRun": springlab.run(str(PINCH), keyframe="open", duration=0.2),
        "RmsSettings": rms_settings.rms_settings(
            "stay_cable", tol=0.5, integrators=("implicitfast",), seed_counts=(1,), record=20.0, sizes=(9,)
        ),
        # a model file's sweep and trade-off (tests/data/pinch_gripper.xml: the box falls freely from 'open')
        "ModelSweep": model_sweep(PINCH, keyframe="open", vary={"opt.timestep": (0.001, 0.004, 4)}, duration=0.2),
        "ModelTradeoff": model_tradeoff(PINCH, keyframe="open", duration=0.2, integrators=["euler", "rk4"]),
    }
    assert {type(r).__name__ for r in built.values()} == set(built)
    return built


@pytest.fixture(scope="module")
def drawn(results):
    """`.plot()` of every result that has one, by class name: each figure drawn once for the tests below."""
    return {name: result.plot() for name, result in results.items() if hasattr(result, "plot")}


def _verdict(result) -> str:
    return result._shown().verdict


# -- the classes ------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_every_top_level_result_shows_itself_and_this_test_builds_each(results):
    shown = {cls.__name__ for cls in _shown_classes()}
    returned = {"Result", "ValidationRow", "Sweep", "Tradeoff", "FitResult", "Audit", "StabilityReport"}
    returned |= {"FrequencyResponse", "Study", "SobolStudy", "FrictionSettings", "Refinement"}
    returned |= {"ZetaFamily", "PhaseFamily", "Ensemble", "RmsSettings", "ModelRun"}
    returned |= {"ModelSweep", "ModelTradeoff"}
    assert returned <= shown, "a result the public functions return has no display"
    assert shown == set(results), "a new Shown class joins the `results` fixture"


def test_the_plotting_backend_is_in_the_plots_layer_and_draws_every_result_with_plot():
    """`.plot()` reaches upward only through display.PLOTTING (imported when called): that module is in the
    plots layer and knows every result class that has `plot`."""
    assert display.PLOTTING.startswith("springlab.")
    assert layer_of(display.PLOTTING.removeprefix("springlab.")) == "plots"
    with_plot = {cls for cls in _shown_classes() if hasattr(cls, "plot")}
    assert with_plot == set(figures.DRAWERS)


def test_importing_the_results_imports_neither_matplotlib_nor_the_plots():
    code = (
        "import sys, springlab, springlab.studies.sweeps, springlab.studies.stability\n"
        "print(sorted(m for m in sys.modules if m.startswith(('matplotlib', 'springlab.plots'))))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


# -- repr -----------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_the_plain_repr_is_a_few_lines_that_lead_with_the_verdict(results):
    for name, result in results.items():
        text = repr(result)
        lines = text.splitlines()
        assert 1 <= len(lines) <= REPR_LINES, f"{name}: {len(lines)} lines"
        assert lines[0].startswith(f"<{name} ") and lines[0].endswith(f": {_verdict(result)}>"), lines[0]
    run = results["Result"]
    assert repr(run).splitlines()[0] == "<Result slider / free: PASS>"
    assert f"max relative error {run.max_rel_error:.4g}" in repr(run)
    assert repr(results["Sweep"]).splitlines()[0] == "<Sweep slider / free: 14 of 14 passed>"


def test_a_summary_escapes_every_string():
    hostile = "<script>alert(1)</script> & 'x'"
    summary = display.Summary(
        hostile,
        hostile,
        hostile,
        None,
        hostile,
        (display.Fact(hostile, hostile, hostile),),
        display.table((hostile,), [(hostile,)]),
        note=hostile,
    )
    page = display.html_text(summary)
    assert "<script" not in page and "'x'" not in page
    assert page.count("&lt;script&gt;alert(1)&lt;/script&gt; &amp; &#x27;x&#x27;") == 10


@pytest.mark.slow
def test_a_long_table_shows_its_first_and_last_rows(results):
    sweep = results["Sweep"]
    page = sweep._repr_html_()
    header, body = sweep.table()
    assert sweep.size == 14 and "... 4 more rows" in page and "14 rows" in page
    damping = [line[header.index("damping")] for line in body]
    shown = [d for d in damping if f">{display.number(d)}<" in page]
    assert shown == damping[:5] + damping[-5:]


# -- .plot() -------------------------------------------------------------------------------------------


@pytest.mark.slow
def test_plot_draws_the_results_own_arrays(results, drawn):
    run = results["Result"]
    lines = drawn["Result"].axes[0].get_lines()
    assert len(drawn["Result"].axes) == 3, "position, velocity, error"
    np.testing.assert_array_equal(lines[0].get_xdata(), run.time)
    np.testing.assert_array_equal(lines[0].get_ydata(), run.pos["slider"])
    np.testing.assert_array_equal(lines[1].get_ydata(), run.ref_pos["slider"])

    sweep = results["Sweep"]
    (line,) = sweep.plot(quantity="damping_ratio").axes[0].get_lines()
    np.testing.assert_array_equal(line.get_xdata(), np.sort(sweep.values["damping"]))
    order = np.argsort(sweep.values["damping"], kind="stable")
    np.testing.assert_array_equal(line.get_ydata(), sweep.column("damping_ratio")[order])

    response = results["FrequencyResponse"]
    curves = [ln.get_ydata() for ln in drawn["FrequencyResponse"].axes[0].get_lines()]
    assert any(np.array_equal(y, np.abs(response.exact)) for y in curves), "the exact magnitude is drawn"

    trade = results["Tradeoff"]
    for ln in drawn["Tradeoff"].axes[0].get_lines():
        name = ln.get_label().split(" ")[0]
        if ln.get_linestyle() != "None" and name in trade.orders:
            ok = [r.dt for r in trade.runs if r.integrator == name and not r.diverged]
            np.testing.assert_array_equal(ln.get_xdata(), ok)


@pytest.mark.slow
def test_every_result_with_plot_returns_a_figure(results, drawn):
    from matplotlib.figure import Figure

    assert set(drawn) == {name for name, result in results.items() if hasattr(result, "plot")}
    for name, fig in drawn.items():
        assert isinstance(fig, Figure) and fig.axes, name
    energy = drawn["StabilityReport"].axes
    assert len(energy) == 3 and "E/E0" in energy[0].get_ylabel()
    with pytest.raises(springlab.BadInputError, match="no figure for a ValidationRow"):
        display.plot(results["ValidationRow"])


# -- the browser ----------------------------------------------------------------------------------------

_PAGE = """<!doctype html><html><head><meta charset="utf-8"><title>springlab results</title>
<script>
window.errors = [];
window.addEventListener("error", e => window.errors.push(String(e.message || e.type)), true);
</script></head><body style="margin:16px">
{cells}
<pre id="errors"></pre>
<script>
const video = document.querySelector("video");
function done() {{
  document.getElementById("errors").textContent = window.errors.join("\\n");
  document.body.dataset.ready = "true";
}}
video.addEventListener("loadedmetadata", () => {{ video.dataset.duration = video.duration; done(); }});
video.addEventListener("error", () => {{ window.errors.push("video: " + video.error.code); done(); }});
</script></body></html>"""


def _page(results, clip) -> str:
    cells = [f'<div class="cell" style="margin-bottom:18px">{r._repr_html_()}</div>' for r in results.values()]
    cells.append(f'<div class="cell">{clip._repr_html_()}</div>')
    return _PAGE.format(cells="\n".join(cells))


@pytest.mark.slow
def test_every_summary_and_a_video_render_in_headless_chromium_without_errors(results, tmp_path):
    chromium = find_chromium()
    clip = springlab.video(results["Result"], duration=0.3, width=160, height=120, slow_motion=1.0)
    assert clip.frames == 9 and clip.mime == "video/mp4" and clip.data[4:8] == b"ftyp"
    assert repr(clip).startswith("<Video slider / free: 160 x 120 px, 9 frames at 30 fps")
    page = tmp_path / "results.html"
    page.write_text(_page(results, clip))
    # one launch; again with a longer budget only if the video's metadata had not arrived (decoding runs on
    # real threads, not on chromium's virtual clock: a loaded machine can need more, as tests/demo/test_report.py says)
    dom, log = browse_until(
        chromium,
        tmp_path / "profile",
        page.as_uri(),
        lambda d: 'data-ready="true"' in d,
        "--enable-logging=stderr",
        "--v=0",
    )
    assert 'data-ready="true"' in dom, "the video's metadata loaded (or failed) and the page finished"
    assert re.search(r'<pre id="errors"></pre>', dom), "no script, resource or media error"
    console = [line for line in log.splitlines() if "CONSOLE" in line]
    assert not console, console
    assert math.isclose(float(re.search(r'data-duration="([^"]+)"', dom).group(1)), 0.3, abs_tol=0.05)
    for name, result in results.items():
        verdict = html.escape(_verdict(result))
        assert f">{verdict}</span>" in dom, f"{name}'s verdict is on the rendered page"
    assert dom.count('class="springlab-result"') == len(results)


# -- CSV: shortest round-trip numbers ------------------------------------------------------------------

#: values whose shortest text differs from %.17g, extremes of the double range, and the signed zero
VALUES = [0.1, 1 / 3, 2 / 3, 1e-300, 5e-324, 2.2250738585072014e-308, -0.0, 0.0, 1e300, 1.7976931348623157e308]
VALUES += [-1.5, 3.0, 123456789012345.0, 1e16, 2.0**53 + 2, 0.30000000000000004, math.pi, math.inf, -math.inf]


def _bits(value: float) -> bytes:
    return struct.pack("<d", value)


def test_numbers_are_written_in_the_shortest_form_that_reads_back_to_the_same_double():
    rng = np.random.default_rng(24)
    raw = rng.integers(0, 2**64, 2000, dtype=np.uint64).view(np.float64)
    for value in VALUES + [float(v) for v in raw if math.isfinite(v)]:
        text = files.number_text(value)
        assert _bits(float(text)) == _bits(value), (value, text)
        assert len(text) <= len(repr(value)), (value, text)
    assert files.number_text(0.1) == "0.1" and files.number_text(1 / 3) == "0.3333333333333333"
    assert files.number_text(-0.0) == "-0.0" and files.number_text(5e-324) == "5e-324"
    assert files.number_text(3.0) == "3.0", "a float column reads back as floats (pandas.read_csv)"
    assert math.isnan(float(files.number_text(math.nan)))
    assert files.number_text(np.float64(0.1)) == "0.1"


def _read(path) -> tuple[list[str], list[list[str]]]:
    rows = list(csv.reader(io.StringIO(path.read_text())))
    return rows[0], rows[1:]


def _assert_exact(cells: list[str], values) -> None:
    """Each cell reads back bit for bit to its value, and is no longer than the value's repr ('' for none)."""
    assert len(cells) == len(values)
    for cell, value in zip(cells, values):
        if value == "":
            assert cell == ""
            continue
        value = float(value)
        if math.isnan(value):
            assert cell == "nan"
            continue
        assert _bits(float(cell)) == _bits(value), (cell, value)
        assert len(cell) <= len(repr(value)), (cell, value)


@pytest.mark.slow
def test_every_csv_reads_back_exactly_in_the_shortest_form(results, tmp_path, monkeypatch):
    # the tables are what this test reads: the figures outputs.write would draw beside them (sweep, Bode, design,
    # Sobol, friction settings: 1 s of CPU) are an empty file each here; the `drawn` fixture draws every result's
    # figure for the legends test below, and each command's test writes its files (tests/scenes/test_every_command.py)
    monkeypatch.setattr(
        outputs, "DRAWN", {key: lambda result, path, options: path.write_bytes(b"") for key in outputs.DRAWN}
    )
    run = results["Result"]
    outputs.write(run, tmp_path / "run")
    header, body = _read(tmp_path / "run" / "trajectory.csv")
    columns = run._csv_columns()  # what outputs.write writes: time is k dt, exactly
    assert header == list(columns)
    for i, name in enumerate(header):
        _assert_exact([row[i] for row in body], columns[name])
    assert body[20][0] == "0.1"  # 20 x 0.005 s is the double nearest 0.1: %.17g wrote 0.10000000000000001

    sweep = results["Sweep"]
    outputs.write(sweep, tmp_path / "sweep")
    header, body = _read(tmp_path / "sweep" / "sweep.csv")
    expected_header, expected = sweep.table()
    assert header == expected_header
    for i in range(len(header)):
        if any(isinstance(line[i], float) for line in expected):
            _assert_exact([row[i] for row in body], [line[i] for line in expected])

    response = results["FrequencyResponse"]
    outputs.write(response, tmp_path / "frequency")
    header, body = _read(tmp_path / "frequency" / "frequency.csv")
    for i, (name, values) in enumerate(response.rows().items()):
        assert header[i] == name
        _assert_exact([row[i] for row in body], values)

    study = results["Study"]
    outputs.write(study, tmp_path / "design")
    header, body = _read(tmp_path / "design" / "configurations.csv")
    for i, (name, values) in enumerate(study.columns.items()):
        assert header[i] == name
        _assert_exact([row[i] for row in body], values)

    friction = results["FrictionSettings"]
    outputs.write(friction, tmp_path / "friction")
    header, body = _read(tmp_path / "friction" / "friction_settings.csv")
    memory = [r.row() for case in friction.cases for r in case.runs]
    numeric = 0
    for cells, row in zip(body, memory):
        for name, value in row.items():
            if isinstance(value, float | np.floating) and not isinstance(value, bool):
                _assert_exact([cells[header.index(name)]], [value])
                numeric += 1
    assert numeric > len(memory), "the rows hold numbers"


@pytest.mark.slow
def test_every_figure_keeps_its_legends_clear_of_points_labels_and_axes(results, drawn):
    """Issue 34 item 4: every result's figure (each study's, a run's) places its legends where they cover no
    marked point, no axis label or title and no axes (the check of tests/plots/test_settings_figures.py, on all)."""
    failures = {}
    for name, figure in drawn.items():
        try:
            assert_legends_clear(figure, require=False)
        except AssertionError as error:
            failures[name] = str(error).splitlines()[0]
    assert not failures, "; ".join(f"{name}: {words[:90]}" for name, words in failures.items())
