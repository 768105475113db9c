"""The interactive page (springlab interactive): real MuJoCo in headless Chromium agrees with springlab's Python.

One Chromium for the module, driven over its DevTools pipe: each page opens from file://, the test reads
#result, moves the page's own sliders (input events, as a reader's hand would) and compares every
setting's final position, error and verdict with `run_scenario` at the same settings. The JavaScript
ports of the closed form, the tolerance and the range of the error estimate are compared with the Python
in node on a grid of parameters. The browser is Debian's chromium (tests/demo/test_report.py: skipped where
absent unless SPRINGLAB_REQUIRE_CHROMIUM is set); mujoco-js comes from `npm pack`, cached.

Agreement: the browser steps MuJoCo 3.3.8 (mujoco-js 0.0.7), Python steps MuJoCo 4.0; the slider's and
the car's models are a slide joint with stiffness, damping (and gravity) stepped by the same integrator
code, and the final positions agree to the last bit (asserted to 1e-12 of the motion's size, the issue's
bound, and bit for bit at the initial settings).
"""

import functools
import http.server
import json
import math
import os
import re
import shutil
import subprocess
import threading
import xml.etree.ElementTree as ElementTree

import mujoco
import numpy as np
import pytest

from helpers.browser import RESULT_AFTER, DevTools, find_chromium
from springlab import scenes
from springlab.errors import BadInputError, DivergedError
from springlab.render import interactive
from springlab.runs import compare
from springlab.runs.run import run_scenario
from springlab.scenes.capabilities.interactive import formula
from springlab.sim import model_files

#: the issue's bound on the agreement of the final position (relative to max |x|) and of the error [-]
AGREEMENT = 1e-12


def _unavailable(what: str) -> None:
    """Skip where Node.js is missing (as test_report skips without chromium); fail where CI requires it."""
    if os.environ.get("SPRINGLAB_REQUIRE_CHROMIUM"):
        pytest.fail(f"{what} is required here (SPRINGLAB_REQUIRE_CHROMIUM): {what} unavailable")
    pytest.skip(f"the interactive page's tests need {what} (Node.js)")


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """Every page of the slider and the car in one folder (the npm tarball from the user's cache after the first run)."""
    out = tmp_path_factory.mktemp("interactive")
    pages = {}
    for scene in ("slider", "car"):
        try:
            written = interactive.write_interactive(scene, None, out)
        except interactive.NodeUnavailableError:
            _unavailable("npm")
        assert [page.scenario for page in written] == list(scenes.get(scene).interactive.scenarios)
        pages.update({(scene, page.scenario): page for page in written})
    return pages


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    chromium = find_chromium()
    tools = DevTools(chromium, tmp_path_factory.mktemp("chromium-profile"))
    yield tools
    tools.close()


def _python(result: dict):
    """springlab's Python run at the page's settings: the values its sliders move, in full precision."""
    spec = scenes.get(result["scene"]).interactive
    params = json.loads(result["parameters"])
    return run_scenario(
        result["scene"],
        result["scenario"],
        integrator=result["integrator"],
        dt=float(result["dt"]),
        duration=float(result["duration"]),
        **{name: params[name] for name in (spec.mass, spec.stiffness, spec.damping)},
    )


def _assert_agrees(page: dict, python) -> None:
    x = python.pos[scenes.get(python.scene).interactive.joint]
    assert page["verdict"] == python.verdict.value
    assert int(page["steps"]) == python.steps
    assert abs(float(page["final-position"]) - float(x[-1])) <= AGREEMENT * float(np.max(np.abs(x)))
    assert abs(float(page["max-error"]) - python.max_rel_error) <= AGREEMENT
    assert math.isclose(float(page["tolerance"]), python.tolerance, rel_tol=1e-9)


