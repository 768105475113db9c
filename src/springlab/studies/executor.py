"""One executor for every sweep: chunks of batched MuJoCo runs, locally or on a Dask cluster.

Every heavy study springlab has (a `sweep`, the tradeoff grid, the stability
map, the printer-head design study and its Sobol analysis) is many independent
simulations. The study cuts them into *chunks*: plain-data payloads, each a
frozen dataclass beside its chunk function (scene names, parameter values,
timesteps; never a pickled MjModel or MjData), each
turned into one batched MuJoCo call (`mujoco.batch.Batch` / `mujoco.rollout`
on threads) by a module-level function of the study. The executor only runs
chunks and hands their results back **in submission order**:

* locally (the default): one chunk after the other in this process, each
  batch on every CPU (`nthread=0`), no new process;
* `workers=N`: a `dask.distributed.LocalCluster` of N worker processes, one
  thread each, one chunk per task (`nthread=1`: the worker's thread is the
  unit of parallelism);
* `scheduler=ADDRESS`: a running scheduler (`dask scheduler` + `dask worker`
  on other machines; each worker needs springlab installed).

Why the numbers are identical bit for bit whichever runs them: the chunks are
cut by the study, not by the executor (same chunks everywhere), a simulation's
result depends only on its own model and state (MuJoCo batches never couple
simulations, and threads only split the list), every worker rebuilds its
models from the same MJCF with the same code, and every reduction runs in the
caller over the results in chunk order.

Failure: a worker that dies mid-sweep loses only the chunks it held; the
scheduler reruns them on another worker (up to `distributed.scheduler.
allowed-failures` times) and, because a chunk is a pure function of its
payload, the rerun gives the same numbers. A scheduler that cannot be reached
within `CONNECT_TIMEOUT_S` is a BadInputError (exit 2), not a hang.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pathlib
import socket
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Protocol, TypeVar
from urllib.parse import urlsplit

from springlab import progress
from springlab.errors import BadInputError, ClusterError, SpringlabError

#: a chunk's payload (a frozen dataclass of plain data) and its result
Payload = TypeVar("Payload")
Result = TypeVar("Result")
_PayloadIn = TypeVar("_PayloadIn", contravariant=True)
_ResultOut = TypeVar("_ResultOut", covariant=True)


class ChunkFunction(Protocol[_PayloadIn, _ResultOut]):
    """A study's chunk: a module-level function of its payload, run as one batched call on `nthread` threads."""

    def __call__(self, payload: _PayloadIn, /, nthread: int = ...) -> _ResultOut: ...


#: seconds to wait for a scheduler to answer before giving up (exit 2)
CONNECT_TIMEOUT_S = 10.0
#: seconds between looks for a worker while no chunk finishes (a scheduler without workers waits forever)
WORKER_POLL_S = 1.0
#: seconds between looks for finished chunks (chunks take seconds: a negligible delay)
RESULT_POLL_S = 0.02
#: the extra that brings dask.distributed
_EXTRA = "pip install 'springlab[distributed]'"


def _import_distributed():
    """dask.distributed, or BadInputError naming the extra that installs it."""
    try:
        import distributed
    except ImportError:
        raise BadInputError(f"--workers/--scheduler need dask.distributed: {_EXTRA}") from None
    return distributed


#: the loggers whose lines stay off stderr unless asked for (--verbose); their children too
_DASK_LOGGERS = ("distributed", "tornado", "asyncio")


@contextlib.contextmanager
def _quiet_dask(quiet: bool = True) -> Iterator[None]:
    """Keep distributed's log lines (worker restarts, closing comms, a lost scheduler's tracebacks) off stderr.

    distributed's logging configuration gives child loggers their own levels
    (`distributed.client: warning`), so silencing the parent alone lets
    `distributed.client`'s reconnect errors through: every existing logger under
    the three names is set to CRITICAL, and restored afterwards.
    """
    if not quiet:
        yield
        return
    names = [
        name
        for name in list(logging.root.manager.loggerDict)
        if any(name == root or name.startswith(root + ".") for root in _DASK_LOGGERS)
    ]
    loggers = [logging.getLogger(name) for name in {*names, *_DASK_LOGGERS}]
    levels = [logger.level for logger in loggers]
    for logger in loggers:
        logger.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels):
            logger.setLevel(level)


