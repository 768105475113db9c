"""Stability limits, step maps and energy of MuJoCo's integrators, against hand-derived theory.

On m x'' + d x' + k x = 0 with omega = sqrt(k/m), zeta = d / (2 sqrt(k m)), y = omega dt
(unit oscillator below: omega = 1, so y = dt):

* euler / implicit / implicitfast: v' = (v - y x) / (1 + 2 zeta y), x' = x + y v'
  (semi-implicit Euler, damping implicit). Jury's test on its 2x2 map gives
  stability iff y^2 < 4 + 4 zeta y, i.e. y < 2 zeta + 2 sqrt(zeta^2 + 1).
* rk4: z' = R(y A) z with R(s) = 1 + s + s^2/2 + s^3/6 + s^4/24.
* discrete: backward Euler, (I - y A) z' = z.
"""

import json
import math
import time

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from helpers.contract import plain_json
from springlab import files, scenes
from springlab.errors import BadInputError
from springlab.exact.limits import stability_limit
from springlab.sim.simulate import INTEGRATORS, simulate
from springlab.studies import extremes, stability

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
EULER_FAMILY = ("euler", "implicit", "implicitfast")


@pytest.fixture
def report(stability_report):
    """`springlab stability`'s default report, computed once per session (tests/conftest.py)."""
    return stability_report


def _theory_map(integrator, zeta, y):
    """The hand-derived one-step map of the unit oscillator (see module docstring)."""
    a = np.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
    if integrator in EULER_FAMILY:
        c = 1 + 2 * zeta * y
        return np.array([[1 - y * y / c, y / c], [-y / c, 1 / c]])
    if integrator == "rk4":
        s = y * a
        return np.eye(2) + s + s @ s / 2 + s @ s @ s / 6 + s @ s @ s @ s / 24
    return np.linalg.inv(np.eye(2) - y * a)


def _independent_limit(integrator, zeta):
    """omega*dt where the map's spectral radius reaches 1, derived without simulate.stability_limit.

    Numerically, from the hand-derived maps (checked against MuJoCo's own steps in
    test_mujoco_step_map_is_the_hand_derived_map), not from the closed form the code uses:
    the first omega*dt on a log grid whose spectral radius clearly exceeds 1, refined by brentq.
    """
    if integrator == "discrete":
        return math.inf
    if integrator in EULER_FAMILY:

        def growth(h):
            # a tiny offset keeps round-off around |mu| = 1 (a neutral centre at zeta = 0) out of the sign test;
            # near the limit |mu| grows like sqrt(h - limit), so the root moves by ~1e-24
            return np.max(np.abs(np.linalg.eigvals(_theory_map(integrator, zeta, h)))) - 1 - 1e-12

        grid = np.geomspace(1e-3, 1e4, 2000)
        first = next(h for h in grid if growth(h) > 1e-9)  # clear growth, not round-off around |mu| = 1
    else:
        roots = np.roots([1.0, 2 * zeta, 1.0])

        def growth(h):
            z = np.multiply.outer(h, roots)  # the grid's steps at once: one row per h
            return np.max(np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24), axis=-1) - 1

        grid = np.geomspace(1e-3, 10.0, 20000)
        first = grid[np.argmax(growth(grid) > 1e-9)]  # the same first h, the whole grid in one call
    return brentq(growth, first / (grid[1] / grid[0]), first, xtol=1e-14)


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
def test_mujoco_step_map_is_the_hand_derived_map(integrator):
    zetas = np.array([0.0, 0.1, 1.0, 10.0])
    ys = np.array([0.01, 0.5, 1.9, 7.0])
    measured = stability.one_step_maps(integrator, zetas, ys)
    for i, zeta in enumerate(zetas):
        for j, y in enumerate(ys):
            np.testing.assert_allclose(measured[i, j], _theory_map(integrator, zeta, y), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.1, 0.5, 0.9, 1.0, 2.0, 10.0, 100.0])
@pytest.mark.parametrize("integrator", list(INTEGRATORS))
def test_stability_limit_theory_matches_an_independent_derivation(integrator, zeta):
    assert stability_limit(integrator, zeta) == pytest.approx(_independent_limit(integrator, zeta), rel=1e-9)


@pytest.mark.slow
def test_measured_boundaries_are_within_2_percent_of_theory(report):
    for integrator in INTEGRATORS:
        for zeta in (0.0, 0.1, 1.0, 10.0):
            row = report.boundary(integrator, zeta)
            theory = _independent_limit(integrator, zeta)
            assert row.theory_omega_dt == pytest.approx(theory, rel=1e-9)
            if math.isinf(theory):
                assert math.isinf(row.measured_omega_dt)  # discrete: nothing grew up to omega*dt = 1e4
            else:
                assert row.measured_omega_dt == pytest.approx(theory, rel=0.02)
            assert row.within_tolerance


