"""The demo's report: out/index.html, one self-contained page that opens from disk.

No external resources: CSS and a few lines of script are inline, images and
videos are relative links into the output folder. It shows

* the demo's wall time and the time of each step,
* the validation table (error, tolerance, pass/fail, the scalar checks),
* per scene and scenario: the videos (<video>), the plots (<img>), the
  scenario's quantities, and links to every other file,
* artifacts that belong to no scene (trade-off charts, ...) in their own section,
* an index of every artifact any demo step returned, by kind, with a link.

It knows no particular step: artifacts are laid out by their kind
('video' is embedded as <video>, 'plot' with an image extension as <img>,
anything else is a link), scene and scenario.

The inline script writes each video's duration next to it once its metadata
has loaded (data-duration on the <video>) and records resources that failed to
load in #load-errors, so a headless browser can check the page.
"""

from __future__ import annotations

import datetime
import html
import math
import pathlib
from collections.abc import Iterable
from typing import Any

from springlab import files, scenes
from springlab.runs.compare import Verdict
from springlab.runs.run import ValidationRow

from .state import DemoState

IMAGE_SUFFIXES = (".png", ".svg", ".jpg", ".jpeg", ".gif", ".webp")
VIDEO_SUFFIXES = (".mp4", ".webm")
KIND_ORDER = ("video", "plot", "data", "report")

_CSS = """
body { font-family: system-ui, -apple-system, 'Segoe UI', sans-serif; margin: 0 auto; max-width: 1280px;
       padding: 0 1.2em 3em; color: #1d1d22; line-height: 1.4; }
h1 { margin-bottom: 0.1em; } h2 { border-bottom: 2px solid #d8d8e0; padding-bottom: 0.2em; margin-top: 2em; }
h3 { margin-bottom: 0.3em; } .muted { color: #666; } code { font-size: 0.92em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.9em; }
th, td { border: 1px solid #d0d0d8; padding: 0.25em 0.55em; text-align: left; vertical-align: top; }
th { background: #f1f1f5; } td.num { text-align: right; font-variant-numeric: tabular-nums; }
.pass { color: #0a7a2f; font-weight: 600; } .fail { color: #b3141b; font-weight: 700; }
.check td { font-size: 0.88em; color: #444; }
.media { display: flex; flex-wrap: wrap; gap: 12px; align-items: flex-start; margin: 0.4em 0; }
.plots { display: grid; grid-template-columns: repeat(auto-fill, minmax(400px, 1fr)); gap: 12px; margin: 0.4em 0; }
figure { margin: 0; } figcaption { font-size: 0.85em; color: #555; max-width: 640px; }
video { max-width: 100%; background: #fff; border: 1px solid #ccc; }
img.plot { width: 100%; border: 1px solid #e0e0e6; }
details { margin: 0.3em 0 0.8em; } summary { cursor: pointer; color: #335; }
nav a { margin-right: 0.8em; }
p.question { background: #f5f7fb; border-left: 3px solid #6b8bd6; padding: 0.4em 0.7em; margin: 0.4em 0; }
p.params { font-size: 0.88em; color: #444; }
"""

_SCRIPT = """
(function () {
  var failed = [];
  function note(what) {
    failed.push(what);
    var box = document.getElementById('load-errors');
    if (box) { box.textContent = failed.join('\\n'); box.hidden = false; }
  }
  window.addEventListener('error', function (event) {
    var t = event.target;
    if (t && t !== window && (t.src || t.currentSrc)) { note('could not load ' + (t.currentSrc || t.src)); }
    else if (event.message) { note('script error: ' + event.message); }
  }, true);
  document.querySelectorAll('video').forEach(function (video) {
    function show() {
      video.setAttribute('data-duration', String(video.duration));
      var label = document.getElementById(video.id + '-duration');
      if (label) { label.textContent = video.duration.toFixed(2) + ' s, ' + video.videoWidth + 'x' + video.videoHeight; }
    }
    if (video.readyState >= 1) { show(); } else { video.addEventListener('loadedmetadata', show); }
    video.addEventListener('error', function () { note('could not play ' + video.currentSrc); });
  });
  window.addEventListener('load', function () {
    document.querySelectorAll('img').forEach(function (img) {
      img.setAttribute('data-loaded', String(img.complete && img.naturalWidth > 0));
      if (!(img.complete && img.naturalWidth > 0)) { note('could not load ' + img.src); }
    });
    document.body.setAttribute('data-ready', 'true');
  });
})();
"""