def _check_reachable(address: str, timeout: float) -> None:
    """Raise BadInputError unless a TCP connection to the scheduler opens within `timeout` [s]."""
    parts = urlsplit(address if "://" in address else f"tcp://{address}")
    if parts.scheme not in ("tcp", "tls"):
        raise BadInputError(f"scheduler address {address!r}: use tcp://HOST:PORT (e.g. tcp://10.0.0.5:8786)")
    try:
        host, port = parts.hostname, parts.port or 8786
    except ValueError:
        raise BadInputError(f"scheduler address {address!r}: the port must be a number 1-65535") from None
    if not host:
        raise BadInputError(f"scheduler address {address!r}: no host; use tcp://HOST:PORT")
    try:
        with socket.create_connection((host, port), timeout=timeout):
            pass
    except OSError as error:
        why = "no answer" if isinstance(error, TimeoutError) else (error.strerror or str(error))
        raise BadInputError(
            f"cannot reach the dask scheduler at {address} within {timeout:g} s ({why});"
            " start one with 'dask scheduler' or run without --scheduler"
        ) from None


class Executor:
    """Runs a study's chunks locally or on dask.distributed; results in submission order.

    Parameters
    ----------
    workers
        start a LocalCluster of this many worker processes (one thread each).
    scheduler
        address of a running dask scheduler, e.g. 'tcp://10.0.0.5:8786'.
        At most one of workers and scheduler; neither: run locally.
    timeout
        seconds [s] to wait for the scheduler (and for LocalCluster workers) to answer.
    progress
        None: a progress bar on a terminal only; False: never (--json, tests).
    on_result
        optional callback(chunk index) after each chunk's result arrives (tests use it).
    nthread
        batch threads of a local run (0: one per CPU); dask tasks always get 1.
    quiet
        keep distributed's own log lines off stderr while the executor is connected (the CLI's
        default; `--verbose` turns it off).

    A lost cluster (the scheduler gone, no worker left for `timeout` seconds, a chunk whose
    workers all died) ends the map with one ClusterError line; the study returns nothing.
    Use as a context manager (or call `close`) so a LocalCluster started here is shut down;
    one Executor can run several maps (a study and its plane) on the same cluster.
    """

    def __init__(
        self,
        *,
        workers: int | None = None,
        scheduler: str | None = None,
        timeout: float = CONNECT_TIMEOUT_S,
        progress: bool | None = None,
        on_result: Callable[[int], None] | None = None,
        nthread: int = 0,
        quiet: bool = True,
    ):
        if workers is not None and scheduler is not None:
            raise BadInputError("give --workers N (a local cluster) or --scheduler ADDRESS (a running one), not both")
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise BadInputError(f"workers must be an integer >= 1, got {workers!r}")
        if not (isinstance(timeout, (int, float)) and timeout > 0):
            raise BadInputError(f"timeout must be a number > 0 s, got {timeout!r}")
        self.workers, self.scheduler, self.timeout = workers, scheduler, float(timeout)
        if isinstance(nthread, bool) or not isinstance(nthread, int) or nthread < 0:
            raise BadInputError(f"threads must be an integer >= 0 (0: one per CPU), got {nthread!r}")
        self.progress, self.on_result, self.nthread, self.quiet = progress, on_result, nthread, quiet
        self._cluster = None
        self._client = None
        # distributed's loggers stay quiet from the connection to `close`: a lost scheduler's
        # reconnect errors are logged from the client's own thread, between and after maps
        self._quiet = contextlib.ExitStack()

    @property
    def distributed(self) -> bool:
        """Whether chunks run on dask (True) or in this process (False)."""
        return self.workers is not None or self.scheduler is not None

    def describe(self) -> str:
        """'local', '2 local dask workers' or 'dask scheduler tcp://...'."""
        if self.workers is not None:
            return f"{self.workers} local dask worker{'s' if self.workers > 1 else ''}"
        if self.scheduler is not None:
            return f"dask scheduler {self.scheduler}"
        return "local"

    # -- lifecycle ---------------------------------------------------------------

    @property
    def client(self) -> Any:
        """The dask Client (connecting or starting the cluster on first use)."""
        if self._client is None:
            distributed = _import_distributed()
            self._quiet.enter_context(_quiet_dask(self.quiet))
            try:
                self._client = self._connect(distributed)
            except BaseException:
                self._quiet.close()
                raise
        return self._client

    def _connect(self, distributed: Any) -> Any:
        if self.scheduler is not None:
            _check_reachable(self.scheduler, self.timeout)
            try:
                return distributed.Client(self.scheduler, timeout=self.timeout, set_as_default=False)
            except (OSError, TimeoutError) as error:
                raise BadInputError(
                    f"cannot connect to the dask scheduler at {self.scheduler} within {self.timeout:g} s: {error}"
                ) from None
        self._cluster = distributed.LocalCluster(
            n_workers=self.workers,
            threads_per_worker=1,
            processes=True,
            dashboard_address=":0",  # any free port: a second cluster must not warn that 8787 is taken
            silence_logs=logging.CRITICAL if self.quiet else False,
            # the workers import springlab from wherever this process does
            env={"PYTHONPATH": _pythonpath_for_workers()},
        )
        return distributed.Client(self._cluster, timeout=self.timeout, set_as_default=False)

    def close(self) -> None:
        """Disconnect, and shut down a LocalCluster this executor started."""
        try:
            if self._client is not None:
                with contextlib.suppress(Exception):  # a client whose scheduler is gone closes as it can
                    self._client.close()
            if self._cluster is not None:
                self._cluster.close()
        finally:
            self._client = self._cluster = None
            self._quiet.close()

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- running chunks ----------------------------------------------------------------

    def map(
        self,
        function: ChunkFunction[Payload, Result],
        payloads: Sequence[Payload],
        *,
        description: str = "chunks",
        sizes: Sequence[int] | None = None,
        unit: str = "run",
    ) -> list[Result]:
        """[function(payload, nthread=...) for payload in payloads], in order.

        Locally `nthread` is the executor's (0: every CPU); on dask it is 1 (one task per worker thread).

        Parameters
        ----------
        function
            a module-level (importable) function of plain data; it runs its chunk as one
            batched MuJoCo call on `nthread` threads (0: every CPU) and returns plain data.
        payloads
            one per chunk, picklable plain data: a frozen dataclass of names, numbers, tuples and numpy
            arrays (e.g. springlab.studies.tradeoff.GridChunk).
        description
            the progress bar's label.
        sizes
            simulations per chunk, for the bar's rate (default: 1 per chunk).
        unit
            what `sizes` counts.

        Raises
        ------
            Whatever a chunk raised (SpringlabErrors pass through unchanged).
        """
        sizes = [1] * len(payloads) if sizes is None else list(sizes)
        results: list[Any] = [None] * len(payloads)  # filled in submission order
        with progress.bar(sum(sizes), description=description, unit=unit, enabled=self.progress) as bar:
            if not self.distributed:
                for index, payload in enumerate(payloads):
                    results[index] = function(payload, nthread=self.nthread)
                    bar.update(sizes[index])
                    if self.on_result is not None:
                        self.on_result(index)
                return results
            self._gather(function, payloads, results, sizes, bar)
        return results

    def _gather(self, function, payloads, results, sizes, bar) -> None:
        """Submit every chunk to dask and collect the results into `results` as they finish.

        Polls rather than blocking on `as_completed`, so a cluster without workers is noticed:
        tasks on a scheduler with no worker would otherwise wait forever.
        """
        distributed = _import_distributed()
        client = self.client
        futures = client.map(function, payloads, nthread=1, pure=False)
        index_of = {future.key: i for i, future in enumerate(futures)}
        finished = 0
        workerless_since: float | None = None
        next_look = time.monotonic() + WORKER_POLL_S
        try:
            pending = distributed.as_completed(futures, loop=client.loop)
            while not pending.is_empty():
                if not pending.has_ready():
                    if time.monotonic() >= next_look:
                        workerless_since = self._look_for_workers(client, workerless_since, finished, len(futures))
                        next_look = time.monotonic() + WORKER_POLL_S
                    time.sleep(RESULT_POLL_S)
                    continue
                for future in pending.next_batch(block=False):
                    index = index_of[future.key]
                    results[index] = self._result(future, finished, len(futures))
                    finished += 1
                    workerless_since = None
                    bar.update(sizes[index])
                    if self.on_result is not None:
                        self.on_result(index)
        except SpringlabError:
            raise
        except (OSError, TimeoutError, distributed.comm.CommClosedError) as error:
            # the client's own calls (submitting, asking for workers) on a connection that broke
            raise self._connection_lost(_why_lost(error), finished, len(futures)) from None
        finally:
            for future in futures:
                with contextlib.suppress(Exception):  # a lost client cannot release; nothing is left to free
                    future.release()

    def _where(self) -> str:
        return f"the dask scheduler at {self.scheduler}" if self.scheduler is not None else "the local dask cluster"

    def _lost(self, what: str, advice: str, finished: int, total: int) -> ClusterError:
        """The one-line ClusterError for a cluster lost after `finished` of `total` chunks."""
        return ClusterError(f"{what} after {finished} of {total} chunks; the study stopped and wrote nothing: {advice}")

    def _connection_lost(self, why: str, finished: int, total: int) -> ClusterError:
        again = "rerun when it is back, or without --scheduler" if self.scheduler is not None else "rerun"
        return self._lost(f"lost the connection to {self._where()} ({why})", again, finished, total)

    def _look_for_workers(self, client: Any, since: float | None, finished: int, total: int) -> float | None:
        """When the cluster first had no worker (None: it has some); ClusterError after `timeout` s without."""
        if client.status not in ("running", "connecting"):
            raise self._connection_lost(f"the client is {client.status}", finished, total)
        workers = client.nthreads(callback_timeout=self.timeout)
        if workers:
            return None
        now = time.monotonic()
        since = now if since is None else since
        if now - since >= self.timeout:
            start = f"start workers with 'dask worker {self.scheduler}' and rerun" if self.scheduler else "rerun"
            raise self._lost(f"{self._where()} has had no worker for {self.timeout:g} s", start, finished, total)
        return since

    def _result(self, future: Any, finished: int, total: int) -> Any:
        """A finished future's value; a chunk's SpringlabError is re-raised as itself, a lost cluster
        as one ClusterError line."""
        distributed = _import_distributed()
        try:
            return future.result()
        except SpringlabError:
            raise
        except distributed.client.FutureCancelledError as error:
            # the client cancels every future when its connection to the scheduler drops
            reason = "the connection closed" if error.reason == "scheduler-connection-lost" else error.reason
            raise self._connection_lost(reason, finished, total) from None
        except distributed.KilledWorker:
            raise self._lost(
                f"a chunk killed every worker that ran it on {self._where()}"
                f" ({_allowed_failures() + 1} deaths; dask's allowed-failures)",
                "see the workers' logs",
                finished,
                total,
            ) from None
        except Exception as error:
            if future.status != "error":
                # the chunk ran, but fetching its result failed (CommClosedError, a reset connection)
                raise self._connection_lost(_why_lost(error), finished, total) from None
            # the chunk itself raised: a broken install on the workers, a bug; one line, the cluster's words
            raise BadInputError(
                f"a chunk failed on the dask cluster: {type(error).__name__}: {_first_line(error)}"
            ) from None