@pytest.mark.slow
def test_every_page_from_file_agrees_with_python_at_its_initial_settings(pages, browser):
    """The slider's seven browser scenarios (free, step, the damping family, the exercise) and the car's two
    releases, opened from disk: bit for bit, MuJoCo 3.3.8 in the page against 4.0 in Python."""
    for (scene_name, name), page in pages.items():
        scene = scenes.get(scene_name)
        session = browser.open(page.path.as_uri())
        initial = browser.evaluate(session, RESULT_AFTER.format(after=0))
        scenario = scene.scenario(name)
        assert (initial["scene"], initial["scenario"]) == (scene_name, name)
        assert initial["integrator"] == scene.integrator
        assert float(initial["dt"]) == scenario.dt and float(initial["duration"]) == scenario.duration
        assert json.loads(initial["parameters"]) == scene.resolve(scenario, {})
        python = run_scenario(scene_name, name)
        _assert_agrees(initial, python)
        x = python.pos[scene.interactive.joint]
        assert float(initial["final-position"]) == float(x[-1])  # bit for bit, in fact
        browser.call("Target.closeTarget", {"targetId": browser.targets[session]})


def test_slider_moves_agree_with_python_and_a_dt_past_the_stability_limit_diverges(pages, browser):
    """Two slider positions set through the page's own inputs: zeta, k, dt and the integrator moved, then
    the dt slider at its top with RK4 (omega dt = 4.9 > 2.83), which the page and springlab call diverged;
    and the page's MJCF edit compiles to the model Scene.edit builds through MjSpec."""
    scene = scenes.get("slider")
    session = browser.open(pages["slider", "free"].path.as_uri())
    initial = browser.evaluate(session, RESULT_AFTER.format(after=0))
    params = json.loads(initial["parameters"]) | {"mass": 2.5, "stiffness": 40.0, "damping": 0.7}
    xml = browser.evaluate(session, f"window.springlabPage.editedMjcf({json.dumps(params)})")
    _assert_same_model(mujoco.MjModel.from_xml_string(xml), scene.build(params, scene.scenario("free")))

    moved = browser.evaluate(
        session,
        "(() => { const set = (id, v) => { const e = document.getElementById(id); e.value = String(v);"
        " e.dispatchEvent(new Event('input')); };"
        " set('zeta', 0.3); set('stiffness', 2.4); set('dt', Math.log10(0.02)); set('integrator', 'euler');"
        f" return {RESULT_AFTER.format(after=1)}; }})()",
    )
    assert moved["integrator"] == "euler" and abs(float(moved["dt"]) - 0.02) < 0.001
    moved_params = json.loads(moved["parameters"])
    assert moved_params["stiffness"] == pytest.approx(10**2.4, rel=1e-12)
    assert moved_params["damping"] == pytest.approx(2 * 0.3 * math.sqrt(10**2.4), rel=1e-12)
    _assert_agrees(moved, _python(moved))

    blown = browser.evaluate(
        session,
        "(() => { const e = document.getElementById('dt'); e.value = e.max; e.dispatchEvent(new Event('input'));"
        " const i = document.getElementById('integrator'); i.value = 'rk4'; i.dispatchEvent(new Event('input'));"
        f" return {RESULT_AFTER.format(after=2)}; }})()",
    )
    # the slider's top, 0.49 s on its 0.01-decade steps
    assert blown["verdict"] == "diverged" and float(blown["dt"]) > 0.45
    with pytest.raises(DivergedError):
        _python(blown)
    # the error axis is log10 |x - x_exact|: its ends read as powers of ten (10⁻¹⁷ .. 10ᵏ), not bare exponents
    ends = json.loads(browser.evaluate(session, "document.getElementById('error').dataset.yLabels"))
    assert ends[0] == "10\u207b\u00b9\u2077"
    assert re.fullmatch("10[\u2070\u00b9\u00b2\u00b3\u2074-\u2079]+", ends[1]), ends


def test_car_release_moves_agree_with_python(pages, browser):
    """The car's damped release at a moved damping ratio, mass and dt: the spring's relaxed length and the
    pushed-down start follow the mass and stiffness in the page as in Release.edit and Release.setup."""
    session = browser.open(pages["car", "damped_release"].path.as_uri())
    browser.evaluate(session, RESULT_AFTER.format(after=0))
    moved = browser.evaluate(
        session,
        "(() => { const set = (id, v) => { const e = document.getElementById(id); e.value = String(v);"
        " e.dispatchEvent(new Event('input')); };"
        " set('zeta', 0.55); set('mass', 3.3); set('dt', Math.log10(0.01));"
        f" return {RESULT_AFTER.format(after=1)}; }})()",
    )
    params = json.loads(moved["parameters"])
    # the mass slider's 0.01-decade steps start at its declared 250 kg: 10^3.3 snaps to 10^3.298
    assert params["mass"] == pytest.approx(10**3.3, rel=0.03) and abs(float(moved["dt"]) - 0.01) < 1e-3
    _assert_agrees(moved, _python(moved))


