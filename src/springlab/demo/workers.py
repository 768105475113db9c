"""The demo's worker processes: its steps and films run on every core, forked from the demo before its first run.

A job is a module-level function and its (picklable) arguments; what it needs besides them (the output folder)
it reads from the state the workers were forked with. An interrupted job unwinds (its files are removed, as
springlab.files and the video writer do on any exception) and then ends its worker, so a worker never starts the
next queued job after an interruption and `Workers.stop` leaves no process and no partial file behind.
"""

from __future__ import annotations

import concurrent.futures
import concurrent.futures.process
import multiprocessing
import os
import signal
from collections.abc import Callable
from typing import Any, TypeVar

from .state import DemoState

#: worker processes (at most the machine's CPUs)
WORKERS = 2
#: how long `Workers.stop` waits for an interrupted worker to remove its partial files [s]
UNWIND_SECONDS = 30.0
#: the state the workers were forked with (only its output folder is read there)
_FORKED: DemoState | None = None

T = TypeVar("T")


def forked_state() -> DemoState:
    """In a worker: the state it was forked with."""
    assert _FORKED is not None, "a demo worker is forked after Workers sets the state"
    return _FORKED


class _Stopped(BaseException):
    """SIGTERM reached a worker in the middle of a job: unwinds the job like Ctrl-C."""


#: in a worker: whether a job is running (SIGTERM then unwinds it; between jobs the worker just ends)
_IN_JOB = False


def _on_sigterm(signum: int, frame: Any) -> None:
    if _IN_JOB:
        raise _Stopped
    os._exit(1)


def _start_worker() -> None:
    # Ctrl-C reaches every process of the terminal's group: the demo's own process stops the workers (SIGTERM),
    # so a worker ignores SIGINT rather than printing its own traceback
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _on_sigterm)


def _job(function: Callable[..., T], *args: Any) -> T:
    global _IN_JOB
    _IN_JOB = True
    try:
        return function(*args)
    except Exception:
        raise  # an error: the demo reports it
    except BaseException:
        # stopped: the job's files are unwound by now (springlab.files and the video writer remove theirs on any
        # exception); end the worker so it never starts the next queued job
        os._exit(1)
    finally:
        _IN_JOB = False


class Workers:
    """A fork-based process pool for the demo's jobs, started before the demo's first run.

    Forked early, the workers carry nothing but the imported modules and the (empty) state; a run a job
    draws crosses to its worker as an argument. No GL context exists in the demo's own process, so every
    worker makes its own.
    """

    def __init__(self, state: DemoState) -> None:
        global _FORKED
        _FORKED = state
        workers = max(1, min(WORKERS, os.cpu_count() or 1))
        context = multiprocessing.get_context("fork")
        self.pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=workers, mp_context=context, initializer=_start_worker
        )

    def submit(self, function: Callable[..., T], *args: Any) -> concurrent.futures.Future[T]:
        """Queue `function(*args)` on the workers (first queued, first started)."""
        return self.pool.submit(_job, function, *args)

    def finish(self) -> None:
        """Every job is done: end the workers."""
        self.pool.shutdown()
        _release()

    def stop(self) -> None:
        """End the workers now (the demo was interrupted or failed): nothing more is started, and each running
        job unwinds its partial files before its worker ends."""
        processes = list((getattr(self.pool, "_processes", None) or {}).values())  # None once shut down
        manager = getattr(self.pool, "_executor_manager_thread", None)
        self.pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            if process.is_alive():
                process.terminate()
        for process in processes:
            process.join(UNWIND_SECONDS)
            if process.is_alive():
                process.kill()
        if manager is not None:
            # the pool's own thread sees its workers gone and ends. Python 3.11's exit hook (concurrent.futures'
            # _python_exit) wakes every such thread through a pipe without the lock that thread closes it under:
            # an interrupted demo printed "Exception ignored in: <module 'threading'>" and a traceback after its
            # one line (about 1 run in 20 on a loaded machine). The thread is done here, so the hook has nothing
            # to wake: take it off the hook's list.
            manager.join(UNWIND_SECONDS)
            if not manager.is_alive():  # (still alive, it needs the hook's wake-up to end)
                getattr(concurrent.futures.process, "_threads_wakeups", {}).pop(manager, None)
        _release()


def _release() -> None:
    """Let go of the state the workers were forked with (they have their own copy)."""
    global _FORKED
    _FORKED = None
