"""`springlab interactive`: a scenario as a web page that runs real MuJoCo in the browser.

The page is the textbook's interactive figure: sliders for the mass, the stiffness and the damping
ratio, the timestep (log scale) and MuJoCo's integrator; every move recompiles the scene's MJCF in
MuJoCo's WebAssembly build, steps it, and redraws x(t), the phase plane and the 3D scene beside the
exact solution, with the error and springlab's verdict (web/exact.js ports the closed form, the
tolerance and the range of the error estimate). The page writes the parameters into the MJCF text
(`InteractiveSpec.edits`, the same values `Scene.edit` sets through MjSpec) rather than into the
compiled model's arrays, so it steps the model springlab's Python run steps: the initial settings
agree with `springlab run` to the last digit (tests/render/test_interactive.py).

MuJoCo's WebAssembly build is the npm package `mujoco-js`, pinned (MUJOCO_JS_VERSION) and checked
against MUJOCO_JS_SHA256, fetched once with `npm pack` into the user's cache folder (never by the
reader's browser). It is published as an ES module with the WebAssembly inlined as base64; Chromium
refuses module scripts from file://, so the build turns it into a classic script (two lines change)
and drops the WebAssembly's custom sections (names and debug information: 8.0 of 10.7 MB of base64,
no code), which leaves the numbers unchanged. Its Apache-2.0 notice is written beside the page.
"""

from __future__ import annotations

import base64
import dataclasses
import hashlib
import io
import json
import os
import pathlib
import re
import shutil
import subprocess
import tarfile
import tempfile

import mujoco

from springlab import files, scenes
from springlab.errors import BadInputError, SpringlabError
from springlab.scenes.base import Scenario, Scene
from springlab.sim import model_files

from .drawings import COIL_RADIUS, DAMPER_PREFIX, SPRING_PREFIX

#: the npm package of MuJoCo's WebAssembly build, its pinned version and its tarball's SHA-256
MUJOCO_JS_PACKAGE = "mujoco-js"
MUJOCO_JS_VERSION = "0.0.7"
MUJOCO_JS_SHA256 = "ee7443760feb69a8871b90fbab6b362ec45a71f777d1fb447c479456d46722d4"
#: the MuJoCo release that mujoco-js 0.0.7 wraps (its README and wasm say so; Python springlab runs 4.0)
MUJOCO_JS_MUJOCO = "3.3.8"
#: the script, the ported formulas and the page's own script, as the output folder holds them
MUJOCO_SCRIPT = f"mujoco-js-{MUJOCO_JS_VERSION}.js"
LICENSE_FILE = "LICENSE-mujoco-js.txt"
_WEB = pathlib.Path(__file__).with_name("web")
_ASSETS = ("springlab-exact.js", "springlab-interactive.js", "springlab-interactive.css")
_SOURCES = {
    "springlab-exact.js": "exact.js",
    "springlab-interactive.js": "page.js",
    "springlab-interactive.css": "page.css",
}
#: the dt slider's range [s] (log scale): from a fine RK4 step to past every integrator's stability limit
DT_RANGE = (1e-4, 0.5)


class NodeUnavailableError(SpringlabError):
    """npm is not on PATH, or `npm pack` failed, and mujoco-js is not in the cache (exit 2)."""


@dataclasses.dataclass(frozen=True)
class InteractivePage:
    """A written interactive page.

    Attributes
    ----------
    scene, scenario
        what it shows.
    path
        the HTML file.
    files
        every file written for it (the page, the scripts, the licence notice).
    size_bytes
        the bytes a reader's browser loads for it (page, scripts, stylesheet).
    """

    scene: str
    scenario: str
    path: pathlib.Path
    files: tuple[pathlib.Path, ...]
    size_bytes: int

    def to_dict(self) -> dict:
        """{scene, scenario, path, files, size_bytes}: what `springlab interactive --json` prints."""
        return {
            "scene": self.scene,
            "scenario": self.scenario,
            "path": str(self.path),
            "files": [str(p) for p in self.files],
            "size_bytes": self.size_bytes,
        }


def interactive_scenes() -> dict[str, tuple[str, ...]]:
    """scene name -> the scenarios that run in the browser, for every scene that declares some."""
    return {name: scene.interactive.scenarios for name, scene in scenes.SCENES.items() if scene.interactive}