def test_a_page_served_over_http_computes_the_same_run(pages, browser):
    """From a web server (loopback, a thread of this test) the free page publishes what it does from file://."""
    folder = pages["slider", "free"].path.parent
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        session = browser.open(f"http://127.0.0.1:{server.server_address[1]}/{pages['slider', 'free'].path.name}")
        served = browser.evaluate(session, RESULT_AFTER.format(after=0))
    finally:
        server.shutdown()
        server.server_close()
    _assert_agrees(served, run_scenario("slider", "free"))


def _assert_same_model(page: mujoco.MjModel, python: mujoco.MjModel) -> None:
    for field in ("body_mass", "body_inertia", "jnt_stiffness", "dof_damping", "qpos0", "actuator_gear"):
        np.testing.assert_array_equal(getattr(page, field), getattr(python, field), err_msg=field)


@pytest.mark.parametrize(
    ("scene_name", "overrides"),
    [("slider", {"mass": 0.3, "stiffness": 7.0, "damping": 0.125}), ("car", {"mass": 1234.5, "stiffness": 3.3e5})],
)
def test_declared_edits_write_what_scene_edit_sets(scene_name, overrides):
    """The InteractiveSpec edits, applied to the MJCF text by ElementTree, compile to Scene.build's model, and
    its x0 formula is where Scene.setup starts the joint."""
    scene = scenes.get(scene_name)
    spec = scene.interactive
    for name in spec.scenarios:
        scenario = scene.scenario(name)
        case = scene.case(scenario, overrides)
        params, built = case.params, case.model
        values = params | {"g": -float(built.opt.gravity[2])}
        root = ElementTree.fromstring(model_files.path(scene_name).read_text())
        for edit in spec.edits:
            element = root.find(f".//{edit.tag}[@name='{edit.name}']")
            assert element is not None
            target = element.find(edit.child) if edit.child else element
            target.set(edit.attribute, repr(formula(edit.value, values)))
        page = mujoco.MjModel.from_xml_string(ElementTree.tostring(root, "unicode"))
        _assert_same_model(page, built)
        np.testing.assert_array_equal(page.qpos_spring, built.qpos_spring)
        setup = case.setup(10, scenario.dt)
        joint = built.joint(spec.joint)
        assert formula(spec.x0, values) == setup.qpos[joint.qposadr[0]]
        assert formula(spec.v0, values) == setup.qvel[joint.dofadr[0]]


_SLIDER = ("mass", "stiffness", "damping", "x0", "v0", "force_amplitude")
#: (scene, scenario, overrides): the slider's every regime, k = 0, heavy overdamping, steps; the car's releases
GRID = [
    ("slider", "step", dict(zip(_SLIDER, values)))
    for values in (
        (1.0, 100.0, 1.0, 0.1, 0.0, 0.0),
        (1.0, 100.0, 0.0, 0.1, 0.3, 0.0),
        (2.0, 8.0, 8.0, 0.5, 0.0, 0.0),  # critical: d = 2 sqrt(k m)
        (1.0, 2.0, 3.0, 5.0, 0.0, 0.0),  # the exercise
        (1.0, 1.0, 1e4, 1.0, -2.0, 0.0),
        (3.0, 0.0, 0.5, 0.0, 1.0, 0.0),
        (1.0, 100.0, 1.0, 0.0, 0.0, 10.0),
        (0.5, 50.0, 20.0, 0.2, 0.1, -3.0),
        (1.0, 0.0, 0.0, 0.0, 1.0, 2.0),
    )
] + [
    ("car", "push_release", {}),
    ("car", "damped_release", {}),
    ("car", "damped_release", {"mass": 2500.0, "stiffness": 2e5, "damping_ratio": 1.5}),
]
SETTINGS = [("rk4", 5e-3, 5.0), ("euler", 2e-2, 5.0), ("implicit", 1e-3, 3.0), ("rk4", 0.25, 6.0)]