@pytest.mark.slow
def test_rk4_limit_is_2_sqrt_2_undamped_and_shrinks_like_2_785_over_the_fast_root(report):
    rows = {(r.integrator, r.zeta): r.measured_omega_dt for r in report.boundaries}
    assert rows[("rk4", 0.0)] == pytest.approx(2 * math.sqrt(2), rel=0.02)
    # R(s) = 1 at s = -2.7853 (real root of (R(s) - 1)/s = s^3/24 + s^2/6 + s/2 + 1); fast root 10 + sqrt(99)
    edge = min(abs(r.real) for r in np.roots([1 / 24, 1 / 6, 1 / 2, 1]) if abs(r.imag) < 1e-9)
    assert rows[("rk4", 10.0)] == pytest.approx(edge / (10 + math.sqrt(99)), rel=0.02)


def _undamped(integrator, omega_dt, steps, x0=0.1, v0=0.0):
    scene = scenes.get("slider")
    chosen = scene.scenario("undamped")
    params = scene.resolve(chosen, {"x0": x0, "v0": v0})
    model = scene.build(params, chosen)
    m, k = float(model.body("block").mass[0]), float(model.jnt_stiffness[0])
    omega = math.sqrt(k / m)
    dt = omega_dt / omega
    run = simulate(model, integrator=integrator, dt=dt, duration=steps * dt, qpos=[x0], qvel=[v0])
    x, v = run.qpos[:, 0], run.qvel[:, 0]
    energy = 0.5 * m * v**2 + 0.5 * k * x**2  # from the state: MuJoCo's data.energy lags a step
    return x, v, energy, omega, dt


@pytest.mark.parametrize("integrator", EULER_FAMILY)
@pytest.mark.parametrize("omega_dt, v0", [(0.2, 0.0), (0.8, 0.0), (1.6, 0.0), (0.5, 0.7)])
def test_euler_energy_is_bounded_by_its_exact_modified_invariant(integrator, omega_dt, v0):
    # symplectic Euler v' = v - dt w^2 x, x' = x + dt v' keeps I = v^2 + w^2 x^2 - dt w^2 x v fixed
    # (I' - I = 0 by expansion). In (w x, v), I = u^T [[1, -y/2], [-y/2, 1]] u with eigenvalues 1 -+ y/2,
    # so 2E = |u|^2 ranges over [I/(1 + y/2), I/(1 - y/2)]: E0/(1 - y/2) is the sharp peak for v0 = 0
    x, v, energy, omega, dt = _undamped(integrator, omega_dt, 20000, v0=v0)
    invariant = v**2 + omega**2 * x**2 - dt * omega**2 * x * v
    np.testing.assert_allclose(invariant, invariant[0], rtol=1e-11)
    mass = 1.0  # slider.xml
    high = mass * invariant[0] / (2 * (1 - omega_dt / 2))
    low = mass * invariant[0] / (2 * (1 + omega_dt / 2))
    assert energy.max() <= high * (1 + 1e-11) and energy.min() >= low * (1 - 1e-11)
    # the bounds are reached, not merely respected (20000 steps sample the invariant ellipse densely)
    assert energy.max() >= high * (1 - 1e-3) and energy.min() <= low * (1 + 1e-3)
    if v0 == 0.0:
        assert high == pytest.approx(energy[0] / (1 - omega_dt / 2), rel=1e-12)


@pytest.mark.parametrize("omega_dt", [0.1, 0.5, 1.0, 2.0])
def test_rk4_undamped_energy_decays_by_the_squared_modulus_of_R_iy_per_step(omega_dt):
    # |R(iy)|^2 = (1 - y^2/2 + y^4/24)^2 + (y - y^3/6)^2 = 1 - y^6/72 + y^8/576, and R(y A) is a scaled rotation
    # in (w x, v), so E_n = E_0 |R(iy)|^(2n) exactly
    y = omega_dt
    steps = min(3000, int(600 / -math.log(1 - y**6 / 72 + y**8 / 576)))  # before E underflows
    x, v, energy, omega, dt = _undamped("rk4", omega_dt, steps)
    n = np.arange(len(energy))
    np.testing.assert_allclose(energy / energy[0], (1 - y**6 / 72 + y**8 / 576) ** n, rtol=1e-10)