def cache_directory() -> pathlib.Path:
    """Where the npm tarball and the prepared script are kept: $XDG_CACHE_HOME/springlab (~/.cache/springlab)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(pathlib.Path.home() / ".cache")
    return pathlib.Path(base) / "springlab"


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _tarball(cache: pathlib.Path) -> bytes:
    """The pinned mujoco-js tarball, from the cache or `npm pack`; its SHA-256 checked either way."""
    target = cache / f"{MUJOCO_JS_PACKAGE}-{MUJOCO_JS_VERSION}.tgz"
    if target.is_file():
        data = target.read_bytes()
        if _sha256(data) == MUJOCO_JS_SHA256:
            return data
        target.unlink()  # a damaged or foreign file: fetch it again
    npm = shutil.which("npm")
    if npm is None:
        raise NodeUnavailableError(
            f"the interactive page needs {MUJOCO_JS_PACKAGE} {MUJOCO_JS_VERSION} from npm, and npm is not on PATH"
            f" (install Node.js, or put {target.name} into {cache})"
        )
    cache.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=cache) as folder:
        done = subprocess.run(
            [npm, "pack", f"{MUJOCO_JS_PACKAGE}@{MUJOCO_JS_VERSION}", "--pack-destination", folder, "--silent"],
            capture_output=True,
            text=True,
            cwd=folder,
            timeout=600,
        )
        packed = pathlib.Path(folder) / target.name
        if done.returncode != 0 or not packed.is_file():
            reason = (done.stderr.strip().splitlines() or ["no tarball written"])[-1]
            raise NodeUnavailableError(f"npm pack {MUJOCO_JS_PACKAGE}@{MUJOCO_JS_VERSION} failed: {reason}")
        data = packed.read_bytes()
        if _sha256(data) != MUJOCO_JS_SHA256:
            raise NodeUnavailableError(
                f"npm pack {MUJOCO_JS_PACKAGE}@{MUJOCO_JS_VERSION} gave a tarball whose SHA-256 is {_sha256(data)},"
                f" not the pinned {MUJOCO_JS_SHA256}: refusing it"
            )
        os.replace(packed, target)
    return data


def _leb128(data: bytes, at: int) -> tuple[int, int]:
    """(unsigned LEB128 value, the offset after it)."""
    value, shift = 0, 0
    while True:
        byte = data[at]
        at += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if byte < 0x80:
            return value, at


def strip_custom_sections(wasm: bytes) -> bytes:
    """A WebAssembly binary without its custom sections (id 0: names, debug information).

    Custom sections carry no code or data the module runs (WebAssembly core spec, 5.5.3), so the
    stripped module computes what the original does.
    """
    if wasm[:4] != b"\0asm":
        raise ValueError("not a WebAssembly binary")
    out = bytearray(wasm[:8])
    at = 8
    while at < len(wasm):
        section = wasm[at]
        size, body = _leb128(wasm, at + 1)
        end = body + size
        if section != 0:
            out += wasm[at:end]
        at = end
    return bytes(out)


def classic_script(module_text: str) -> str:
    """mujoco-js's ES module as a classic script defining `loadMujoco`, its WebAssembly stripped."""
    text = module_text.replace(
        "import.meta.url",
        "(typeof document != 'undefined' && document.currentScript ? document.currentScript.src : '')",
    )
    if "\nexport default loadMujoco;" not in text or "import.meta" in text:
        raise ValueError("mujoco-js is not the module this build knows how to load as a classic script")
    text = text.replace("\nexport default loadMujoco;", "\n")

    def stripped(match: re.Match) -> str:
        wasm = strip_custom_sections(base64.b64decode(match.group(1)))
        return f"base64Decode('{base64.b64encode(wasm).decode()}')"

    text, count = re.subn(r"base64Decode\('([A-Za-z0-9+/=]+)'\)", stripped, text, count=1)
    if count != 1:
        raise ValueError("mujoco-js does not inline its WebAssembly as this build expects")
    return text


def mujoco_script(cache: pathlib.Path | None = None) -> tuple[str, str]:
    """(the classic script of the pinned mujoco-js, its licence notice), prepared once and cached.

    Raises
    ------
    NodeUnavailableError
        npm is missing or failed and nothing is cached.
    """
    cache = cache_directory() if cache is None else cache
    prepared = cache / f"{MUJOCO_JS_PACKAGE}-{MUJOCO_JS_VERSION}-{MUJOCO_JS_SHA256[:12]}.classic.js"
    if prepared.is_file():
        return prepared.read_text(encoding="utf-8"), _notice()
    with tarfile.open(fileobj=io.BytesIO(_tarball(cache)), mode="r:gz") as archive:
        member = archive.extractfile("package/dist/mujoco_wasm.js")
        assert member is not None, "the pinned tarball holds package/dist/mujoco_wasm.js"
        text = classic_script(member.read().decode("utf-8"))
    prepared.parent.mkdir(parents=True, exist_ok=True)
    with files.atomic_path(prepared) as temporary:
        temporary.write_text(text, encoding="utf-8")
    return text, _notice()