def test_javascript_exact_solution_tolerance_and_range_match_the_python(tmp_path):
    """web/exact.js in node against springlab.exact.analytic and springlab.runs.compare on GRID x SETTINGS:
    the scenes' own references (the car's about its gravity-loaded rest height), built by the scenes."""
    node = shutil.which("node")
    if node is None:
        _unavailable("node")
    cases = []
    for scene_name, scenario_name, overrides in GRID:
        scene = scenes.get(scene_name)
        spec, scenario = scene.interactive, scene.scenario(scenario_name)
        case = scene.case(scenario, overrides)
        params, model = case.params, case.model
        values = params | {"g": -float(model.opt.gravity[2])}
        p = {
            "m": params[spec.mass],
            "k": params[spec.stiffness],
            "d": params[spec.damping],
            "x0": formula(spec.x0, values),
            "v0": formula(spec.v0, values),
            "force": formula(spec.force, values) if spec.force else 0.0,
            "rest": formula(spec.rest, values) if spec.rest else None,
        }
        for integrator, dt, duration in SETTINGS:
            times = np.arange(round(duration / dt) + 1) * dt
            reference = case.reference(times, dt=dt)
            cases.append(
                dict(p=p, integrator=integrator, dt=dt, time=list(times), reference=reference, joint=spec.joint)
            )
    script = tmp_path / "grid.js"
    script.write_text(
        f"const exact = require({json.dumps(str(interactive._WEB / 'exact.js'))});\n"
        f"const cases = {json.dumps([{k: c[k] for k in ('p', 'integrator', 'dt', 'time')} for c in cases])};\n"
        "const out = cases.map(c => { const p = c.p, t = Float64Array.from(c.time);"
        " const ref = exact.reference(t, p);"
        " const tol = exact.tolerances(t, ref, p.m, p.k, p.d, exact.generatorOf(p), c.integrator, c.dt);"
        " const range = exact.estimateRange(exact.rates(p.m, p.k, p.d), c.integrator, c.dt, t[t.length - 1]);"
        " return {x: Array.from(ref.x), v: Array.from(ref.v), tol, inside: range.inside, factor: range.factor,"
        " largest: range.largestDt}; });\n"
        "process.stdout.write(JSON.stringify(out));\n"
    )
    done = subprocess.run([node, str(script)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    answers = json.loads(done.stdout, parse_constant=float)
    for case, js in zip(cases, answers):
        reference, times, joint, where = case["reference"], np.array(case["time"]), case["joint"], case["p"]
        x, v = reference.pos[joint], reference.vel[joint]
        # the same operations in the same order: libm's and V8's exp/cos differ by an ulp at most
        scale_x, scale_v = float(np.max(np.abs(x))) or 1.0, float(np.max(np.abs(v))) or 1.0
        assert np.max(np.abs(np.array(js["x"]) - x)) <= 64 * np.finfo(float).eps * scale_x, where
        assert np.max(np.abs(np.array(js["v"]) - v)) <= 64 * np.finfo(float).eps * scale_v, where
        tolerances = compare.tolerances(reference, case["integrator"], case["dt"], times)
        noise = _roundoff_of_tolerance(reference, joint, case["integrator"], case["dt"], times)
        for kind in ("pos", "vel"):
            python = min(tolerances[f"{joint}_{kind}"], compare.CERTIFIED_CAP)
            assert abs(js["tol"][kind] - python) <= 1e-9 * python + noise[kind], (where, case["integrator"], kind)
        expected = compare.estimate_range(
            compare.system_rates(reference), case["integrator"], case["dt"], float(times[-1])
        )
        assert js["inside"] == expected.inside, where
        factor = js["factor"] if js["factor"] is not None else math.inf
        assert factor == pytest.approx(expected.factor, rel=1e-9) or factor == expected.factor == math.inf
        largest = js["largest"] if js["largest"] is not None else math.inf
        assert largest == expected.largest_dt


def _roundoff_of_tolerance(reference, joint: str, integrator: str, dt: float, times: np.ndarray) -> dict[str, float]:
    """How far round-off alone moves the tolerance [-]: A^(p+1) z(t) loses eps |A|^(p+1) |z| to cancellation.

    Where A is stiff (d = 1e4: |A|^5 ~ 1e20 while A^5 z follows the slow mode) the predicted error is
    round-off in Python and JavaScript alike; elsewhere this is far below the 1e-9 agreement.
    """
    order = compare.ORDERS[integrator]
    a = np.asarray(reference.system, float)
    power = np.linalg.matrix_power(np.abs(a), order + 1)
    bound = 16 * np.finfo(float).eps * compare.ERROR_CONSTANTS[integrator] * dt**order
    spread = bound * (times - times[0])[:, None] * (np.abs(reference.states) @ power.T)
    rho = max(float(np.max(np.abs(np.linalg.eigvals(a)))), 1.0 / float(times[-1]))
    worst = float(np.max(np.hypot(spread[:, 0], spread[:, 1] / rho)))
    return {
        kind: compare.SAFETY * worst * scale / (float(np.max(np.abs(series))) or 1.0)
        for kind, scale, series in (("pos", 1.0, reference.pos[joint]), ("vel", rho, reference.vel[joint]))
    }


def test_scenes_without_a_browser_page_and_bad_scenarios_are_one_line_errors(tmp_path):
    with pytest.raises(BadInputError, match="kinematics has no interactive page"):
        interactive.write_interactive("kinematics", None, tmp_path)
    with pytest.raises(BadInputError, match="pitch_heave"):
        interactive.write_interactive("car", "pitch_heave", tmp_path)
    # a known scenario without a page is named as such (not 'unknown'), with every scenario that has one
    with pytest.raises(BadInputError) as known:
        interactive.write_interactive("slider", "harmonic", tmp_path)
    message = str(known.value)
    assert "slider / harmonic has no interactive page" in message and "unknown" not in message
    for scene, names in interactive.interactive_scenes().items():
        assert f"{scene}: {', '.join(names)}" in message
    # a name the scene does not know stays an unknown scenario, with the scene's scenarios
    with pytest.raises(BadInputError, match="unknown scenario of slider 'harmonix'; valid: .*harmonic"):
        interactive.write_interactive("slider", "harmonix", tmp_path)
    assert not any(tmp_path.iterdir())


def test_the_vendored_module_is_pinned_and_its_webassembly_only_loses_custom_sections(pages):
    """The written script is the pinned tarball's module, classic, with a wasm whose code sections are unchanged."""
    folder = pages["slider", "free"].path.parent
    notice = (folder / interactive.LICENSE_FILE).read_text()
    assert "Apache License, Version 2.0" in notice and interactive.MUJOCO_JS_SHA256 in notice
    script = (folder / interactive.MUJOCO_SCRIPT).read_text()
    assert "import.meta" not in script and "export default" not in script
    module = b"\0asm\x01\0\0\0" + bytes([0, 5, 4]) + b"name" + bytes([1, 1, 0]) + bytes([0, 3, 2]) + b"ab"
    assert interactive.strip_custom_sections(module) == b"\0asm\x01\0\0\0" + bytes([1, 1, 0])


def test_the_demo_links_the_pages_from_its_report_and_skips_them_in_one_line_without_npm(
    pages, tmp_path, monkeypatch, capsys
):
    from springlab.demo import report
    from springlab.demo import steps as demo

    state = demo.DemoState(out=tmp_path / "out")
    artifacts = demo.interactive_step(state)
    paths = {a.path for a in artifacts}
    assert {"interactive/slider-free.html", "interactive/car-push_release.html"} <= paths
    assert len(paths) == sum(len(s.interactive.scenarios) for s in scenes.SCENES.values() if s.interactive)
    assert all((state.out / path).is_file() for path in paths)
    state.artifacts.extend(artifacts)
    assert "href='interactive/slider-free.html'" in report.build_html(state)

    # no npm on PATH and nothing cached: the demo goes on and says so in one line
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    capsys.readouterr()
    assert demo.interactive_step(demo.DemoState(out=tmp_path / "bare")) == []
    said = capsys.readouterr().out.strip().splitlines()
    assert len(said) == 1 and said[0].startswith("demo: interactive page skipped: ") and "npm is not on PATH" in said[0]
    assert not (tmp_path / "bare" / "interactive").exists()
