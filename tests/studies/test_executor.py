"""The executor: the same numbers bit for bit locally and on a dask LocalCluster of 2 worker processes,
a worker killed mid-sweep changes nothing, and an unreachable scheduler is a one-line exit 2 in time.

The claim checked is exact equality (np.array_equal, ==), not closeness: every simulation's result
depends only on its own model and state, the workers rebuild their models from the same MJCF, and
the caller reduces the chunks in submission order.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import os
import pickle
import pkgutil
import signal
import socket
import threading
import time
import typing

import numpy as np
import pytest

import springlab
from helpers.paths import ROOT
from helpers.timing import constant_time_run
from springlab.cli.main import main
from springlab.errors import BadInputError
from springlab.studies import stability, tradeoff
from springlab.studies.design import sobol
from springlab.studies.design import study as design
from springlab.studies.executor import Executor, chunked

pytest.importorskip("distributed", reason="the distributed extra (make test installs it)")

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def cluster(dask_cluster):
    """The session's LocalCluster of 2 worker processes (one thread each; tests/conftest.py)."""
    return dask_cluster


def _sweep(executor=None):
    return springlab.sweep(
        "slider",
        "free",
        vary={"damping": (0.5, 40.0, 4, "log"), "stiffness": (100.0, 1000.0, 3)},
        chunk_size=3,
        executor=executor,
    )


def test_chunks_depend_only_on_the_count_and_size():
    assert chunked(7, 3) == [range(0, 3), range(3, 6), range(6, 7)]
    with pytest.raises(BadInputError):
        chunked(7, 0)


def test_sweep_on_two_workers_equals_the_local_sweep(cluster):
    local, remote = _sweep(), _sweep(cluster)
    assert remote.executor == "2 local dask workers" and local.executor == "local"
    assert remote.rows == local.rows
    for name in local.quantity_names():
        assert np.array_equal(local.column(name), remote.column(name), equal_nan=True)


def test_tradeoff_grid_on_two_workers_equals_the_local_grid(cluster, monkeypatch):
    # errors and steps compared, no wall time: the timing runs (here, after either grid) take helpers/timing.py's
    # constant
    monkeypatch.setattr(tradeoff, "time_run", constant_time_run)

    def grid(executor):
        result = tradeoff.sweep("slider", "free", duration=0.5, timing_repeats=1, executor=executor)
        return [(r.integrator, r.dt, r.steps, r.max_rel_error, r.diverged) for r in result.runs]

    assert grid(cluster) == grid(None)


def test_design_study_on_two_workers_equals_the_local_study(cluster, small_design_study):
    local = small_design_study  # 3^4, computed locally (tests/conftest.py); its plane is not compared
    remote = design.run_study("printer_head", levels=3, plane_levels=0, executor=cluster)
    assert local.executor == "local" and remote.executor == "2 local dask workers"
    for field in ("positioning_time_s", "settling_time_s", "residual_amplitude_m", "dt_s", "estimate_s"):
        assert np.array_equal(getattr(local, field), getattr(remote, field)), field
    assert local.steps == remote.steps


def test_sobol_indices_on_two_workers_equal_the_local_ones(cluster, small_design_study):
    local = small_design_study.sobol  # N = 8, seed 0, computed locally
    remote = sobol.run_sobol("printer_head", 8, executor=cluster)
    assert local.executor == "local" and remote.executor == "2 local dask workers"
    assert np.array_equal(local.positioning_time_s, remote.positioning_time_s)
    assert local.indices == remote.indices  # the bootstrap is seeded: intervals too


def test_stability_boundaries_on_two_workers_equal_the_local_ones(cluster):
    local = stability.map_boundaries(["euler", "rk4"], [0.0, 1.0], steps=200)
    assert stability.map_boundaries(["euler", "rk4"], [0.0, 1.0], steps=200, executor=cluster) == local


def test_a_worker_killed_mid_sweep_changes_nothing():
    expected = springlab.sweep(
        "slider", "free", vary={"damping": (0.5, 40.0, 8, "log"), "stiffness": (100.0, 1000.0, 5)}
    )
    killed = []

    def kill_one_worker(index):
        # at the first finished chunk, SIGKILL one worker process: its chunks must rerun elsewhere
        if killed:
            return
        pids = executor.client.run(os.getpid)
        victim = sorted(pids.values())[0]
        os.kill(victim, signal.SIGKILL)
        killed.append(victim)

    with Executor(workers=2, progress=False, on_result=kill_one_worker) as executor:
        result = springlab.sweep(
            "slider",
            "free",
            vary={"damping": (0.5, 40.0, 8, "log"), "stiffness": (100.0, 1000.0, 5)},
            chunk_size=1,
            executor=executor,
        )
        alive = set(executor.client.run(os.getpid).values())
    assert killed and killed[0] not in alive  # the worker really died (its nanny started a new one)
    assert result.rows == expected.rows


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


