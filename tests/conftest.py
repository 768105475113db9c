"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs; studies that several
tests read are computed once per test session (session-scoped fixtures; their results are immutable, so
sharing them cannot couple the tests)."""

import inspect
import os

import mujoco
import pytest

from helpers.cli import CliResult

os.environ.setdefault("MUJOCO_GL", "egl")


def _ignore_warning(message: str) -> None:
    """Tests that load a model themselves (e.g. dm_control's suite, which still uses the deprecated
    `settotalmass`) would otherwise leave MUJOCO_LOG.TXT in the working directory; springlab's own code
    routes warnings itself (springlab.sim.simulate.quiet_mujoco), and tests that count warnings use it."""


mujoco.set_mju_user_warning(_ignore_warning)


@pytest.fixture
def cli(capsys):
    """`springlab ARGV` in this process: `cli("run", "slider", "--output", tmp_path)` calls
    springlab.cli.main.main with every argument as a string and returns a frozen CliResult(code, out, err) of
    what that command printed (output printed before the call is dropped). A test that needs a real process
    (signals, the interpreter's warnings, a working directory) runs `python -m springlab` itself."""
    from springlab.cli.main import main

    def run(*argv: object) -> CliResult:
        capsys.readouterr()
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return CliResult(code, out, err)

    return run


@pytest.fixture(scope="session")
def dask_cluster():
    """A dask LocalCluster of 2 worker processes (one thread each), started on first use and shared by every
    test that compares a study on dask workers with the same study run locally (each start costs 1-2 s of
    process spawning and imports). The tests only submit work to it; one that kills a worker starts its own."""
    pytest.importorskip("distributed", reason="the distributed extra (make test installs it)")
    from springlab.studies.executor import Executor

    with Executor(workers=2, progress=False) as executor:
        yield executor


@pytest.fixture(scope="session")
def stability_report():
    """`springlab stability`'s default report (a springlab.studies.stability.StabilityReport), computed once."""
    from springlab.studies import stability

    return stability.stability_report()


@pytest.fixture(scope="session")
def shipped_audit():
    """`audit(scene, tol=1e-3)` of a shipped scene (the demo's and the command's default tol), computed once per
    scene: call the fixture with the scene's name."""
    from springlab.studies.audit.audit import audit

    done = {}

    def get(scene):
        if scene not in done:
            done[scene] = audit(scene, tol=1e-3)
        return done[scene]

    return get


@pytest.fixture(scope="session")
def scenario_run():
    """`run_scenario(scene, scenario)` at the scenario's own settings, computed once per scenario: call the
    fixture with the scene's and the scenario's names (the non-linear scene's chaos figures alone cost 5 s)."""
    from springlab.runs.run import run_scenario

    done = {}

    def get(scene, scenario):
        if (scene, scenario) not in done:
            done[scene, scenario] = run_scenario(scene, scenario)
        return done[scene, scenario]

    return get


@pytest.fixture(scope="session")
def default_design_study():
    """The printer head's design study on its default grid (7^4 = 2401 configurations, no plane): computed
    once per test run and read by tests/studies/design/test_design.py and test_printer_head_settling.py (10-25 s)."""
    from springlab.studies.design import run_study

    return run_study("printer_head", plane_levels=0)


@pytest.fixture(scope="session")
def small_design_study():
    """The printer head's design study on 3^4 = 81 configurations (the grid's corners and centre), with a
    9 x 9 plane and Sobol indices from N = 8 base samples: computed once per test run (its readers share one
    xdist group, below) and read by tests/studies/design/test_design.py, test_sobol.py and test_executor.py."""
    from springlab.studies.design import run_study

    return run_study("printer_head", levels=3, plane_levels=9, sobol=8)


_TESTS = os.path.dirname(os.path.abspath(__file__))


def _shared_fixture(item: pytest.Item) -> str | None:
    """The shared fixture of this test suite that `item` reads, as a group name: a session-scoped one first
    (a module fixture built on it then joins its group), else the first module-scoped one."""
    infos = getattr(item, "_fixtureinfo", None)
    found: dict[str, str] = {}
    for name in getattr(infos, "names_closure", ()):
        definitions = infos.name2fixturedefs.get(name)
        if not definitions:
            continue
        definition = definitions[-1]
        source = os.path.abspath(inspect.getfile(definition.func))
        if definition.scope in ("module", "session") and source.startswith(_TESTS):
            group = name if definition.scope == "session" else f"{item.module.__name__}.{name}"
            found.setdefault(definition.scope, group)
    return found.get("session", found.get("module"))


def pytest_itemcollected(item: pytest.Item) -> None:
    """Under `pytest -n N --dist loadgroup` (make test), the tests that read one shared study run on one
    worker, so the study is computed once, not once per worker (a session fixture is per process). Marked
    as each test is collected: xdist reads the groups in its own pytest_collection_modifyitems."""
    group = _shared_fixture(item)
    if group is not None:
        item.add_marker(pytest.mark.xdist_group(group))