@pytest.mark.parametrize("omega_dt", [0.01, 0.2, 1.0, 5.0])
def test_discrete_undamped_energy_decays_by_1_over_1_plus_omega2_dt2_per_step(omega_dt):
    # backward Euler: (I - y A) is sqrt(1 + y^2) times a rotation in (w x, v)
    steps = min(3000, int(600 / math.log1p(omega_dt**2)))  # before E underflows
    x, v, energy, omega, dt = _undamped("discrete", omega_dt, steps)
    n = np.arange(len(energy))
    np.testing.assert_allclose(energy / energy[0], (1 + omega_dt**2) ** -n.astype(float), rtol=1e-10)


@pytest.mark.slow
def test_energy_report_agrees_with_the_formulas(report):
    rows = {r.integrator: r for r in report.energy}
    assert set(rows) == set(INTEGRATORS)
    for row in rows.values():
        assert row.max_relative_deviation < 1e-9
    y = rows["rk4"].omega_dt
    assert rows["euler"].max_ratio <= 1 / (1 - y / 2) and rows["euler"].min_ratio >= 1 / (1 + y / 2)
    assert rows["rk4"].final_ratio < 1 and rows["discrete"].final_ratio < rows["rk4"].final_ratio


@pytest.mark.slow
def test_extremes_cover_stiff_light_long_and_overdamped_at_three_fractions_of_each_limit(report):
    rows = [r for r in report.extremes if r.kind == "limit"]
    cases = {r.case for r in rows}
    assert {"stiff", "light", "undamped-long", "overdamped"} <= cases
    described = " ".join(r.description for r in rows)
    for text in ("k = 1e12 N/m", "m = 1e-9 kg", "1e4 periods", "zeta = 1e4"):
        assert text in described
    for case in cases:
        for integrator in INTEGRATORS:
            assert sorted(r.fraction for r in rows if r.case == case and r.integrator == integrator) == [
                0.5,
                0.99,
                1.01,
            ]


@pytest.mark.slow
def test_every_run_just_past_a_stability_limit_is_reported_diverged(report):
    past = [r for r in report.extremes if r.kind == "limit" and r.fraction > 1 and r.integrator != "discrete"]
    assert past and all(r.outcome == "diverged" for r in past)


@pytest.mark.slow
def test_no_run_inside_a_limit_diverges_while_mujoco_values_stay_in_range(report):
    inside = [
        r
        for r in report.extremes
        if r.kind == "limit" and r.case != "stiff-large-x0" and (r.fraction < 1 or r.integrator == "discrete")
    ]
    assert inside and all(r.outcome != "diverged" for r in inside)


@pytest.mark.slow
def test_mujoco_value_limit_diverges_at_any_timestep_and_the_advice_says_rescale(report):
    # k = 1e12 N/m, x0 = 0.1 m: |qacc| = 1e11 m/s^2 > mjMAXVAL = 1e10, which MuJoCo treats as a blow-up
    rows = [r for r in report.extremes if r.case == "stiff-large-x0"]
    assert len(rows) == 15 and all(r.outcome == "diverged" for r in rows)
    assert all("BADQACC" in r.detail and "rescale" in r.advice for r in rows)


@pytest.mark.slow
def test_every_row_is_classified_with_its_error_or_its_divergence_and_one_piece_of_advice(report):
    for r in report.extremes:
        if r.outcome == "diverged":
            assert r.max_rel_error is None and "diverged" in r.detail
        else:
            assert math.isfinite(r.max_rel_error) and r.detail == ""
            assert (r.max_rel_error <= extremes.ACCURACY) == (r.outcome == "accurate")
        assert r.advice and "\n" not in r.advice


@pytest.mark.slow
def test_the_advised_settings_are_accurate_when_run_over_the_whole_case(report):
    # cheap advice is run by default (the 1e4-period rk4 run of 1.1e6 steps only with --full)
    advised = {r.case: r for r in report.extremes if r.kind == "advised"}
    assert {"stiff", "light", "overdamped"} <= set(advised)
    for case in extremes.EXTREME_CASES:
        if case.name in advised:
            row = advised[case.name]
            assert row.outcome == "accurate" and row.max_rel_error <= extremes.ACCURACY
            assert row.duration == pytest.approx(case.duration, rel=0.01)