def _e(value: Any) -> str:
    return html.escape(str(value), quote=True)


def _number(value: Any, spec: str = ".2e") -> str:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return format(value, spec) if math.isfinite(value) else str(value)
    return _e(value)


def _verdict(passed: bool | None, verdict: Verdict | None = None) -> str:
    if passed is None:
        return '<span class="muted">n/a</span>'
    if not passed and verdict is Verdict.NOT_VALIDATED:
        return '<span class="fail">not validated</span>'
    return '<span class="pass">pass</span>' if passed else '<span class="fail">FAIL</span>'


def _is_image(path: str) -> bool:
    return pathlib.PurePosixPath(path).suffix.lower() in IMAGE_SUFFIXES


def _is_video(path: str) -> bool:
    return pathlib.PurePosixPath(path).suffix.lower() in VIDEO_SUFFIXES


def _href(path: str) -> str:
    return _e(pathlib.PurePath(path).as_posix())


def _validation_table(rows: list[ValidationRow]) -> str:
    if not rows:
        return "<p class='muted'>No validated scenarios.</p>"
    notes: dict[str, int] = {}  # tolerance basis -> footnote number (most rows share one)

    def note(basis: str) -> str:
        if not basis:
            return ""
        number = notes.setdefault(basis, len(notes) + 1)
        return f"<a href='#basis-{number}'>[{number}]</a>"

    out = [
        "<table><tr><th>scene</th><th>scenario</th><th>integrator</th><th>dt [s]</th><th>steps</th>"
        "<th>error of</th><th>error</th><th>tolerance</th><th>result</th><th>basis</th></tr>"
    ]
    for r in rows:
        checks = {c.name for c in r.checks}
        basis = r.note or r.tolerance_basis
        head, _, tail = basis.partition(": ")
        if head in checks and tail:  # "period_s: <the check's basis>": one footnote, not two
            basis = tail
        out.append(
            f"<tr><td>{_e(r.scene)}</td><td><a href='#{_e(r.scene)}-{_e(r.scenario)}'>"
            f"{_e(r.scenario)}</a></td><td>{_e(r.integrator)}</td><td class='num'>{_number(r.dt, 'g')}</td>"
            f"<td class='num'>{_e(r.steps)}</td><td>{_e(r.measure)}</td>"
            f"<td class='num'>{_number(r.max_rel_error)}</td>"
            f"<td class='num'>{_number(r.tolerance)}</td><td>{_verdict(r.passed, r.verdict)}</td>"
            f"<td>{note(basis)}</td></tr>"
        )
        for c in r.checks:
            out.append(
                f"<tr class='check'><td></td><td colspan='5'>check <code>{_e(c.name)}</code>: "
                f"{_number(float(c.value), '.10g')} against {_number(float(c.reference), '.10g')}</td>"
                f"<td class='num'>{_number(c.error)}</td><td class='num'>{_number(float(c.tolerance))}</td>"
                f"<td>{_verdict(c.passed)}</td><td>{note(c.basis)}</td></tr>"
            )
    out.append("</table>")
    failed = sum(not r.passed for r in rows)
    out.append(
        f"<p>{len(rows) - failed} passed, {failed} failed. Errors are max |MuJoCo - exact| / max |exact|"
        f" over the run (for checks: relative error of the value, absolute where the reference is 0).</p>"
    )
    out.append(
        "<ol class='muted'>" + "".join(f"<li id='basis-{n}'>{_e(basis)}</li>" for basis, n in notes.items()) + "</ol>"
    )
    return "\n".join(out)


class _Ids:
    def __init__(self):
        self.count = 0

    def next(self) -> str:
        self.count += 1
        return f"video-{self.count}"