#: every command that takes --scheduler, with cheap arguments (the scheduler is reached before the work)
_SCHEDULED_COMMANDS = {
    "sweep": ["sweep", "slider", "--vary", "mass=1:2:2"],
    "audit": ["audit", "slider", "--duration", "1"],
    "fit": [
        "fit", "slider", str(ROOT / "docs" / "examples" / "decay_mm.csv"),
        "--map", "t=time", "--map", "x_mm=slider_pos", "--scale", "0.001", "--set", "mass=2", "--starts", "2",
    ],
}  # fmt: skip


@pytest.mark.parametrize("command", sorted(_SCHEDULED_COMMANDS))
def test_an_unreachable_scheduler_is_a_one_line_exit_2_within_the_timeout(command, tmp_path, capsys):
    address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    start = time.perf_counter()
    code = main([*_SCHEDULED_COMMANDS[command], "--scheduler", address, "--output", str(tmp_path / "o")])
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == 2 and address in err and err.count("\n") == 1 and "Traceback" not in err
    assert elapsed < 10.0 + 5.0  # CONNECT_timeout_s, plus the command's own set-up
    assert not (tmp_path / "o").exists()


def test_a_scheduler_that_never_answers_gives_up_after_the_stated_timeout():
    # a listening socket that never accepts: the TCP handshake completes, but no dask reply ever
    # comes; the executor must give up after its timeout, not hang
    with socket.socket() as silent:
        silent.bind(("127.0.0.1", 0))
        silent.listen(0)
        address = f"tcp://127.0.0.1:{silent.getsockname()[1]}"
        outcome = {}
        # idle time: no reply ever comes, so a short timeout cannot be missed on a loaded machine, only waited out
        timeout_s = 0.5

        def connect():
            start = time.perf_counter()
            try:
                _ = Executor(scheduler=address, timeout=timeout_s).client
            except BadInputError as error:
                outcome["error"] = str(error)
            outcome["elapsed"] = time.perf_counter() - start

        worker = threading.Thread(target=connect, daemon=True)
        worker.start()
        worker.join(30.0)
    assert "error" in outcome and address in outcome["error"]
    assert outcome["elapsed"] < timeout_s + 8.0


def test_the_amplification_map_and_the_ishigami_check_on_two_workers_equal_the_local_ones(cluster):
    zetas, omega_dts = np.array([0.0, 0.5]), np.geomspace(0.1, 10.0, 7)
    local = stability.amplification_map(["euler", "rk4"], zetas, omega_dts)
    remote = stability.amplification_map(["euler", "rk4"], zetas, omega_dts, executor=cluster)
    assert all(np.array_equal(local.radius[name], remote.radius[name]) for name in ("euler", "rk4"))
    assert sobol.ishigami(64, executor=cluster) == sobol.ishigami(64)


def _chunk_functions():
    """Every study's chunk function: module-level, first parameter `payload`, then `nthread` (executor.ping,
    the overhead probe that returns whatever it gets, aside)."""
    import springlab.studies

    found = {}
    for info in pkgutil.walk_packages(springlab.studies.__path__, "springlab.studies."):
        module = importlib.import_module(info.name)
        for name, function in vars(module).items():
            if not inspect.isfunction(function) or function.__module__ != info.name or name == "ping":
                continue
            parameters = list(inspect.signature(function).parameters)
            if parameters[:2] == ["payload", "nthread"]:
                found[f"{info.name}.{name}"] = function
    return found


def test_every_chunk_takes_a_frozen_dataclass_of_plain_data():
    # a payload's keys are written down (its fields, typed), it cannot change between submission and a
    # rerun on another worker (frozen), and a worker finds its class by name (module level); the tests
    # above send each study's chunks to two workers and get the local numbers back
    chunks = _chunk_functions()
    assert len(chunks) >= 13, sorted(chunks)  # the eleven of issue 32, the sinestream's, the random load's
    for name, function in chunks.items():
        payload = typing.get_type_hints(function)["payload"]
        assert dataclasses.is_dataclass(payload), f"{name} takes {payload!r}, not a dataclass"
        assert payload.__dataclass_params__.frozen, f"{name}'s {payload.__name__} is not frozen"
        assert pickle.loads(pickle.dumps(payload)) is payload, f"{name}'s payload class is not importable"


def test_workers_and_scheduler_together_are_refused(capsys):
    code = main(["sweep", "slider", "--vary", "mass=1:2:2", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"])
    assert code == 2 and "not allowed with argument" in capsys.readouterr().err


def test_the_refine_study_on_two_workers_equals_the_local_one(cluster):
    from springlab.studies import refine

    def numbers(study):
        return [(r.size, r.integrator, r.dt, r.steps, r.value, r.exact, r.continuum) for r in study.runs]

    options = dict(sizes=(2, 4), integrators=("rk4", "euler"))
    local = refine.refine("drill_string", **options)
    assert numbers(refine.refine("drill_string", executor=cluster, **options)) == numbers(local)