def _why_lost(error: BaseException) -> str:
    """A short reason for a broken connection (distributed's messages name its internal pools)."""
    import distributed

    if isinstance(error, distributed.comm.CommClosedError):
        return "the connection closed"
    if isinstance(error, TimeoutError):
        return "no answer"
    return getattr(error, "strerror", None) or _first_line(error)


def _first_line(error: BaseException) -> str:
    """The first line of an exception's message (distributed's run over several)."""
    text = str(error).strip()
    return text.splitlines()[0] if text else type(error).__name__


def _allowed_failures() -> int:
    """Dask's `distributed.scheduler.allowed-failures`: worker deaths a task survives before KilledWorker."""
    import dask

    return int(dask.config.get("distributed.scheduler.allowed-failures"))


def _pythonpath_for_workers() -> str:
    """PYTHONPATH for LocalCluster workers: this springlab's folder first, so they import the same code."""
    here = str(pathlib.Path(__file__).resolve().parents[2])  # src/springlab/studies/executor.py -> src/
    return os.pathsep.join(p for p in (here, os.environ.get("PYTHONPATH", "")) if p)


def ping(payload: Any, nthread: int = 0) -> Any:
    """A chunk that does nothing (returns its payload): measures the executor's per-task overhead."""
    return payload


def chunked(count: int, size: int) -> list[range]:
    """Index ranges [0, size), [size, 2 size), ... covering `count` items; the study's chunks.

    The cut depends only on (count, size), never on the executor, so local and
    distributed runs make the same batched calls.
    """
    if size < 1:
        raise BadInputError(f"chunk size must be >= 1, got {size!r}")
    return [range(start, min(start + size, count)) for start in range(0, count, size)]


def resolve(executor: Executor | None) -> Executor:
    """`executor`, or a local one."""
    return Executor(progress=False) if executor is None else executor