def test_the_advice_is_the_least_counted_work_and_no_timer_changes_it(report, monkeypatch):
    # the advice ranks settings by counted work (steps x model evaluations per step: rk4 4, the others 1), so a
    # noisy or busy machine cannot flip it: with clocks that return noise, every case still gets the report's advice
    rng = np.random.default_rng(0)
    monkeypatch.setattr(time, "perf_counter", lambda: float(rng.uniform(0.0, 1e3)))
    monkeypatch.setattr(time, "process_time", lambda: float(rng.uniform(0.0, 1e3)))
    picks = {}
    for case in extremes.EXTREME_CASES:
        pick = picks[case.name] = extremes._advice(case, extremes._case_model(case))
        if pick["integrator"] is None:
            continue
        assert any(pick["phrase"] in r.advice for r in report.extremes if r.case == case.name)
        evaluations = {"rk4": 4, "implicitfast": 1, "discrete": 1}[pick["integrator"]]
        assert pick["cost"] == pick["steps"] * evaluations
    overdamped = picks["overdamped"]
    # zeta = 1e4: discrete (backward Euler) holds the accuracy at dt up to 53 s (docs/stability.md's extremes
    # table), the implicit Euler family only up to about 10 s, so discrete takes the fewest model evaluations
    assert overdamped["integrator"] == "discrete"


def _fast_mode(scenario):
    scene = scenes.get("slider")
    return scene.case(scenario).modes()


@pytest.mark.parametrize("scenario", ["free", "undamped", "critical", "overdamped", "step", "harmonic"])
@pytest.mark.parametrize("integrator", ["euler", "implicit", "implicitfast", "rk4"])
def test_a_diverged_run_always_exits_3_and_writes_nothing(tmp_path, cli, integrator, scenario):
    # 5 % past the tightest mode's limit, 3000 steps: the growth must be caught, however MuJoCo reacts
    dt = 1.05 * min(stability_limit(integrator, zeta) / omega for omega, zeta in _fast_mode(scenario))
    dt = float(dt)
    out = tmp_path / "d"
    code, _, err = cli(
        "run",
        "slider",
        scenario,
        "--integrator",
        integrator,
        "--dt",
        repr(dt),
        "--duration",
        repr(3000 * dt),
        "--output",
        str(out),
    )
    assert code == 3, err
    assert err.count("\n") == 1 and "diverged" in err and "Traceback" not in err
    assert not out.exists() or not any(out.iterdir())


@pytest.mark.parametrize("integrator", list(INTEGRATORS))
def test_a_run_beyond_mujocos_value_limit_exits_3_for_every_integrator(cli, integrator):
    code, _, err = cli(
        "run",
        "slider",
        "free",
        "--integrator",
        integrator,
        "--dt",
        "1e-8",
        "--duration",
        "1e-5",
        "--set",
        "stiffness=1e12",
        "--set",
        "x0=0.1",
    )
    assert code == 3 and "diverged" in err


@pytest.mark.slow
def test_stability_cli_prints_json_and_writes_the_charts(stability_command, report):
    # the session's run of the command (tests/conftest.py), its report the session's `report`
    (code, out, err), folder = stability_command
    assert code == 0, err
    data = json.loads(out)
    assert data == files.json_ready(report.to_dict())  # --json prints the report's to_dict(), inf as null
    assert {"boundaries", "extremes"} <= set(data)
    for row in data["boundaries"]:
        assert {"integrator", "zeta", "measured_omega_dt", "theory_omega_dt"} <= set(row)
    zetas = {row["zeta"] for row in data["boundaries"]}
    assert {0.0, 0.1, 1.0, 10.0} <= zetas
    assert json.loads((folder / "stability.json").read_text()) == data
    for name in ("stability.png", "energy.png"):
        assert (folder / name).read_bytes()[:8] == PNG_SIGNATURE


#: stability.json's keys: the report's to_dict() keeps every one, in this order
REPORT_KEYS = [
    *("question", "answer", "answer_numbers"),
    *("boundaries", "extremes", "energy", "growth_test", "accuracy_threshold", "wall_time_s"),
]
BOUNDARY_KEYS = [
    "integrator",
    "zeta",
    "measured_omega_dt",
    "theory_omega_dt",
    "relative_difference",
    "within_tolerance",
]
EXTREME_KEYS = [
    "kind",
    "case",
    "description",
    "integrator",
    "fraction",
    "limit_of",
    "omega_dt",
    "limit_omega_dt",
    "dt",
    "duration",
    "steps",
    "outcome",
    "max_rel_error",
    "detail",
    "advice",
]
ENERGY_KEYS = ["integrator", "omega_dt", "steps", "final_ratio", "min_ratio", "max_ratio", "formula"]