def _media(artifacts: Iterable, ids: _Ids) -> tuple[str, list]:
    """(HTML of the embedded videos and images, the remaining artifacts to link)."""
    blocks, images, rest = [], [], []
    for a in artifacts:
        if a.kind == "video" and _is_video(a.path):
            vid = ids.next()
            kind = "video/webm" if a.path.lower().endswith(".webm") else "video/mp4"
            blocks.append(
                f"<figure><video id='{vid}' controls muted loop playsinline preload='metadata'>"
                f"<source src='{_href(a.path)}' type='{kind}'></video><figcaption>{_e(a.title)} "
                f"(<span id='{vid}-duration'>loading</span>) <a href='{_href(a.path)}'>"
                f"{_e(pathlib.PurePath(a.path).name)}</a></figcaption></figure>"
            )
        elif _is_image(a.path) and a.kind in ("plot", "video"):
            images.append(
                f"<figure><a href='{_href(a.path)}'><img class='plot' src='{_href(a.path)}' "
                f"alt='{_e(a.title)}' loading='lazy'></a><figcaption>{_e(a.title)}</figcaption></figure>"
            )
        else:
            rest.append(a)
    html_text = f"<div class='media'>{''.join(blocks)}</div>" if blocks else ""
    if images:
        html_text += f"<div class='plots'>{''.join(images)}</div>"
    return html_text, rest


def _links(artifacts: list) -> str:
    if not artifacts:
        return ""
    items = "".join(
        f"<li><a href='{_href(a.path)}'>{_e(pathlib.PurePath(a.path).name)}</a> "
        f"<span class='muted'>({_e(a.kind)})</span> {_e(a.title)}</li>"
        for a in artifacts
    )
    return f"<ul>{items}</ul>"


def _quantities(quantities: dict[str, Any]) -> str:
    if not quantities:
        return ""
    rows = "".join(
        f"<tr><td><code>{_e(k)}</code></td><td class='num'>"
        f"{_number(v, '.8g') if isinstance(v, (int, float)) else _e(v)}</td></tr>"
        for k, v in quantities.items()
        if isinstance(v, (int, float, str, bool))
    )
    return f"<details><summary>quantities</summary><table>{rows}</table></details>" if rows else ""


def _question(result) -> str:
    """The scenario's question and the run's answer: the run's own Answer, the sentence its terminal and JSON carry."""
    answer = getattr(result, "answer", None)
    if answer is None:
        return ""
    text = f"<p class='question'><b>Question.</b> {_e(answer.question)}"
    if answer.answer:
        text += f"<br><b>Answer.</b> {_e(answer.answer)}"
    return text + "</p>"


def _answer(artifact) -> str:
    """A study's question (the artifact's title) and its answer, one paragraph per line of the answer."""
    lines = "".join(f"<br>{_e(line)}" for line in artifact.answer.splitlines() if line.strip())
    return f"<p class='question'><b>Question.</b> {_e(artifact.title)}<br><b>Answer.</b>{lines}</p>"


def _parameters(scene, result) -> str:
    """The run's parameters with their units, on one line."""
    if result is None or not result.parameters:
        return ""
    units = {name: p.unit for name, p in getattr(scene, "parameters", {}).items()}
    items = []
    for name, value in result.parameters.items():
        unit = units.get(name, "")
        unit = "" if unit in ("", "-") else f" {unit}"
        shown = _number(value, ".4g") if isinstance(value, (int, float)) else _e(value)
        items.append(f"<code>{_e(name)}</code> = {shown}{_e(unit)}")
    return f"<p class='params'><b>Parameters:</b> {', '.join(items)}</p>"


