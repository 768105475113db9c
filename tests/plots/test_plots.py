"""Plots carry what they claim: the curves, the exact overlay, the log error axis, the field and equilibria."""

import json
import math
import subprocess
import sys

import matplotlib.colors
import numpy as np
import pytest
from matplotlib.quiver import Quiver

from springlab.cli.main import main
from springlab.errors import BadInputError
from springlab.plots import run as plots
from springlab.runs.run import run_scenario
from springlab.studies import families


def _lines(ax, label=None):
    return [line for line in ax.get_lines() if label is None or line.get_label() == label]


def _legend_texts(ax):
    legend = ax.get_legend()
    return [text.get_text() for text in legend.get_texts()] if legend else []


def test_time_series_overlays_the_exact_solution_and_puts_the_error_on_a_log_axis():
    result = run_scenario("slider", "underdamped")
    figure = plots.time_series(result)
    axes = figure.axes
    assert len(axes) == 3
    position, velocity, error = axes
    for ax, series, exact in ((position, result.pos, result.ref_pos), (velocity, result.vel, result.ref_vel)):
        (sim,), (ref,) = _lines(ax, "MuJoCo"), _lines(ax, "exact")
        np.testing.assert_array_equal(sim.get_ydata(), series["slider"])
        np.testing.assert_array_equal(ref.get_ydata(), exact["slider"])
    assert position.get_ylabel() == "position x [m]" and velocity.get_ylabel() == "velocity v [m/s]"
    assert position.get_title() == "joint slider"  # the joint in the title, the quantity and unit on the axis
    assert error.get_yscale() == "log" and error.get_xlabel() == "time t [s]"
    labels = [line.get_label() for line in error.get_lines()]
    assert "|position error| [m]" in labels and "position tolerance" in labels
    # the plotted error is |sim - exact| (zeros left out of the log axis, not drawn at -inf)
    drawn = _lines(error, "|position error| [m]")[0].get_ydata()
    expected = np.abs(result.pos["slider"] - result.ref_pos["slider"])
    np.testing.assert_array_equal(np.isnan(drawn), expected == 0)
    np.testing.assert_allclose(drawn[expected > 0], expected[expected > 0])


def test_time_series_has_a_column_per_joint_with_its_units():
    figure = plots.time_series(run_scenario("car", "pitch_heave"))
    labels = [ax.get_ylabel() for ax in figure.axes]
    assert "position x [m]" in labels and "angle θ [rad]" in labels and "angular velocity ω [rad/s]" in labels
    assert {"joint heave", "joint pitch"} <= {ax.get_title() for ax in figure.axes}
    assert sum(ax.get_yscale() == "log" for ax in figure.axes) == 2
    figure.draw_without_rendering()  # placed, as when saved (no pixels needed): legends beside the axes cover no data
    legends = [ax.get_legend().get_window_extent() for ax in figure.axes if ax.get_legend()]
    assert legends and not any(box.overlaps(ax.get_window_extent()) for box in legends for ax in figure.axes)


def test_phase_plane_of_the_softening_spring_shows_field_equilibria_and_separatrix():
    result = run_scenario("nonlinear", "softening")
    k1, k3 = result.parameters["k1"], result.parameters["k3"]
    saddle = math.sqrt(-k1 / k3)  # force -(k1 x + k3 x^3) vanishes at 0 and +-sqrt(-k1/k3)
    figure = plots.phase_plane(result)
    ax = figure.axes[0]
    assert any(isinstance(c, Quiver) for c in ax.collections), "vector field drawn"
    (stable,), (unstable,) = _lines(ax, "stable equilibrium"), _lines(ax, "unstable equilibrium")
    np.testing.assert_allclose(stable.get_xdata(), [0.0], atol=1e-12)
    np.testing.assert_allclose(sorted(unstable.get_xdata()), [-saddle, saddle], rtol=1e-12)
    assert stable.get_markerfacecolor() != unstable.get_markerfacecolor()  # filled vs hollow
    assert unstable.get_markerfacecolor() in ("white", (1.0, 1.0, 1.0, 1.0))
    # the separatrix is the saddle's energy level: m v^2 / 2 + k1 x^2 / 2 + k3 x^4 / 4 = V(saddle)
    (separatrix,) = _lines(ax, "separatrix")
    x, v = separatrix.get_xdata(), separatrix.get_ydata()
    m = result.parameters["mass"]

    def potential(x):
        return k1 * x**2 / 2 + k3 * x**4 / 4

    np.testing.assert_allclose(m * v**2 / 2 + potential(x), potential(saddle), atol=1e-9 * abs(potential(saddle)))
    (sim,), (_start,) = _lines(ax, "MuJoCo"), _lines(ax, "start")
    np.testing.assert_array_equal(sim.get_xdata(), result.pos["block"])
    assert ax.get_xlabel() == "position x [m]" and ax.get_ylabel() == "velocity v [m/s]"
    assert ax.get_title() == "phase plane of joint block"


