# ---
# jupyter:
#   jupytext:
#     formats: py:percent
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # A sweep on a Dask cluster
#
# `springlab.sweep` runs a scene over a grid of parameters, each configuration checked against its
# exact solution. It runs in this process by default, or on any `dask.distributed` cluster through an
# `Executor`, with the same numbers bit for bit. Here the cluster is a `LocalCluster` of two worker
# processes started in the notebook (`pip install 'springlab[distributed]'`); on machines of your
# own, start `dask scheduler` and `dask worker` and give the scheduler's address instead.

# %%
# %matplotlib inline
import pathlib
import tempfile

import numpy as np
from distributed import Client, LocalCluster
from IPython.display import Image

import springlab
from springlab.plots import sweep as sweep_plots
from springlab.studies.executor import Executor

cluster = LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0")
client = Client(cluster)  # in Jupyter this shows the cluster and a link to its dashboard
print(cluster.scheduler_address, len(cluster.workers), "workers")

# %% [markdown]
# The slider over damping (three values, log-spaced) and stiffness (two values), 2 s each:

# %%
VARY = {"damping": (0.5, 40.0, 3, "log"), "stiffness": (200.0, 800.0, 2)}
with Executor(scheduler=cluster.scheduler_address, progress=False) as executor:
    on_dask = springlab.sweep("slider", "free", vary=VARY, duration=2.0, chunk_size=2, executor=executor)
print(f"{on_dask.size} runs on {on_dask.executor} in {on_dask.chunks} chunks: {on_dask.passed} passed")
frame = on_dask.to_pandas()
frame[["damping", "stiffness", "damping_ratio", "regime", "slider_pos_max_rel", "passed"]]

# %%
# the files this notebook writes go to a folder of their own, never into the folder it runs in (a checkout,
# opened as the README says): a fresh temporary one, or name yours, e.g. pathlib.Path("my-results")
output = pathlib.Path(tempfile.mkdtemp(prefix="sweep-on-dask-"))
sweep_plots.plot(on_dask, output / "sweep.png", quantity="damping_ratio")
Image(output / "sweep.png")

# %% [markdown]
# *Check*: every configuration's damping ratio is d / (2 √(k m)), every run met its
# tolerance, and the same sweep in this process gives the same numbers, bit for bit.

# %%
mass = np.array([row.parameters["mass"] for row in on_dask.rows])  # [kg]
exact = frame["damping"] / (2 * np.sqrt(frame["stiffness"] * mass))
assert np.allclose(frame["damping_ratio"], exact, rtol=1e-12, atol=0)
assert on_dask.passed == on_dask.size == 6
here = springlab.sweep("slider", "free", vary=VARY, duration=2.0, chunk_size=2)
assert here.executor == "local"
assert here.to_pandas().equals(frame)
print(f"max |zeta - d / (2 sqrt(k m))| = {np.abs(frame['damping_ratio'] - exact).max():.1e}; local == dask")

# %%
client.close()
cluster.close()
