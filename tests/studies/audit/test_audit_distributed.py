"""`springlab audit` on dask workers: the same audit bit for bit as locally, the model sent as plain data.

The claim checked is exact equality of every number of audit.json (its text, whose floats are written
at full precision, compared as strings) except the stage timings: each run's trajectory depends only
on its own model and start, the workers compile the model from its file's text and named files to the
same numbers as the caller (audit_ship checks that before sending), and every reduction runs in the
caller. The cost per step is a timing of the caller's machine and decides which setting is cheapest,
so it is fixed here (the same table for both audits); it is not what the executor changes.
"""

from __future__ import annotations

import importlib
import pathlib
import pickle

import dm_control  # a test-only dependency (the `test` extra)
import mujoco
import numpy as np
import pytest

from springlab import files
from springlab.errors import BadInputError
from springlab.sim.batch import Job, run_batched
from springlab.sim.simulate import Setup
from springlab.studies.audit import ship as audit_ship
from springlab.studies.audit.audit import audit
from springlab.studies.audit.ship import AuditRun, Runner, RunsChunk, cut, runs_chunk, ship
from springlab.studies.executor import Executor

pytest.importorskip("distributed", reason="the distributed extra (make test installs it)")

SUITE = pathlib.Path(dm_control.__file__).parent / "suite"
#: a fixed cost per step [s] per integrator, in place of the caller's timing (module docstring)
COSTS = {"euler": 1.0e-6, "implicit": 1.3e-6, "implicitfast": 1.1e-6, "rk4": 3.9e-6, "discrete": 1.0e-6}


@pytest.fixture(scope="module")
def cluster(dask_cluster):
    """The session's LocalCluster of 2 worker processes (one thread each; tests/conftest.py)."""
    return dask_cluster


@pytest.fixture
def fixed_costs(monkeypatch):
    module = importlib.import_module("springlab.studies.audit.audit")  # the package's `audit` attribute is the function
    monkeypatch.setattr(module, "cost_per_step", lambda model, start, name, dt: COSTS[name])


def _json_without_timings(result) -> str:
    data = result.to_dict()
    data.pop("timings_s")
    return files.dumps(data)


def _twice(cluster, model, **options):
    """(local audit, audit on the cluster, chunks the cluster ran)."""
    local = audit(model, **options)
    ran = []
    cluster.on_result = ran.append
    try:
        remote = audit(model, executor=cluster, **options)
    finally:
        cluster.on_result = None
    return local, remote, ran


@pytest.mark.slow
def test_slider_audit_on_two_workers_equals_the_local_audit(cluster, fixed_costs):
    local, remote, ran = _twice(cluster, "slider", duration=1.0, dts=[0.004, 0.002, 0.001])
    assert ran  # the confirmation runs and the sweep went to the workers
    assert _json_without_timings(remote) == _json_without_timings(local)
    assert [r.error for r in remote.runs] == [r.error for r in local.runs]
    assert remote.recommendation == local.recommendation and remote.recommendation.verified


@pytest.mark.slow
def test_dm_control_cartpole_with_its_included_files_audits_identically_on_two_workers(cluster, fixed_costs):
    # cartpole.xml includes ./common/{visual,skybox,materials}.xml: the workers have only the shipped text;
    # a large push makes it nonlinear, so the converged RK4 reference's levels run on the workers too
    path = str(SUITE / "cartpole.xml")
    local, remote, ran = _twice(cluster, path, duration=0.5, dts=[0.01, 0.005, 0.0025], perturb=0.3, tol=1e-2)
    assert not local.is_linear and local.reference.kind.startswith("RK4")
    assert ran
    assert _json_without_timings(remote) == _json_without_timings(local)
    for name in local.stability:
        assert remote.stability[name] == local.stability[name]


MESH_OBJ = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
PART_XML = """<mujoco><worldbody><body name="arm" pos="0 0 1"><joint name="hinge" type="hinge" axis="0 1 0"
  damping="0.1"/><geom type="mesh" mesh="tetra" density="1000"/></body></worldbody></mujoco>"""