@pytest.mark.slow
def test_the_report_is_an_object_whose_to_dict_keeps_every_key_of_stability_json(report):
    data = report.to_dict()
    assert list(data) == REPORT_KEYS and plain_json(data)
    assert all(list(row) == BOUNDARY_KEYS for row in data["boundaries"])
    assert all(list(row) == EXTREME_KEYS for row in data["extremes"])
    for row in data["energy"]:
        tail = ["formula_low", "formula_high"] if row["integrator"] in EULER_FAMILY else ["formula_final_ratio"]
        assert list(row) == [*ENERGY_KEYS, *tail, "max_relative_deviation"]
    # the attributes are the JSON's rows; the exit code's fact is every boundary within its tolerance
    assert [b.to_dict() for b in report.boundaries] == data["boundaries"]
    assert report.passed == all(row["within_tolerance"] for row in data["boundaries"])
    assert report.boundary("rk4", 0.0).measured_omega_dt == pytest.approx(2 * math.sqrt(2), rel=0.02)
    with pytest.raises(KeyError):
        report.boundary("rk4", 0.3)
    # the energy series the chart draws agree with the checks the JSON holds
    series = report.energy_histories
    for check in report.energy:
        assert series.ratio[check.integrator][-1] == check.final_ratio
        if check.integrator in EULER_FAMILY:
            assert series.bounds[check.integrator] == (check.formula_low, check.formula_high)
        else:
            assert series.exact[check.integrator][-1] == check.formula_final_ratio


@pytest.mark.slow
def test_the_report_cannot_be_changed_once_returned(report):
    import dataclasses

    for target, name in (
        (report, "boundaries"),
        (report.boundaries[0], "measured_omega_dt"),
        (report.extremes[0], "outcome"),
        (report.energy[0], "final_ratio"),
        (report.energy_histories, "omega_dt"),
    ):
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(target, name, 0.0)
    with pytest.raises(ValueError, match="read-only"):
        report.energy_histories.ratio["rk4"][0] = 0.0
    with pytest.raises(TypeError):
        report.energy_histories.ratio["rk4"] = None


@pytest.mark.slow
def test_the_reports_tables_come_out_as_data_frames_row_for_row(report):
    data = report.to_dict()
    for table in ("boundaries", "extremes", "energy"):
        frame = report.to_pandas(table)
        assert len(frame) == len(data[table])
        for record, row in zip(frame.to_dict("records"), data[table]):
            for key, value in row.items():
                same = record[key] == value or (value is None and record[key] != record[key])
                nan_like = isinstance(value, float) and math.isnan(value) and record[key] != record[key]
                assert same or nan_like, (table, key, row)
    boundaries = report.to_pandas()  # the default: the boundaries
    assert list(boundaries.columns) == BOUNDARY_KEYS
    assert set(boundaries["integrator"]) == set(INTEGRATORS)
    with pytest.raises(BadInputError, match="unknown table"):
        report.to_pandas("modes")


def test_the_declared_oscillator_is_the_textbook_mass_spring_damper():
    # the studies read the scene that declares Scene.oscillator by the names it declares: its free scenario
    # at m, k, d, x0, v0 must move as m x'' + d x' + k x = 0 from (x0, v0), checked against expm
    mass, stiffness, damping, x0, v0 = 2.0, 800.0, 4.0, 0.05, 0.3
    oscillator = extremes.build_oscillator(mass=mass, stiffness=stiffness, damping=damping, x0=x0, v0=v0)
    case, model = oscillator.case, oscillator.model
    assert case.scene.oscillator == oscillator.spec and model.nv == 1
    assert oscillator.spec.constants(model) == (mass, stiffness, damping)
    dt, steps = 1e-4, 5000
    setup = case.setup(steps, dt)
    run = simulate(
        model, integrator="rk4", dt=dt, duration=steps * dt, qpos=setup.qpos, qvel=setup.qvel, control=setup.control
    )
    system = np.array([[0.0, 1.0], [-stiffness / mass, -damping / mass]])
    every = slice(None, None, 50)  # 101 of the 5001 states
    exact = np.array([expm(system * t) @ [x0, v0] for t in run.time[every]])
    # RK4 at omega dt = 2e-3: its error, ~(omega dt)^4 omega t / 120 of the amplitude, is far below 1e-9
    np.testing.assert_allclose(run.qpos[every, 0], exact[:, 0], rtol=0, atol=1e-9 * x0)
    np.testing.assert_allclose(run.qvel[every, 0], exact[:, 1], rtol=0, atol=1e-9 * 20 * x0)
    reference = case.reference(run.time[every], dt=dt)
    np.testing.assert_allclose(reference.pos[oscillator.spec.joint], exact[:, 0], rtol=0, atol=1e-12)
