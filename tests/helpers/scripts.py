"""The scripts of scenarios/ run as a user runs them (`python scenarios/NAME.py` in an empty folder, headless), each
in a process of its own, but without paying the interpreter's start and `import springlab` once per script: one
interpreter imports springlab, then forks a child per script that runs it as `__main__` (runpy) with its own
argv, working folder, stdout and stderr, and exits with the script's exit code. Every script thus starts from the
state right after `import springlab` and the first lookup of a scene (which imports the scenes' modules: a
read-only catalogue, CONTRIBUTING), with the libraries springlab imports on first use in most runs already loaded
(threadpoolctl, scipy.optimize), as it would be in a fresh interpreter once those had loaded, and no script sees
another's. 21 scripts at 0.6 s of start-up each were two thirds of test_scenarios' cost.

A script may be handed results the test session already has (`served`): `springlab.run(scene, scenario)`
called in it exactly so (no option) returns the session's Result of that call, unpickled in the child, and any
other call runs as usual. The script's own lines, what it reads of the result and prints, run unchanged; the
run itself is held by the tests of its scene (a chaotic scenario's run cost 4 s twice over)."""

import json
import pathlib
import pickle
import subprocess
import sys
from typing import Any, NamedTuple

#: the interpreter's program: argv[1] is a JSON list of [script, [args...], folder, served], `served` the path of
#: a pickled {(scene, scenario): Result} or null; prints one JSON list of [exit code, stdout, stderr], one per
#: script, in order
_DRIVER = r"""
import json, os, pickle, runpy, sys, traceback
import springlab  # what every script imports first: paid once, before the forks
import threadpoolctl  # imported by the first exact reference of any run (springlab.exact.linear)
import scipy.optimize  # imported on first use by many scenes' exact references and answers (0.25 s per script)
from springlab import scenes

# the catalogue, found by importing every scene's module on first lookup (read-only): once, not per script
len(scenes.SCENES)


def serve(path):
    # springlab.run(scene, scenario) with no option returns the session's Result of that very call
    with open(path, "rb") as handle:
        served = pickle.load(handle)
    real = springlab.run

    def run(model, scenario=None, **options):
        if (model, scenario) in served and all(value is None for value in options.values()):
            return served[model, scenario]
        return real(model, scenario, **options)

    springlab.run = run


jobs = json.loads(sys.argv[1])
done = []
for script, args, folder, served in jobs:
    out, err = os.path.join(folder, ".stdout"), os.path.join(folder, ".stderr")
    sys.stdout.flush()
    sys.stderr.flush()
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            os.chdir(folder)
            for fd, path in ((1, out), (2, err)):
                os.dup2(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC), fd)
            sys.argv = [script, *args]
            sys.path[0] = os.path.dirname(script)
            if served:
                serve(served)
            runpy.run_path(script, run_name="__main__")
            code = 0
        except SystemExit as stop:
            code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
        except BaseException:
            traceback.print_exc()
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    code = os.waitstatus_to_exitcode(status)
    with open(out) as o, open(err) as e:
        done.append([code, o.read(), e.read()])
    os.remove(out)
    os.remove(err)
sys.stdout.write(json.dumps(done))
"""


class ScriptRun(NamedTuple):
    """What one script did: its exit code (negative: killed by that signal) and what it printed."""

    code: int
    out: str
    err: str


def run_scripts(
    scripts: list[pathlib.Path],
    args: dict[str, list[str]],
    folder: pathlib.Path,
    timeout: float = 600,
    served: dict[str, dict[tuple[str, str], Any]] | None = None,
) -> dict[str, ScriptRun]:
    """Run every script of `scripts` (module docstring), each in an empty folder of its own under `folder`.

    Parameters
    ----------
    scripts
        the scripts' paths.
    args
        command-line arguments by script stem (absent: none).
    folder
        where each script's working folder is made (`folder/STEM`).
    timeout
        for all of them together [s].
    served
        by script stem, the session's Results {(scene, scenario): Result} that `springlab.run(scene, scenario)`
        returns in that script (module docstring; absent: none).

    Returns
    -------
    dict[str, ScriptRun]
        by script stem.
    """
    jobs = []
    for script in scripts:
        work = folder / script.stem
        work.mkdir(parents=True)
        results = None
        if served and script.stem in served:
            results = folder / f"{script.stem}.served.pickle"  # beside the script's folder, not in it
            results.write_bytes(pickle.dumps(served[script.stem]))
        jobs.append([str(script), args.get(script.stem, []), str(work), results and str(results)])
    proc = subprocess.run(
        [sys.executable, "-c", _DRIVER, json.dumps(jobs)],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    return {script.stem: ScriptRun(*run) for script, run in zip(scripts, json.loads(proc.stdout))}
