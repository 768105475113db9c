"""A trade-off's timer replaced by one constant per step, for tests that read no wall time (as helpers/audit.py's
stub_the_timer does for the audit): `springlab.studies.tradeoff` times every run of its grid again, alone
(`springlab.sim.batch.time_run`), which only fills the wall times reported beside the runs, while its front and
its pick rank counted work (the real timer is held by tests/studies/test_tradeoff.py)."""

from springlab.sim.batch import Job

#: the wall time of one step [s] the stand-in reports
SECONDS_PER_STEP = 1e-6


def constant_time_run(job: Job, **options: object) -> float:
    """`time_run`'s stand-in: SECONDS_PER_STEP per step of `job` [s], nothing run."""
    return SECONDS_PER_STEP * job.steps