def test_family_of_undamped_releases_are_ellipses_of_semi_axes_x0_and_omega_x0():
    figure = plots.phase_family(families.run_phase_family(run_scenario("slider", "undamped")))
    ax = figure.axes[0]
    result = run_scenario("slider", "undamped")
    omega = math.sqrt(result.parameters["stiffness"] / result.parameters["mass"])
    members = [line for line in ax.get_lines() if line.get_label().startswith("slider(0) = ")]
    assert len(members) == len(families.FAMILY_FRACTIONS)
    for line, fraction in zip(members, families.FAMILY_FRACTIONS):
        x, v = line.get_xdata(), line.get_ydata()
        x0 = fraction * result.parameters["x0"]
        assert x[0] == pytest.approx(x0)
        # energy m v^2 / 2 + k x^2 / 2 is conserved: (x/x0)^2 + (v/(omega x0))^2 = 1 (eq. 5.9)
        np.testing.assert_allclose((x / x0) ** 2 + (v / (omega * x0)) ** 2, 1.0, atol=1e-6)
    assert any(isinstance(c, Quiver) for c in ax.collections)


def test_family_across_the_separatrix_marks_exactly_the_releases_beyond_the_saddle_as_escaping():
    figure = plots.phase_family(families.run_phase_family(run_scenario("nonlinear", "softening")))
    ax = figure.axes[0]
    result = run_scenario("nonlinear", "softening")
    saddle = math.sqrt(-result.parameters["k1"] / result.parameters["k3"])
    members = [line for line in ax.get_lines() if line.get_label().startswith("block(0) = ")]
    assert len(members) == len(families.FAMILY_SEPARATRIX_FRACTIONS)
    for line in members:
        start = line.get_xdata()[0]
        # released at rest beyond the saddle, the spring force pushes outwards: escape (section 5.5)
        assert ("(escapes)" in line.get_label()) == (start > saddle)
        if start < saddle:
            assert np.max(np.abs(line.get_xdata())) == pytest.approx(start, rel=1e-6)  # turns back at x0


def test_zeta_family_draws_each_damping_ratio_with_its_regime_and_exact_curve():
    figure = plots.zeta_family(families.run_zeta_family("slider", "free"))
    response, phase = figure.axes
    texts = [text.get_text() for text in figure.legends[0].get_texts()]  # beside the axes, over no curve
    assert [t.split(" ")[2] for t in texts[:-1]] == [f"{z:g}" for z in families.ZETAS]
    assert "ζ = 1 (critical)" in texts and "ζ = 2 (overdamped)" in texts and "ζ = 0 (undamped)" in texts
    solid = [line for line in response.get_lines() if line.get_label().startswith("ζ")]
    dashed = [line for line in response.get_lines() if line.get_linestyle() != "-"]
    assert len(solid) == len(families.ZETAS) and len(dashed) >= len(families.ZETAS)
    # every pair of ratios is told apart by colour (zeta = 0 and 0.1 included), and the exact curves are
    # white dashes inside them, not dark dashes over them
    colours = np.array([matplotlib.colors.to_rgb(line.get_color()) for line in solid])
    distances = np.linalg.norm(colours[:, None] - colours[None], axis=-1)[np.triu_indices(len(colours), 1)]
    assert distances.min() > 0.25
    assert all(matplotlib.colors.to_rgb(line.get_color()) == (1.0, 1.0, 1.0) for line in dashed)
    # the legend sits beside the axes: it covers no data
    figure.draw_without_rendering()  # every artist placed as when saved; no pixels needed
    legend_box = figure.legends[0].get_window_extent()
    assert not any(legend_box.overlaps(ax.get_window_extent()) for ax in figure.axes)
    # the critically damped curve is x0 (1 + omega t) e^{-omega t} (eq. 5.16 with v0 = 0)
    result = run_scenario("slider", "free")
    omega = math.sqrt(result.parameters["stiffness"] / result.parameters["mass"])
    critical = solid[families.ZETAS.index(1.0)]
    t, x = critical.get_xdata(), critical.get_ydata()
    np.testing.assert_allclose(x, result.parameters["x0"] * (1 + omega * t) * np.exp(-omega * t), atol=1e-6)
    assert len(phase.get_lines()) == 2 * len(families.ZETAS)


def test_kinds_that_do_not_apply_say_so():
    with pytest.raises(BadInputError, match="family"):
        families.run_phase_family(run_scenario("kinematics", "tachograph"))
    with pytest.raises(BadInputError, match="damping"):
        families.run_zeta_family("kinematics")