def _notice() -> str:
    return (
        f"{MUJOCO_SCRIPT} is the npm package {MUJOCO_JS_PACKAGE} {MUJOCO_JS_VERSION} (MuJoCo {MUJOCO_JS_MUJOCO}"
        " compiled to WebAssembly), Copyright Google DeepMind, licensed under the Apache License, Version 2.0\n"
        "(the License); you may not use this file except in compliance with the License. You may obtain a copy\n"
        "of the License at https://www.apache.org/licenses/LICENSE-2.0. Unless required by applicable law or\n"
        "agreed to in writing, software distributed under the License is distributed on an AS IS BASIS, WITHOUT\n"
        "WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.\n\n"
        "Changes made by springlab (springlab.render.interactive): the ES module is loaded as a classic script\n"
        "(`import.meta.url` replaced by the script's own URL, `export default` removed), and the inlined\n"
        "WebAssembly's custom sections (function names, debug information) are removed. The code is otherwise\n"
        f"the published file, whose tarball has SHA-256 {MUJOCO_JS_SHA256}.\n"
    )


def _pictures(model: mujoco.MjModel, prefix: str) -> list[dict]:
    """The drawn springs or dampers the MJCF declares (springlab.render.drawings), as the page draws them."""
    out = []
    for i in range(model.ntext):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_TEXT, i) or ""
        if not name.startswith(prefix):
            continue
        start = model.text_adr[i]
        first, second, size, *rest = bytes(model.text_data[start : start + model.text_size[i] - 1]).decode().split()
        out.append(
            {
                "a": model.site(first).id,
                "b": model.site(second).id,
                "size": float(size),
                "rgba": [float(c) for c in rest[:4]],
                "offset": [float(c) for c in rest[4:7]] if len(rest) >= 7 else [0.0, 0.0, 0.0],
            }
        )
    return out


def _choose(scene_name: str, scenario_name: str | None) -> tuple[Scene, Scenario]:
    scene = scenes.get(scene_name)
    spec = scene.interactive
    if spec is None:
        raise BadInputError(
            f"{scene.name} has no interactive page (it declares no Scene.interactive); scenarios that have one:"
            f" {_pages_named()}"
        )
    name = spec.scenarios[0] if scenario_name is None else scenario_name
    scenario = scene.scenario(name)  # a name the scene does not know: the scene's own 'unknown scenario' line
    if name not in spec.scenarios:
        # a known scenario without a page is not 'unknown': say so, and where the pages are
        raise BadInputError(f"{scene.name} / {name} has no interactive page; scenarios that have one: {_pages_named()}")
    return scene, scenario


def _pages_named() -> str:
    """'car: push_release, ...; slider: free, step': every scene's scenarios that run in the browser."""
    return "; ".join(f"{scene}: {', '.join(names)}" for scene, names in sorted(interactive_scenes().items()))


def page_config(scene_name: str, scenario_name: str | None = None) -> dict:
    """What the page needs, as the JSON it embeds: the MJCF text, the edits, addresses, initial settings.

    Parameters
    ----------
    scene_name, scenario_name
        the scene and one of its `InteractiveSpec.scenarios` (None: the first).

    Raises
    ------
    BadInputError
        the scene declares no interactive page, or the scenario does not run in the browser.
    """
    scene, scenario = _choose(scene_name, scenario_name)
    spec = scene.interactive
    assert spec is not None
    case = scene.case(scenario)
    params, model = case.params, case.model
    joint = model.joint(spec.joint)
    question = scene.questions.get(scenario.name, ("", ""))[0]
    camera = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, scene.camera) if scene.camera else -1
    return {
        "scene": scene.name,
        "scenario": scenario.name,
        "title": scene.title,
        "description": scenario.description,
        "question": question,
        "mjcf": model_files.path(scene.name).read_text(encoding="utf-8"),
        "edits": [dataclasses.asdict(edit) for edit in spec.edits],
        "names": {"mass": spec.mass, "stiffness": spec.stiffness, "damping": spec.damping},
        "formulas": {"x0": spec.x0, "v0": spec.v0, "force": spec.force, "rest": spec.rest},
        "ranges": {name: list(bounds) for name, bounds in spec.ranges.items()},
        "g": -float(model.opt.gravity[2]),
        "parameters": params,
        "qposadr": int(joint.qposadr[0]),
        "dofadr": int(joint.dofadr[0]),
        "actuator": int(model.actuator(spec.actuator).id) if spec.actuator else -1,
        "integrator": scene.setting(scenario)[0],
        "dt": float(scene.setting(scenario)[1]),
        "duration": float(scenario.duration),
        "dtRange": list(DT_RANGE),
        "camera": int(camera),
        "springs": _pictures(model, SPRING_PREFIX),
        "dampers": _pictures(model, DAMPER_PREFIX),
        "coilRadius": COIL_RADIUS,
        "mujocoJs": {"package": MUJOCO_JS_PACKAGE, "version": MUJOCO_JS_VERSION, "mujoco": MUJOCO_JS_MUJOCO},
    }


