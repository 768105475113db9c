"""Shared test settings: off-screen GL for any test that renders, no stray MuJoCo logs; studies that several
tests read are computed once per test session (session-scoped fixtures; their results are immutable, so
sharing them cannot couple the tests)."""

import gc
import inspect
import os

import mujoco
import pytest

from helpers.cli import CliResult, run_cli

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


#: the tests of this process that read `dask_cluster` and have not finished yet (pytest_collection_finish fills
#: it, pytest_runtest_teardown empties it); the cluster shuts down when the last of them is done
_CLUSTER_READERS: set[str] = set()
_CLUSTER: list = []


@pytest.fixture(scope="session")
def dask_cluster():
    """A dask LocalCluster of 2 worker processes (one thread each), started on first use and shared by every
    test that compares a study on dask workers with the same study run locally (each start costs 1-2 s of
    process spawning and imports). The tests only submit work to it; one that kills a worker starts its own.
    It closes after the last test of this process that reads it (pytest_runtest_teardown below), not at the
    session's end: an idle cluster (its scheduler's thread here, two nannies, two workers) costs about 6 % of
    a core in heartbeats, some 10 s of CPU over a full run."""
    pytest.importorskip("distributed", reason="the distributed extra (make test installs it)")
    from springlab.studies.executor import Executor

    with Executor(workers=2, progress=False) as executor:
        _CLUSTER.append(executor)
        try:
            yield executor
        finally:
            _CLUSTER.clear()


def pytest_collection_finish(session: pytest.Session) -> None:
    """The tests this process will run that read the session's cluster (all of them under --dist loadgroup,
    which keeps the fixture's readers on one worker; elsewhere the cluster closes at the session's end)."""
    _CLUSTER_READERS.update(item.nodeid for item in session.items if "dask_cluster" in item.fixturenames)
    # the collected modules (numpy, scipy, matplotlib, mujoco, dask, the tests) live all session: frozen, the
    # collector stops scanning them, and a larger first generation collects the arrays' short-lived wrappers
    # less often; over a full run the collector's CPU fell from 9.2 to 5.0 s (both workers)
    gc.collect()
    gc.freeze()
    gc.set_threshold(10_000, 20, 20)


@pytest.hookimpl(trylast=True)
def pytest_runtest_teardown(item: pytest.Item) -> None:
    """Close the session's cluster once every test that reads it has run (its fixture's own exit, later,
    finds it closed: Executor.close is idempotent)."""
    if item.nodeid in _CLUSTER_READERS:
        _CLUSTER_READERS.discard(item.nodeid)
        if not _CLUSTER_READERS and _CLUSTER:
            _CLUSTER[0].close()


@pytest.fixture(scope="session")
def stability_report():
    """`springlab stability`'s default report (a springlab.studies.stability.StabilityReport), computed once."""
    from springlab.studies import stability

    return stability.stability_report()


@pytest.fixture(scope="session")
def stability_command(stability_report, tmp_path_factory):
    """`springlab stability --json --output DIR` as a user types it (the default amplification map), its report the
    session's `stability_report` (the command's own default report, computed once): run once and read by every
    test of what the command prints and writes (tests/studies/test_stability.py, tests/scenes/test_every_command.py,
    tests/cli/test_cli_usage.py).
    Returns (CliResult, DIR); the files are read-only, so no reader can change what the next one reads."""
    from springlab.studies import stability

    out = tmp_path_factory.mktemp("stability") / "out"
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(stability, "stability_report", lambda **options: stability_report)
        printed = run_cli("stability", "--json", "--output", out)
    for path in out.iterdir() if out.is_dir() else ():
        path.chmod(0o444)
    return printed, out


#: the shipped scenes whose session audit runs on the audit's real timer (`shipped_audit`)
_TIMED_AUDITS = ("slider",)


@pytest.fixture(scope="session")
def shipped_audit():
    """`audit(scene, tol=1e-3)` of a shipped scene (the demo's and the command's default tol), computed once per
    scene: call the fixture with the scene's name. The slider's runs on the audit's real timer (read by
    tests/studies/audit/test_audit_cli.py beside the command's own timed audit); the other scenes' readers read
    limits, orders and files, no wall time, so their timer returns one constant (helpers/audit.py:
    stub_the_timer; the pick ranks counted work, which no timer moves: about 0.7 s of timing runs per audit)."""
    from helpers.audit import stub_the_timer
    from springlab.studies.audit.audit import audit

    done = {}

    def get(scene):
        if scene not in done:
            with pytest.MonkeyPatch.context() as patch:
                if scene not in _TIMED_AUDITS:
                    stub_the_timer(patch)
                done[scene] = audit(scene, tol=1e-3)
        return done[scene]

    return get


@pytest.fixture(scope="session")
def slider_free_sweep():
    """`tradeoff.sweep("slider", "free", timing_repeats=1)`: the full default slider/free sweep (5 integrators x 13
    timesteps, one timing repeat to save time), computed once: read by tests/studies/test_tradeoff.py and by the
    slider audit's agreement with the trade-off (tests/studies/audit/test_audit.py)."""
    from springlab.studies import tradeoff

    return tradeoff.sweep("slider", "free", timing_repeats=1)


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


def _shared_fixtures(item: pytest.Item) -> tuple[list[str], str | None]:
    """The shared fixtures of this test suite that `item` reads: every session-scoped one, and the first
    module-scoped one as a group name of its own (module.name)."""
    infos = getattr(item, "_fixtureinfo", None)
    session: list[str] = []
    module: str | None = None
    for name in getattr(infos, "names_closure", ()):
        definitions = infos.name2fixturedefs.get(name)
        if not definitions:
            continue
        definition = definitions[-1]
        source = os.path.abspath(inspect.getfile(definition.func))
        if source.startswith(_TESTS):
            if definition.scope == "session":
                session.append(name)
            elif definition.scope == "module" and module is None:
                module = f"{item.module.__name__}.{name}"
    return session, module


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_collection_modifyitems(items: list[pytest.Item]):
    """Group the tests that share a study (`_group_shared_studies`, before every other plugin's hook: xdist
    reads the groups in its own), then, after every other plugin's hook (pytest-randomly's shuffle among
    them), move the tests marked slow to the front, in their shuffled order. xdist hands out the shared
    groups first, then the single tests in this order: a 10-15 s test dealt last kept one worker busy that
    long after the other had finished (up to 15 s of a 2-worker run's wall time), dealt first the short
    tests fill in behind it."""
    _group_shared_studies(items)
    result = yield
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)  # stable: random within each part
    return result


def _group_shared_studies(items: list[pytest.Item]) -> None:
    """Under `pytest -n N --dist loadgroup` (make test), the tests that read one shared study run on one
    worker, so the study is computed once, not once per worker (a session fixture is per process). A test
    that reads two session fixtures joins their groups into one (else the second would be computed on a
    second worker too), a test with only a module-scoped one groups by it. Marked before xdist reads the
    groups in its own pytest_collection_modifyitems."""
    parent: dict[str, str] = {}

    def root(name: str) -> str:
        while parent.setdefault(name, name) != name:
            name = parent[name]
        return name

    found = [_shared_fixtures(item) for item in items]
    for session, _ in found:
        for other in session[1:]:
            first, second = root(session[0]), root(other)
            if first != second:
                parent[max(first, second)] = min(first, second)  # the same root whatever the order of the tests
    for item, (session, module) in zip(items, found):
        group = root(session[0]) if session else module
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))