def test_plot_command_writes_png_and_svg_and_refuses_other_formats(tmp_path, capsys):
    assert main(["plot", "slider", "step", "--output", str(tmp_path / "t.png")]) == 0
    assert (tmp_path / "t.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["plot", "nonlinear", "double_well", "--kind", "phase", "--output", str(tmp_path / "p.svg")]) == 0
    assert b"<svg" in (tmp_path / "p.svg").read_bytes()[:500]
    capsys.readouterr()
    assert main(["plot", "slider", "--output", str(tmp_path / "t.jpg")]) == 2
    err = capsys.readouterr().err
    assert "unsupported plot format '.jpg'" in err and ".png, .svg, .pdf" in err
    assert main(["plot", "slider", "--kind", "pie", "--output", str(tmp_path / "x.png")]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.svg", "t.png"]


@pytest.fixture(scope="module")
def fresh_plotting(tmp_path_factory):
    """One fresh interpreter (a library's effect on a caller's matplotlib shows only from a clean start) that
    notes the rcParams, draws a run's phase plane and time series and saves one, then prints what the two tests
    below read: whether pyplot got imported, the rcParams that changed, the axis label's font size (one
    interpreter for both: each start and import of springlab and matplotlib cost ~1.5 s of CPU)."""
    png = tmp_path_factory.mktemp("fresh_plotting") / "t.png"
    code = (
        "import json, sys, matplotlib\n"
        # the stored values: reading rcParams['backend'] through the mapping would pick a backend and import
        # pyplot itself; the backend's stored value stays 'not chosen yet' unless something chooses it
        "stored = lambda: dict(dict.items(matplotlib.rcParams))\n"
        "before = stored()\n"
        "import springlab.plots.run as p, springlab.runs.run as a\n"
        "run = a.run_scenario('slider', 'free', duration=0.2)\n"
        "p.phase_plane(run)\n"
        "figure = p.time_series(run)\n"
        f"p.save(figure, {str(png)!r})\n"
        "changed = [k for k, v in stored().items() if before[k] != v]\n"
        "size = figure.axes[0].xaxis.label.get_fontsize()\n"
        "print(json.dumps({'pyplot': 'matplotlib.pyplot' in sys.modules, 'changed': changed, 'size': size}))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False, timeout=120)
    assert done.returncode == 0, done.stderr
    assert png.stat().st_size > 0
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_plotting_never_touches_pyplot_global_state(fresh_plotting):
    assert not fresh_plotting["pyplot"], "pyplot imported"


@pytest.mark.slow
def test_tradeoff_stability_and_design_charts_leave_the_callers_backend_alone(tmp_path):
    # a library must not switch a notebook's backend (matplotlib.use) or import pyplot; the charts only need
    # results to draw: small studies (each run timed once: the chart reads no wall time), and a hand-built
    # stability report (tests/studies/test_stability.py checks the real one)
    code = (
        "import sys, matplotlib\n"
        "matplotlib.use('svg')\n"
        "import numpy as np\n"
        "from springlab import outputs\n"
        "from springlab.plots import charts, design as design_chart\n"
        "from springlab.studies import stability, tradeoff\n"
        "from springlab.studies.design import study as design\n"
        f"charts.plot_tradeoff(tradeoff.sweep('slider', 'free', duration=0.5, timing_repeats=1), {str(tmp_path / 't.png')!r})\n"
        f"design_chart.plot(design.run_study('printer_head', levels=3, plane_levels=5), {str(tmp_path / 'd.png')!r})\n"
        "n = np.arange(4)\n"
        "series = stability.EnergyHistories('oscillator', 0.2, 1.0, n / 3, {'euler': 1 + 0.01 * np.sin(n),"
        " 'rk4': 0.99**n, 'discrete': 0.9**n}, {'rk4': 0.99**n, 'discrete': 0.9**n}, {'euler': (0.9, 1.1)}, ())\n"
        "report = stability.StabilityReport((stability.Boundary('rk4', 0.0, 2.83, 2.83, 0.0, True),), (), series,"
        " 'grows', 0.01, 0.0)\n"
        "amplification = stability.AmplificationMap(np.array([0.0, 1.0]), np.geomspace(0.01, 1e3, 4),"
        " {'rk4': np.full((2, 4), 0.5)})\n"
        f"outputs.write(report, {str(tmp_path / 's')!r}, amplification=amplification)\n"
        "assert matplotlib.get_backend() == 'svg', matplotlib.get_backend()\n"
        "assert 'matplotlib.pyplot' not in sys.modules, 'pyplot imported'\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)
    assert (tmp_path / "t.png").stat().st_size > 0 and (tmp_path / "d.png").stat().st_size > 0
    for name in ("stability.png", "energy.png"):
        assert (tmp_path / "s" / name).stat().st_size > 0


def test_plotting_leaves_the_callers_rcparams_alone_and_still_uses_its_own_style(fresh_plotting):
    from springlab.plots.style import STYLE

    assert not fresh_plotting["changed"], fresh_plotting["changed"]
    assert fresh_plotting["size"] == STYLE["font.size"]