def page_html(config: dict) -> str:
    """The page for a config (`page_config`): controls, canvases, #result, and the scripts beside it."""
    data = json.dumps(config, allow_nan=False).replace("</", "<\\/")
    title = f"springlab: {config['scene']} / {config['scenario']} with MuJoCo in the browser"
    esc = _escape
    links = " ".join(
        f"<a href='{esc(config['scene'])}-{esc(name)}.html'>{esc(name)}</a>" for name in config.get("linked", [])
    )
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width, initial-scale=1">
<title>{esc(title)}</title><link rel="stylesheet" href="springlab-interactive.css"></head>
<body>
<header><h1>{esc(config["scene"])} / {esc(config["scenario"])}</h1>
<p class="muted">{esc(config["title"])}: {esc(config["description"])}</p>
<p class="question">{esc(config["question"])}</p>
{f'<p class="muted">other scenarios: {links}</p>' if links else ""}</header>
<p id="status">loading MuJoCo {esc(config["mujocoJs"]["mujoco"])} (WebAssembly)…</p>
<section id="controls" aria-label="settings"></section>
<p id="result" role="status" aria-live="polite"></p>
<section id="views">
<figure><canvas id="scene3d" width="560" height="300"></canvas><figcaption>the model's own geoms, springs drawn as in the videos; <button id="play" type="button">play</button></figcaption></figure>
<figure><canvas id="xt" width="560" height="300"></canvas><figcaption>x(t): MuJoCo (solid) and exact (dashed)</figcaption></figure>
<figure><canvas id="phase" width="360" height="300"></canvas><figcaption>phase plane (x, v)</figcaption></figure>
<figure><canvas id="error" width="560" height="200"></canvas><figcaption>|x − x<sub>exact</sub>| (log scale) and the tolerance × max|x|</figcaption></figure>
</section>
<table id="numbers"></table>
<footer class="muted"><p>Each move recompiles the scene's MJCF (models/{esc(config["scene"])}.xml with the same edits
springlab makes in Python) and steps it with MuJoCo {esc(config["mujocoJs"]["mujoco"])} compiled to WebAssembly
(npm {esc(config["mujocoJs"]["package"])} {esc(config["mujocoJs"]["version"])}); the exact solution, the tolerance and the
verdict are springlab's (springlab run {esc(config["scene"])} {esc(config["scenario"])} gives the same numbers).
MuJoCo: Apache-2.0, see <a href="{LICENSE_FILE}">{LICENSE_FILE}</a>. Made by springlab interactive.</p></footer>
<script type="application/json" id="springlab-config">{data}</script>
<script src="{MUJOCO_SCRIPT}"></script>
<script src="springlab-exact.js"></script>
<script src="springlab-interactive.js"></script>
</body></html>
"""


def _escape(value: object) -> str:
    import html

    return html.escape(str(value), quote=True)


def write_interactive(
    scene: str, scenario: str | None, output: str | os.PathLike, *, cache: pathlib.Path | None = None
) -> tuple[InteractivePage, ...]:
    """Write `<scene>-<scenario>.html` and the files it loads into the folder `output`.

    Parameters
    ----------
    scene, scenario
        the scene and one of the scenarios it runs in the browser (None: every one of them, each page
        linking to the others).
    output
        the folder (created; the pages share their scripts).
    cache
        where the npm tarball and the prepared script are kept (None: `cache_directory()`).

    Returns
    -------
    tuple[InteractivePage, ...]
        the pages written, the named (or first) scenario's first.

    Raises
    ------
    BadInputError
        the scene or scenario does not run in the browser, or the folder cannot be written.
    NodeUnavailableError
        mujoco-js is not cached and npm is missing or failed.
    """
    if scenario is None:
        _choose(scene, None)
        chosen = list(scenes.get(scene).interactive.scenarios)  # type: ignore[union-attr]
    else:
        chosen = [_choose(scene, scenario)[1].name]
    configs = [page_config(scene, name) for name in chosen]
    folder = files.check_directory(output)
    script, notice = mujoco_script(cache)
    texts = {MUJOCO_SCRIPT: script, LICENSE_FILE: notice}
    for asset in _ASSETS:
        texts[asset] = (_WEB / _SOURCES[asset]).read_text(encoding="utf-8")
    names = []
    for config in configs:
        config["linked"] = [other for other in chosen if other != config["scenario"]]
        names.append(f"{config['scene']}-{config['scenario']}.html")
        texts[names[-1]] = page_html(config)
    written = tuple(files.write_text_files(folder, texts))
    shared = sum((folder / n).stat().st_size for n in (MUJOCO_SCRIPT, *_ASSETS))
    return tuple(
        InteractivePage(
            scene=config["scene"],
            scenario=config["scenario"],
            path=folder / name,
            files=written,
            size_bytes=shared + (folder / name).stat().st_size,
        )
        for config, name in zip(configs, names)
    )
