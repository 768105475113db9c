"""Every example notebook in docs/examples/ executes top to bottom (one test each) and fails on any error.

The notebooks are jupytext percent-format .py files: their diffs read like code and they hold no outputs by
construction. Each is turned into a notebook here (jupytext) and run by nbclient on a fresh ipykernel in the
folder it lives in, as a reader who opens it from the checkout runs it: its files must go to a folder of its own
(a temporary one, here under the test's), never beside it, and the checkout's `git status` is the same after it.
`jupytext --to ipynb --execute`, the other way people run them, is run on one of them. Each asserts physical
claims against closed forms in its own cells, so a notebook that runs but computes nonsense fails too.
"""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import tempfile
import time
from queue import Empty

import jupytext
import nbclient
import pytest
from jupyter_client.asynchronous.client import AsyncKernelClient
from jupyter_client.channels import AsyncZMQSocketChannel
from jupyter_client.manager import AsyncKernelManager
from traitlets import Type

from helpers.paths import ROOT

EXAMPLES = ROOT / "docs" / "examples"
NOTEBOOKS = sorted(EXAMPLES.glob("*.py"))
#: notebooks over ~5 s of CPU on one core (a local Dask cluster starts worker processes)
SLOW = {"sweep_on_dask"}
#: seconds a cell may take before the run is called hung
CELL_TIMEOUT_S = 300


@pytest.fixture(autouse=True)
def _this_python_kernel(monkeypatch):
    # the kernel named python3 is this interpreter's (ipykernel's spec, "python" replaced by sys.executable);
    # searched first, so a personal python3 kernel elsewhere (~/.local/share/jupyter) cannot shadow it
    monkeypatch.setenv("JUPYTER_PATH", str(pathlib.Path(sys.prefix) / "share" / "jupyter"))


class _SlicedShellChannel(AsyncZMQSocketChannel):
    """The shell channel, polled in quarter-second slices up to the caller's timeout.

    One run of the widget notebook in 5 to 10 got its cell's execute_reply only when nbclient's single long
    poll ran out (300 s; then no error, the cell had run: nbclient issue 312, where nbclient answers the
    Output widget on the same socket meanwhile): the descriptor's wake-up was missed, the message was there.
    Polled in slices, 16 of 16 runs were clean against 2 stalls in 14 before."""

    async def get_msg(self, timeout: float | None = None) -> dict:
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            left = 0.25 if deadline is None else min(0.25, max(0.0, deadline - time.monotonic()))
            try:
                return await super().get_msg(timeout=left)
            except Empty:
                if deadline is not None and time.monotonic() >= deadline:
                    raise


class _KernelClient(AsyncKernelClient):
    shell_channel_class = Type(_SlicedShellChannel)


def _execute(path: pathlib.Path, folder: pathlib.Path):
    notebook = jupytext.read(path)
    # the kernel's channels are Unix sockets (a TCP port picked, then released, can be taken by a Dask worker
    # meanwhile), in a short folder of their own: a Unix socket's path is limited to about 100 bytes
    with tempfile.TemporaryDirectory(prefix="nb") as sockets:
        kernel = AsyncKernelManager(kernel_name="python3", transport="ipc", ip=os.path.join(sockets, "k"))
        kernel.client_factory = _KernelClient
        client = nbclient.NotebookClient(
            notebook,
            km=kernel,
            timeout=CELL_TIMEOUT_S,
            kernel_name="python3",
            resources={"metadata": {"path": str(folder)}},
        )
        return client.execute()


CHECKOUT = EXAMPLES.parents[1]
#: the notebooks that write files, and the files each writes into its own folder
WRITES = {
    "audit_your_model": {"two_blocks.xml", "audit.png"},
    "fit_a_measurement": {"decay.csv", "fit.png"},
    "sweep_on_dask": {"sweep.png"},
}


def _untouched() -> tuple:
    """What running a notebook must not change: every file of the examples folder (name, size, modification
    time) and the checkout's `git status` (ignored files included), but for Python's bytecode caches: the
    interpreter writes them (here and in the other test processes, whenever a module is first imported; make
    test turns them on), never a notebook."""
    files = sorted((str(p.relative_to(EXAMPLES)), p.stat().st_size, p.stat().st_mtime_ns) for p in EXAMPLES.rglob("*"))
    status = subprocess.run(
        ["git", "-C", str(CHECKOUT), "status", "--porcelain", "--ignored", "--untracked-files=all"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    return files, [line for line in status.splitlines() if "__pycache__/" not in line]


def _written(folder: pathlib.Path, stem: str) -> set[str]:
    """The files in the notebook's own temporary folder(s) under `folder` ('audit-your-model-*': Dask's scratch
    space beside it is not the notebook's)."""
    return {p.name for own in folder.glob(f"{stem.replace('_', '-')}-*") for p in own.rglob("*") if p.is_file()}


@pytest.mark.parametrize(
    "path", [pytest.param(p, marks=pytest.mark.slow) if p.stem in SLOW else p for p in NOTEBOOKS], ids=lambda p: p.stem
)
def test_notebook_runs_top_to_bottom_and_writes_nothing_into_the_checkout(path, tmp_path, monkeypatch):
    # run where it lives (the checkout), its temporary folder under the test's so the test can see it and
    # pytest removes it
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    before = _untouched()
    notebook = _execute(path, EXAMPLES)
    assert _untouched() == before, f"{path.name} wrote into the checkout"
    assert _written(tmp_path, path.stem) == WRITES.get(path.stem, set())
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert code and all(cell.execution_count for cell in code), "a code cell did not run"
    assert any("assert " in cell.source for cell in code), f"{path.name} checks no claim"
    errors = [out for cell in code for out in cell.get("outputs", []) if out.output_type == "error"]
    assert not errors


@pytest.mark.slow
def test_jupytext_execute_runs_a_notebook_as_the_docs_say(tmp_path, monkeypatch):
    """`jupytext --to ipynb --execute` (nbconvert, from the notebooks extra) on the audit notebook: the .ipynb it
    writes has every cell run without an error, and the notebook's own files are in their own folder."""
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    copy = tmp_path / "audit_your_model.py"
    copy.write_text((EXAMPLES / "audit_your_model.py").read_text())
    done = subprocess.run(
        [sys.executable, "-m", "jupytext", "--to", "ipynb", "--execute", copy.name],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=CELL_TIMEOUT_S,
    )
    assert done.returncode == 0, done.stderr
    notebook = jupytext.read(tmp_path / "audit_your_model.ipynb")
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert code and all(cell.execution_count for cell in code)
    assert not [out for cell in code for out in cell.get("outputs", []) if out.output_type == "error"]
    assert {p.name for p in tmp_path.iterdir() if p.is_file()} == {"audit_your_model.py", "audit_your_model.ipynb"}
    assert _written(tmp_path, "audit_your_model") == WRITES["audit_your_model"]


def test_a_failing_claim_fails_the_notebook(tmp_path):
    # the runner must surface an assertion in a cell as a failure, or the tests above prove nothing
    broken = tmp_path / "broken.py"
    broken.write_text("# %%\nx = 1\n\n# %%\nassert x == 2, 'the claim'\n")
    with pytest.raises(nbclient.exceptions.CellExecutionError, match="the claim"):
        _execute(broken, tmp_path)


def test_the_examples_are_found():
    assert {"damping_slider", "car_suspension", "audit_your_model", "fit_a_measurement", "sweep_on_dask"} <= {
        p.stem for p in NOTEBOOKS
    }