MAIN_XML = """<mujoco><compiler meshdir="meshes"/><option timestep="0.002"/>
  <asset><mesh name="tetra" file="tetra.obj"/></asset><include file="parts/arm.xml"/></mujoco>"""


def test_a_model_with_an_include_and_a_mesh_travels_as_text_and_bytes_and_runs_identically(tmp_path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "parts").mkdir()
    (tmp_path / "meshes" / "tetra.obj").write_text(MESH_OBJ)
    (tmp_path / "parts" / "arm.xml").write_text(PART_XML)
    (tmp_path / "robot.xml").write_text(MAIN_XML)
    model = mujoco.MjModel.from_xml_path(str(tmp_path / "robot.xml"))
    payload = pickle.loads(pickle.dumps(ship(("path", str(tmp_path / "robot.xml")), model)))
    assert set(payload.assets) >= {"meshes/tetra.obj", "parts/arm.xml"}
    assert all(isinstance(v, bytes) for v in payload.assets.values())
    start = Setup(np.array([0.3]), np.array([0.0]), np.zeros(0), np.zeros(0))
    runs = [("euler", 0.002, 200), ("rk4", 0.004, 100), ("implicitfast", 0.001, 400)]
    audit_ship._COMPILED.clear()  # compiled from the payload alone, as on a fresh worker
    shipped = runs_chunk(
        RunsChunk(payload, tuple(AuditRun(n, dt, s, start.qpos, start.qvel, None, None) for n, dt, s in runs))
    )
    local = run_batched([Job(model, n, dt, s, start) for n, dt, s in runs])
    for a, b in zip(shipped, local):
        assert np.array_equal(a.qpos, b.qpos) and np.array_equal(a.qvel, b.qvel) and np.array_equal(a.time, b.time)


def test_a_missing_named_file_is_one_clear_error_before_any_worker_starts(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "arm.xml").write_text(PART_XML.replace('type="mesh" mesh="tetra"', 'type="sphere" size=".1"'))
    main_xml = tmp_path / "robot.xml"
    main_xml.write_text('<mujoco><include file="parts/arm.xml"/></mujoco>')
    model = mujoco.MjModel.from_xml_path(str(main_xml))
    (tmp_path / "parts" / "arm.xml").unlink()  # gone after loading: the workers could not get it
    with pytest.raises(BadInputError, match="cannot send .* to dask workers"):
        ship(("path", str(main_xml)), model)


def test_an_in_memory_mjmodel_runs_locally_but_asks_for_a_path_on_workers():
    model = mujoco.MjModel.from_xml_string(PART_XML.replace('type="mesh" mesh="tetra"', 'type="sphere" size=".1"'))
    executor = Executor(workers=2, progress=False)  # never started: the error comes first
    with pytest.raises(BadInputError, match="MjModel passed in memory cannot be sent to dask workers"):
        audit(model, duration=0.2, dts=[0.004, 0.002], integrators=["euler"], executor=executor)
    assert executor._cluster is None
    local = audit(model, duration=0.2, dts=[0.004, 0.002], integrators=["euler"], executor=Executor(progress=False))
    assert local.runs and local.runs[0].error is not None


def test_runs_are_cut_into_at_most_n_chunks_of_about_equal_steps():
    assert cut([100, 100, 100, 100], 2) == [range(0, 2), range(2, 4)]
    assert cut([3, 3, 3, 3, 3], 2) == [range(0, 2), range(2, 5)]  # the middle run's middle is at half
    assert cut([1000, 10, 10, 10], 4) == [range(0, 1), range(1, 4)]
    assert cut([5], 16) == [range(0, 1)]
    pieces = cut(list(range(1, 63)), 16)
    assert len(pieces) <= 16 and [i for p in pieces for i in p] == list(range(62))
    assert Runner(None, None).distributed is False
