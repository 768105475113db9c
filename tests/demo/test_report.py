"""The demo report opens from disk in a real browser: no errors, every video plays, every artifact linked.

The browser is Debian's `chromium` package. .ci/run installs it on CI (as root
with apt-get); elsewhere this test finds it or skips, saying how to get it.
Set SPRINGLAB_REQUIRE_CHROMIUM=1 (as .ci/run does) to turn that skip into a failure.
"""

import html.parser
import re

import numpy as np
import pytest

from helpers.browser import browse_until, find_chromium
from springlab.demo import steps as demo
from springlab.runs.run import ValidationRow, run_scenario

SCENARIOS = [("slider", "undamped"), ("car", "pitch_heave")]
CLIP_SECONDS = 0.5


@pytest.fixture(scope="module")
def demo_out(tmp_path_factory):
    """A small demo: two scenes' runs through the real media and report steps, plus foreign artifacts."""
    out = tmp_path_factory.mktemp("demo")
    state = demo.DemoState(out=out)
    for scene, scenario in SCENARIOS:
        result = run_scenario(scene, scenario)
        state.results[(scene, scenario)] = result
        state.validation.append(ValidationRow.of(result))
    saved = demo.DEMO_CLIP_SECONDS
    demo.DEMO_CLIP_SECONDS = CLIP_SECONDS  # short clips keep the test quick; the page is the same
    try:
        state.artifacts.extend(demo.media_step(state))
    finally:
        demo.DEMO_CLIP_SECONDS = saved
    # artifacts from steps this report does not know (e.g. a trade-off study): listed by kind alone
    (out / "tradeoff").mkdir()
    (out / "tradeoff" / "pareto.csv").write_text("dt,error\n0.001,1e-9\n")
    (out / "tradeoff" / "pareto.svg").write_text(
        "<svg xmlns='http://www.w3.org/2000/svg' width='20' height='20'><rect width='20' height='20'/></svg>"
    )
    state.artifacts += [
        demo.Artifact("tradeoff/pareto.csv", "data", "error vs wall time"),
        demo.Artifact("tradeoff/pareto.svg", "plot", "Pareto front"),
        demo.Artifact("tradeoff/pareto.csv", "data", "the same sweep for the slider", "slider"),
    ]
    state.artifacts += demo.report_step(state)
    return out, state