def build_html(state: DemoState, *, wall_time_s: float | None = None) -> str:
    """The report page for a finished demo state (validation rows, results, artifacts)."""
    ids = _Ids()
    artifacts = list(state.artifacts)
    scene_names = list(dict.fromkeys([a.scene for a in artifacts if a.scene] + [scene for scene, _ in state.results]))
    body = []
    nav = " ".join(f"<a href='#{_e(name)}'>{_e(name)}</a>" for name in scene_names)
    if any(not a.scene for a in artifacts):
        nav += " <a href='#across-scenes'>across scenes</a>"
    nav += " <a href='#all-files'>all files</a>"
    now = datetime.datetime.now().astimezone().strftime("%Y-%m-%d %H:%M %Z")
    timing = f"; demo wall time {wall_time_s:.1f} s" if wall_time_s is not None else ""
    # the count the CLI prints ("wrote N files"): the artifacts so far plus this report itself
    body.append(
        f"<h1>springlab demo report</h1><p class='muted'>generated {_e(now)}{_e(timing)};"
        f" {len(artifacts) + 1} files, this page included</p><nav>{nav}</nav>"
    )
    body.append("<pre id='load-errors' class='fail' hidden></pre>")
    body.append("<h2 id='validation'>Validation against the exact solutions</h2>")
    body.append(_validation_table(state.validation))
    if getattr(state, "timings", None):
        rows = "".join(
            f"<tr><td>{_e(name)}</td><td class='num'>{seconds:.1f}</td></tr>" for name, seconds in state.timings
        )
        body.append(
            "<details><summary>wall time of each step of the demo [s] (the demo's own steps, not physics"
            f" time steps)</summary><table><tr><th>demo step</th><th>wall time [s]</th></tr>{rows}</table></details>"
        )

    for name in scene_names:
        scene = scenes.SCENES.get(name)
        title = scene.title if scene is not None else ""
        body.append(f"<h2 id='{_e(name)}'>{_e(name)}</h2><p>{_e(title)}</p>")
        own = [a for a in artifacts if a.scene == name]
        scenario_names = list(
            dict.fromkeys(
                [s for scene_name, s in state.results if scene_name == name] + [a.scenario for a in own if a.scenario]
            )
        )
        for scenario_name in scenario_names:
            items = [a for a in own if a.scenario == scenario_name]
            description = ""
            if scene is not None and scenario_name in scene.scenarios:
                description = scene.scenarios[scenario_name].description
            result = state.results.get((name, scenario_name))
            verdict = ""
            if result is not None and result.passed is not None:
                verdict = " " + _verdict(result.passed, result.verdict)
            body.append(
                f"<h3 id='{_e(name)}-{_e(scenario_name)}'>{_e(name)} / {_e(scenario_name)}{verdict}</h3>"
                f"<p class='muted'>{_e(description)}</p>"
            )
            body.append(_question(result))
            if scene is not None:
                body.append(_parameters(scene, result))
            media, rest = _media(sorted(items, key=_kind_rank), ids)
            body.append(media)
            if result is not None:
                body.append(_quantities(result.quantities))
            body.append(_links(rest))
        general = [a for a in own if not a.scenario]
        if general:
            media, rest = _media(sorted(general, key=_kind_rank), ids)
            answers = "".join(_answer(a) for a in general if a.answer)
            body.append(f"<h3>{_e(name)}: all scenarios</h3>{answers}{media}{_links(rest)}")

    shared = [a for a in artifacts if not a.scene]
    if shared:
        media, rest = _media(sorted(shared, key=_kind_rank), ids)
        body.append(f"<h2 id='across-scenes'>Across scenes</h2>{media}{_links(rest)}")

    body.append(
        "<h2 id='all-files'>All files</h2><table><tr><th>kind</th><th>scene</th><th>scenario</th>"
        "<th>what</th><th>file</th></tr>"
    )
    for a in sorted(artifacts, key=lambda a: (_kind_rank(a), a.scene, a.scenario, a.path)):
        body.append(
            f"<tr><td>{_e(a.kind)}</td><td>{_e(a.scene)}</td><td>{_e(a.scenario)}</td><td>{_e(a.title)}</td>"
            f"<td><a href='{_href(a.path)}'>{_e(a.path)}</a></td></tr>"
        )
    body.append("</table>")
    return (
        "<!doctype html>\n<html lang='en'><head><meta charset='utf-8'>"
        "<meta name='viewport' content='width=device-width, initial-scale=1'>"
        f"<title>springlab demo report</title><style>{_CSS}</style></head>\n<body>\n"
        + "\n".join(part for part in body if part)
        + f"\n<script>{_SCRIPT}</script>\n</body></html>\n"
    )


def _kind_rank(artifact) -> int:
    """Videos first, then plots, data, reports, other kinds; a stable sort keeps the steps' order."""
    return KIND_ORDER.index(artifact.kind) if artifact.kind in KIND_ORDER else len(KIND_ORDER)


def write_report(state: DemoState, *, wall_time_s: float | None = None) -> pathlib.Path:
    """Write state.out/index.html atomically; return its path."""
    files.write_text_files(state.out, {"index.html": build_html(state, wall_time_s=wall_time_s)})
    return state.out / "index.html"