class _Links(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        self.refs += [value for name, value in attrs if name in ("href", "src") and value]


@pytest.mark.slow
def test_report_links_every_artifact_and_nothing_outside_the_folder(demo_out):
    out, state = demo_out
    page = (out / "index.html").read_text()
    parser = _Links()
    parser.feed(page)
    local = [ref for ref in parser.refs if not ref.startswith("#")]
    assert not [ref for ref in local if re.match(r"[a-z]+:", ref)], "self-contained: no external resources"
    for ref in local:
        assert (out / ref).is_file(), f"broken link {ref}"
    for artifact in state.artifacts:
        if artifact.path == "index.html":
            continue  # the report itself
        assert artifact.path in local, f"{artifact.path} ({artifact.kind}) not linked"
    kinds = {a.kind for a in state.artifacts}
    assert {"data", "plot", "video", "report"} <= kinds
    videos = [a.path for a in state.artifacts if a.kind == "video"]
    assert len(videos) == len(SCENARIOS) and page.count("<video") == len(videos)
    # the validation table: one row per validated run with its error, tolerance and verdict
    for row in state.validation:
        assert f"{row.max_rel_error:.2e}" in page and f"{row.tolerance:.2e}" in page
    assert page.count('class="pass"') + page.count("class='pass'") >= len(state.validation)


@pytest.mark.slow
def test_report_loads_in_headless_chromium_with_playing_videos_and_no_errors(demo_out, tmp_path):
    chromium = find_chromium()
    out, state = demo_out
    url = (out / "index.html").as_uri()
    shot = tmp_path / "shot.png"
    # one launch dumps the DOM and takes the screenshot of the same page at the end of its virtual time (a
    # second launch for the picture cost about a second of CPU)
    dom, log = browse_until(
        chromium,
        tmp_path / "profile-dom",
        url,
        lambda d: len(re.findall(r'data-duration="', d)) == len(SCENARIOS),
        "--enable-logging=stderr",
        "--v=0",
        "--window-size=1280,1600",
        f"--screenshot={shot}",
    )
    assert 'data-ready="true"' in dom, "the page finished loading"
    assert re.search(r'<pre id="load-errors"[^>]*hidden[^>]*></pre>', dom), "no resource failed to load"
    durations = [float(d) for d in re.findall(r'data-duration="([^"]+)"', dom)]
    assert len(durations) == len(SCENARIOS)
    np.testing.assert_allclose(durations, CLIP_SECONDS, atol=0.05)  # non-zero and the clip's length
    loaded = re.findall(r'data-loaded="(\w+)"', dom)
    assert loaded and set(loaded) == {"true"}, "every image decoded"
    console_errors = [
        line for line in log.splitlines() if "CONSOLE" in line and re.search(r"Uncaught|Error|error", line)
    ]
    assert not console_errors, console_errors

    from PIL import Image

    with Image.open(shot) as image:
        assert image.size == (1280, 1600)
        pixels = np.asarray(image.convert("RGB"), dtype=float)
    assert pixels.std() > 20, "the screenshot shows a page, not a blank"


@pytest.mark.slow
def test_chromium_decodes_the_h264_videos_to_the_rendered_pictures(demo_out, tmp_path):
    """Debian's chromium could lack H.264; draw each video's first frame to a canvas to be sure it decodes."""
    chromium = find_chromium()
    out, state = demo_out
    videos = [a.path for a in state.artifacts if a.kind == "video"]
    probe = out / "probe.html"
    probe.write_text(
        "<!doctype html><body><pre id='r'></pre><script>\n"
        "const r = document.getElementById('r'); const done = [];\n"
        f"for (const src of {videos!r}) {{\n"
        "  const v = document.createElement('video'); v.muted = true; v.preload = 'auto';\n"
        # on a loaded machine 'loadeddata' can fire before the decoded frame reaches the canvas (all
        # zeros, not even alpha): draw again a few times before taking the frame for what it shows
        "  const draw = (tries) => {\n"
        "    const c = document.createElement('canvas'); c.width = v.videoWidth; c.height = v.videoHeight;\n"
        "    const g = c.getContext('2d'); g.drawImage(v, 0, 0);\n"
        "    const d = g.getImageData(0, 0, c.width, c.height).data; let s = 0, a = 0;\n"
        "    for (let i = 0; i < d.length; i += 4) { s += (d[i] + d[i + 1] + d[i + 2]) / 3; a += d[i + 3]; }\n"
        "    if (a === 0 && tries > 0) { setTimeout(() => draw(tries - 1), 200); return; }\n"
        "    done.push(src + ' ' + (s / (d.length / 4)).toFixed(1)); r.textContent = done.join('\\n'); };\n"
        "  v.addEventListener('loadeddata', () => draw(25));\n"
        "  v.addEventListener('error', () => { done.push(src + ' error'); r.textContent = done.join('\\n'); });\n"
        "  v.src = src; document.body.appendChild(v); }\n"
        "</script></body>"
    )
    try:
        dom, _ = browse_until(
            chromium,
            tmp_path / "profile-probe",
            probe.as_uri(),
            lambda d: len(re.findall(r"\.mp4 ", d)) == len(videos),
            "--allow-file-access-from-files",
        )
    finally:
        probe.unlink()
    means = dict(re.findall(r"([\w/]+\.mp4) ([\d.]+|error)", dom))
    assert set(means) == set(videos), dom[-500:]
    for src, mean in means.items():
        # the first frame is the light 3D scene beside the white phase panel: bright, not black
        assert mean != "error" and float(mean) > 150, (src, mean)


def test_report_reads_like_the_chapter(demo_out):
    import html as html_module

    out, state = demo_out
    page = (out / "index.html").read_text()
    for (scene_name, scenario), result in state.results.items():
        assert result.answer is not None, f"{scene_name}/{scenario} states its question and answer"
        question, answer = result.answer.question, result.answer.answer
        assert question and answer, f"{scene_name}/{scenario} states its question and answer"
        assert html_module.escape(question) in page and html_module.escape(answer) in page
        for name in result.parameters:  # every parameter listed, with its value
            assert f"<code>{name}</code> = " in page
    # the count the CLI prints: every artifact, this report included
    assert f"{len(state.artifacts)} files, this page included" in page
    # each tolerance basis is one footnote, however many rows and checks share it
    notes = re.findall(r"<li id='basis-\d+'>(.*?)</li>", page)
    assert notes and len(notes) == len(set(notes))
    assert "the demo's own steps, not physics time steps" in page


@pytest.mark.slow
def test_every_scenario_states_its_question_and_an_answer_from_its_own_run(scenario_run):
    from springlab import scenes

    for scene in scenes.SCENES.values():
        for scenario in scene.scenarios:
            result = scenario_run(scene.name, scenario)
            answer = result.answer
            assert answer is not None and answer.question.strip() and answer.answer.strip(), f"{scene.name}/{scenario}"
            assert "{" not in answer.answer and "nan" not in answer.answer.split(), f"{scene.name}/{scenario}"
