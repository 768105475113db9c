"""The human-readable answers of the `springlab` commands: tables and lines printed to stdout.

`cli` parses the arguments and calls the library; this module only formats what came back
(`--json` prints the same results machine-readably and does not come through here). Times are
printed in seconds [s] or milliseconds [ms] as each header says; errors are relative [-].
"""

from __future__ import annotations

import collections
import math
import pathlib
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from springlab.answer import Answer
from springlab.render import scale as render_scale
from springlab.runs.compare import Verdict
from springlab.runs.run import Result, ValidationRow
from springlab.scenes.declarations import Check
from springlab.studies import tradeoff
from springlab.studies.settings import COST_BASIS, Recommendation

if TYPE_CHECKING:  # annotations only: these load mujoco.batch, scipy or sysid, which the commands import lazily
    from springlab.studies.audit.results import Audit
    from springlab.studies.design.sobol import SobolStudy
    from springlab.studies.design.study import Study
    from springlab.studies.fit.results import FitResult
    from springlab.studies.frequency import FrequencyResponse
    from springlab.studies.friction_settings import FrictionSettings
    from springlab.studies.refine import Refinement
    from springlab.studies.stability import StabilityReport
    from springlab.studies.sweeps import Sweep


def print_answer(answer: Answer) -> None:
    """A study's question and its answer, the first lines it prints (the same words as its JSON's)."""
    print(answer.text())


def check_line(check: Check) -> str:
    """'period_s  value 1.234  ref 1.234  error 1.0e-09 <= 1.0e-06 pass' for a Check."""
    return (
        f"{check.name:<30} value {float(check.value):<14.10g} ref {float(check.reference):<14.10g}"
        f" error {check.error:.2e} {'<=' if check.passed else '>'} {float(check.tolerance):.2e}"
        f"  {'pass' if check.passed else 'FAIL'}"
    )


def print_list(catalogue: list[dict[str, Any]]) -> None:
    """`springlab list`: each scene's title, default setting, scenarios (validated dt [ms]) and parameters."""
    for entry in catalogue:
        print(f"{entry['scene']}: {entry['title']}")
        print(
            f"  default setting: {entry['default_integrator']}, dt = {entry['default_dt']:g} s unless a scenario says"
        )
        print("  scenarios (validated dt):")
        for name, text in entry["scenarios"].items():
            dt = entry["scenario_settings"][name]["dt"]
            print(f"    {name:<22} {f'{dt * 1e3:g} ms':>8}  {text}")
        print("  parameters:")
        for name, p in entry["parameters"].items():
            print(f"    {name:<16} [{p['unit']}] {p['description']} ({p['valid']})")


def print_run(result: Result, output: str | None) -> None:
    """`springlab run`: the question and its answer first, then the setting, quantities, errors against the
    exact solution, checks and the verdict (with what the step grid changed in the input)."""
    if result.answer is not None:
        print(result.answer.text())
    for note in result.grid_notes:
        print(f"Note: {note}")
    print(
        f"{result.scene} / {result.scenario}: {result.integrator}, dt = {result.dt:g} s,"
        f" {result.steps} steps in {result.wall_time_s * 1e3:.1f} ms"
    )
    for name, value in result.quantities.items():
        print(f"  {name:<26} {value:.10g}" if isinstance(value, float) else f"  {name:<26} {value}")
    for column, error in result.errors.items():
        print(f"  error {column:<20} max_abs {error.max_abs:.3e}  max_rel {error.max_rel:.3e}")
    for check in result.checks:
        print(f"  check {check_line(check)}")
    if result.tolerance is not None or result.checks:
        verdict = "FAIL (outside tolerance)" if result.verdict is Verdict.FAIL else str(result.verdict)
        grid = "".join(f" ({note})" for note in result.grid_notes)
        print(
            f"  tolerance {result.tolerance:.3e}: {verdict}{grid}"
            if result.tolerance is not None
            else f"  checks: {verdict}{grid}"
        )
        validity = result.estimate_range
        if validity is not None and not validity.inside:
            print(f"  basis: {validity.reason()}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'trajectory.csv'} and summary.json")


def validation_table(rows: Sequence[ValidationRow]) -> str:
    """The validate/demo table: one column says what each row's error measures (trajectory or a check)."""
    # columns as wide as their longest name, so long scenario names stay readable
    scene_width = max([12] + [len(r.scene) for r in rows]) + 1
    scenario_width = max([13] + [len(r.scenario) for r in rows]) + 1
    measures = [r.measure for r in rows]
    measure_width = max([len("error of")] + [len(m) for m in measures]) + 2
    lines = [
        f"{'scene':<{scene_width}}{'scenario':<{scenario_width}}{'integrator':<11}{'dt [s]':>9}"
        f"  {'error of':<{measure_width}}{'error':>9}{'tolerance':>11}  result"
    ]
    for r, measure in zip(rows, measures):
        lines.append(
            f"{r.scene:<{scene_width}}{r.scenario:<{scenario_width}}{r.integrator:<11}{r.dt:>9.2g}"
            f"  {measure:<{measure_width}}{r.max_rel_error:>9.2e}{r.tolerance:>11.2e}  {_row_result(r)}"
        )
        lines.extend(f"    check {check_line(c)}" for c in r.checks)
    return "\n".join(lines)


def _row_result(row: ValidationRow) -> str:
    """'pass', 'FAIL' or 'not validated' (outside the range of the error estimate) for a validate row."""
    if row.passed:
        return "pass"
    return "not validated" if row.verdict is Verdict.NOT_VALIDATED else "FAIL"


def print_validate(rows: Sequence[ValidationRow]) -> None:
    """`springlab validate`: the table, the tolerance bases, the scenarios' notes, one answer line per scenario
    and the count."""
    print(validation_table(rows))
    for basis in dict.fromkeys(r.tolerance_basis for r in rows):
        print(f"tolerance = {basis}")
    for r in rows:
        if r.note:
            print(f"{r.scene} {r.scenario}: {r.note}")
    answered = [r for r in rows if r.answer is not None and r.answer.answer]
    if answered:
        print("answers:")
        for r in answered:
            assert r.answer is not None
            print(f"  {r.scene} {r.scenario}: {r.answer.answer}")
    failed = sum(not r.passed for r in rows)
    unvalidated = sum(r.verdict is Verdict.NOT_VALIDATED for r in rows)
    outside = f" ({unvalidated} not validated: outside the range of the error estimate)" if unvalidated else ""
    print(f"{len(rows) - failed} passed, {failed} failed{outside}")


def print_render(info: dict) -> None:
    """`springlab render`: the file written, its frames and the simulated time [s] they cover."""
    scaled = "".join(f", {note}" for note in render_scale.labels(info["slow_motion"], info["exaggeration"]))
    print(
        f"wrote {info['path']}: {info['frames']} frames, {info['width']}x{info['height']} at {info['fps']:g} fps"
        f" ({info['frames'] / info['fps'] / info['slow_motion']:.3g} s of simulation{scaled})"
        f" in {info['seconds']:.1f} s ({info['frames'] / max(info['seconds'], 1e-9):.0f} frames/s)"
    )


def _run_verdict(run: tradeoff.TradeoffRun) -> str:
    """A sweep row's verdict in a word or two: pass, FAIL, not validated, beyond its stability limit, or blank
    when diverged."""
    if run.verdict is None:
        return ""
    word = {Verdict.PASS: "pass", Verdict.FAIL: "FAIL"}.get(run.verdict, "not validated")
    return f"{word}, beyond the stability limit" if run.beyond_limit else word


def _recommendation_line(pick: Recommendation, time_s: float | None) -> str:
    """The recommendation's sentence, its measured time beside it (never ranked on)."""
    measured = (
        f" Measured time of its run: {time_s * 1e3:.3g} ms." if time_s is not None and math.isfinite(time_s) else ""
    )
    return f"{pick.text}{measured}"


def print_tradeoff(result: tradeoff.Tradeoff, output: str | None) -> None:
    """`springlab tradeoff`: the question and answer, every (integrator, dt) run, the observed orders and the
    recommendation."""
    print_answer(result.question_answer)
    print(
        f"{result.scene} / {result.scenario}: {len(result.runs)} runs over {result.duration:g} s"
        f" in {result.sweep_wall_time_s:.1f} s"
    )
    print(
        f"  {'integrator':<13}{'dt [s]':>10}{'steps':>9}{'max rel err':>13}{'work':>10}{'wall [ms]':>11}"
        f"{'wall/sim s':>12}  pareto  verdict"
    )
    front = {id(r) for r in result.pareto}
    for r in result.runs:
        error = "diverged" if r.diverged else f"{r.max_rel_error:.3e}"
        print(
            f"  {r.integrator:<13}{r.dt:>10.3g}{r.steps:>9}{error:>13}{r.cost:>10.4g}{r.wall_time_s * 1e3:>11.3f}"
            f"{r.wall_time_s / result.duration * 1e3:>10.3f}ms  {'*' if id(r) in front else ' ':<6}  {_run_verdict(r)}"
        )
    orders = ", ".join(f"{name} {p:.2f}" if p is not None else f"{name} -" for name, p in result.orders.items())
    print(f"  observed order: {orders}")
    pick = result.recommendation
    if pick is not None:
        print(f"  tol {pick.tolerance:g}: {_recommendation_line(pick, pick.time_s)}")
    print(f"  work: {COST_BASIS}")
    print(f"  wall time: {tradeoff.WALL_TIME_BASIS}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'tradeoff.json'} and tradeoff.png")


def print_audit(result: Audit, output: str | None) -> None:
    """`springlab audit`: the audit's message (modes, your setting's margin and error, the cheapest setting
    meeting tol) and what was written."""
    print_answer(result.question_answer)
    print(result.message)
    if output:
        print(f"wrote {pathlib.Path(output) / 'audit.json'} and audit.png")


def print_frequency(result: FrequencyResponse, output: str | None) -> None:
    """`springlab frequency`: a few lines, the band the setting reproduces, resonances, the dt each integrator
    needs, and what was written."""
    print_answer(result.question_answer)
    print(f"{result.description} ({result.source})")
    for line in result.verdict():
        print(f"  {line}")
    for warning in result.warnings:
        print(f"  warning: {warning}")
    if output:
        extra = ", sinestream.csv" if result.sinestreams or result.sweeps else ""
        print(f"wrote {pathlib.Path(output) / 'frequency.json'}, frequency.csv{extra} and bode.png")


def print_stability(report: StabilityReport, output: str | None) -> None:
    """`springlab stability`: boundaries omega*dt [-] against theory, the extremes table, undamped energy."""
    print_answer(report.question_answer)
    print("stability boundary omega*dt (measured by a growth test vs theory)")
    print(f"  {'integrator':<13}{'zeta':>7}{'measured':>12}{'theory':>12}{'rel diff':>10}")
    for b in report.boundaries:
        print(
            f"  {b.integrator:<13}{b.zeta:>7g}{b.measured_omega_dt:>12.5g}{b.theory_omega_dt:>12.5g}"
            f"{b.relative_difference:>10.1e}"
        )
    print(f"extremes (accurate: max rel error <= {report.accuracy_threshold:g})")
    print(
        f"  {'case':<15}{'integrator':<13}{'x limit':>8}{'omega*dt':>10}{'steps':>8}  {'outcome':<11}"
        f"{'error':>9}  advice"
    )
    for r in report.extremes:
        error = "-" if r.max_rel_error is None else f"{r.max_rel_error:.1e}"
        if r.fraction is None:
            fraction = "advised"
        else:
            fraction = f"{r.fraction:g}" + ("*" if r.limit_of != r.integrator else "")
        print(
            f"  {r.case:<15}{r.integrator:<13}{fraction:>8}{r.omega_dt:>10.4g}{r.steps:>8}"
            f"  {r.outcome:<11}{error:>9}  {r.advice}"
        )
    print("  * discrete has no stability limit: fractions of the euler limit")
    print("undamped energy E/E0 vs the exact step-map formulas")
    for e in report.energy:
        print(
            f"  {e.integrator:<13} omega*dt {e.omega_dt:g}, {e.steps} steps: E/E0 in"
            f" [{e.min_ratio:.6g}, {e.max_ratio:.6g}], final {e.final_ratio:.6g};"
            f" {e.formula}: max deviation {e.max_relative_deviation:.1e}"
        )
    print(f"done in {report.wall_time_s:.1f} s")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'stability.json'}, stability.png and energy.png")


def print_design(study: Study, output: str | None) -> None:
    """`springlab design`: the question and answer, the study's size and speed, ranked elasticities [-]."""
    print_answer(study.question_answer)
    where = f" on {study.nthread} threads" if study.executor == "local" else f" on {study.executor}"
    print(
        f"{study.scene} design study: {study.size} configurations ({study.levels} levels of "
        f"{', '.join(study.design.names)}) in {study.wall_time_s:.1f} s, {study.size / study.wall_time_s:.0f}/s" + where
    )
    print(f"  {'property':<16}{'default':>11}{'range':>22}{'elasticity':>12}{'local':>9}")
    for name in study.ranking:
        grid = study.grids[name]
        unit = study.design.get(name).unit
        default = float(study.values[name][study.default_index])
        print(
            f"  {name:<16}{default:>11.4g}{f'{grid[0]:.3g}..{grid[-1]:.3g} {unit}':>22}"
            f"{study.elasticities[name]:>+12.3f}{study.local_elasticities[name]:>+9.3f}"
        )
    finite = np.isfinite(study.positioning_time_s)
    ratio = study.estimate_s[finite] / study.positioning_time_s[finite]
    print(
        f"  log-log fit R^2 {study.regression_r2:.3f}; analytic estimate / simulation: median"
        f" {float(np.median(ratio)):.3f}, 5-95% {float(np.percentile(ratio, 5)):.3f}-{float(np.percentile(ratio, 95)):.3f}"
    )
    if output:
        print(f"  wrote {pathlib.Path(output) / 'design.json'}, configurations.csv and design.png")


def print_sobol(indices: SobolStudy, output: str | None) -> None:
    """`springlab design --sobol`: first-order and total Sobol indices [-] with their 95% half-widths."""
    print_answer(indices.question_answer)
    print(
        f"Sobol indices of {indices.merit}: {indices.runs} runs in {indices.wall_time_s:.1f} s on {indices.executor}"
        f" ({indices.runs / indices.wall_time_s:.0f}/s), {indices.unsettled} unsettled"
    )
    print(f"  {'property':<16}{'range':>24}{'S1':>14}{'ST':>14}{'ST-S1':>8}{'elasticity':>12}")
    s1, s1_conf, st, st_conf = (indices.indices[key] for key in ("S1", "S1_conf", "ST", "ST_conf"))
    for name in indices.ranking:
        low, high = indices.ranges[name]
        unit = indices.units[name]
        print(
            f"  {name:<16}{f'{low:.3g}..{high:.3g} {unit}':>24}{s1[name]:>8.3f}+-{s1_conf[name]:<4.2f}"
            f"{st[name]:>8.3f}+-{st_conf[name]:<4.2f}{indices.interactions[name]:>8.3f}"
            f"{indices.elasticities[name]:>+12.3f}"
        )
    if output:
        print(f"  wrote {pathlib.Path(output) / 'sobol.png'} and the sobol entry of design.json")


def print_sweep(result: Sweep, quantity: str | None, output: str | None) -> None:
    """`springlab sweep`: counts by outcome and the range of `quantity` (default: the scenario's headline)."""
    from springlab.plots import sweep as sweep_plot  # mujoco.batch only for the command that sweeps

    print_answer(result.question_answer)
    print(
        f"{result.scene} / {result.scenario}: {result.size} configurations ({result.integrator},"
        f" dt = {result.dt:g} s, {result.duration:g} s each) in {result.wall_time_s:.2f} s on {result.executor}"
        f" ({result.configurations_per_s:.0f}/s, {result.chunks} chunks)"
    )
    print(f"  passed {result.passed}, failed {result.failed}, diverged {result.diverged}, invalid {result.invalid}")
    # why the failures failed, by kind (each row's `detail` has its own reason and numbers)
    kinds = collections.Counter(
        "diverged" if row.diverged else row.detail.split(":")[0] for row in result.rows if row.passed is False
    )
    if kinds:
        print(
            f"  not passed: {', '.join(f'{n} {kind}' for kind, n in kinds.most_common())} (each row's detail says why)"
        )
    quantity = quantity or (sweep_plot.default_quantity(result) if result.diverged < result.size else None)
    if quantity:
        values = result.column(quantity)
        finite = values[np.isfinite(values)]
        if finite.size:
            best = int(np.nanargmin(np.where(np.isfinite(values), values, np.nan)))
            where = ", ".join(f"{n} = {result.values[n][best]:.4g}" for n in result.values)
            print(f"  {quantity}: min {finite.min():.4g} (at {where}), max {finite.max():.4g}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'sweep.csv'} and sweep.png")


def print_friction_settings(study: FrictionSettings, output: str | None) -> None:
    """`springlab friction-settings`: per case MuJoCo's default, the model errors, the Pareto front and the pick."""
    integrator, dt = study.mujoco_default
    print_answer(study.question_answer)
    print(
        f"{study.scene}: {study.runs} runs in {study.wall_time_s:.1f} s ({', '.join(study.integrators)};"
        f" dt = {', '.join(f'{d:g}' for d in study.dts)} s); baseline MuJoCo's defaults ({integrator}, dt = {dt:g} s)"
    )
    for case in study.cases:
        print(f"\n{study.case_answer(case)}")
        # the settings column as wide as its longest entry: four changed settings run past 58 characters
        width = max([58, *(len(case.describe(r.settings)) + 2 for r in case.pareto)])
        print(f"  {'Pareto front':<{width}}{'integrator':<13}{'dt [s]':>9}{'error':>10}{'work':>10}{'cpu [ms]':>10}")
        for r in case.pareto:
            print(
                f"  {case.describe(r.settings):<{width}}{r.integrator:<13}{r.dt:>9.3g}{r.error:>10.2e}"
                f"{r.cost:>10.4g}{r.cpu_time_s * 1e3:>10.2f}"
            )
        if case.pick is not None and case.pick.found:
            print(f"  pick: {_recommendation_line(case.pick, case.pick.time_s)}")
    print(f"\nwork: {COST_BASIS}")
    if output:
        print(
            f"\nwrote {pathlib.Path(output) / 'friction_settings.json'}, friction_settings.csv and friction_settings.png"
        )


def print_fit(result: FitResult, output: str | None) -> None:
    """`springlab fit`: the question and answer (the verdict), the record used, each estimate with its 95%
    interval (in its unit)."""
    print_answer(result.question_answer)
    record = result.record
    print(
        f"{result.scene} / {result.scenario} from {record.column} ({record.time.size} samples,"
        f" {record.time[0]:g} to {record.time[-1]:g} s): fitted {', '.join(result.free)}"
    )
    for note in record.notes:
        print(f"  {note}" if note.startswith("warning: ") else f"  data: {note}")
    if result.release:
        print(f"  release: {result.release['reason']}")
    for name, q in {**result.estimates, **result.derived}.items():
        low, high = q["ci95"]
        unit = "" if q["unit"] == "-" else q["unit"]
        print(f"  {name:<26} {q['value']:<16.10g} 95% [{low:.8g}, {high:.8g}] {unit}")
    check = result.cross_check
    print(
        f"  closed-form cross-check: max relative difference {check['max_relative_difference']:.1e},"
        f" {check['max_difference_in_tolerances']:.2g} of its tolerance ({'agrees' if check['agrees'] else 'DISAGREES'})"
    )
    o = result.optimizer
    print(
        f"  optimizer: {o['status']} after {o['iterations']} iterations, {o['rollouts']} rollouts"
        f" of {o['steps']} steps ({o['time_per_rollout_s'] * 1e3:.1f} ms each), {o['wall_time_s']:.2f} s"
    )
    if result.starts.get("count", 1) > 1:
        from springlab.studies.fit.starts import (
            line,  # here: fit_starts loads MuJoCo's sysid machinery, needed only for a fit
        )

        print(line(result.starts))
    judged = result.convergence
    if judged and (not judged["converged"] or not judged["optimizer_met_tolerance"]):
        print(f"  convergence: {judged['reason']}")
    if result.run_note:
        print(f"  note: {result.run_note}")
    if output:
        wrote = "fit.json, fit.png" + (", trajectory.csv and summary.json" if result.run is not None else "")
        print(f"  wrote {wrote} under {output}")


def print_demo(rows: Sequence[ValidationRow], artifacts: int, out: pathlib.Path | str, seconds: float) -> None:
    """`springlab demo`: the validation table and what was written where, in how many seconds [s]."""
    print(validation_table(rows))
    failed = sum(not r.passed for r in rows)
    print(f"{len(rows) - failed} passed, {failed} failed; wrote {artifacts} files under {out}/ in {seconds:.1f} s")


def print_refine(result: Refinement, output: str | None) -> None:
    """`springlab refine`: per size the discretization error and the costs, the Pareto front, the recommendation."""
    print_answer(result.question_answer)
    size = result.size_parameter
    print(
        f"{result.scene} / {result.scenario}: {result.description} ({result.quantity}), {len(result.runs)} runs"
        f" over {result.duration:g} s in {result.sweep_wall_time_s:.1f} s"
    )
    names = list(result.cost_growth)
    print(
        f"  {size:>12}  {'w_max [1/s]':>11}  {'discretiz.':>10}  {'per step [us]':>13}  "
        + "  ".join(f"{name + ' [ms/s]':>17}" for name in names)
    )
    for cost in result.sizes:
        step = min(cost.cost_per_step_s.values(), default=float("nan")) * 1e6
        per_second = [cost.cost_per_simulated_second_s.get(name) for name in names]
        error = f"{cost.discretization_error:.3e}" if cost.discretization_error is not None else "-"
        print(
            f"  {cost.size:>12}  {cost.fastest_rate_rad_s:>11.4g}  {error:>10}  {step:>13.2f}  "
            + "  ".join(f"{v * 1e3:>17.4g}" if v is not None else f"{'no limit':>17}" for v in per_second)
        )
    order = result.discretization_order
    print(
        f"  discretization error ~ {size}^-{order:.2f} (expected {result.expected_order:g})"
        if order is not None
        else "  discretization order: too few sizes"
    )
    growth = ", ".join(f"{name} {g:.2f}" if g is not None else f"{name} -" for name, g in result.cost_growth.items())
    step_growth = result.step_cost_growth
    print(
        f"  cost per step ~ {size}^{step_growth:.2f}; per simulated second at the stability limit: {growth}"
        if step_growth is not None
        else f"  per simulated second at the stability limit: {growth}"
    )
    print("  Pareto front (error bound = discretization + integration, vs counted work; wall time beside it):")
    for run in result.pareto:
        print(
            f"    {size} = {run.size:<5} {run.integrator:<13} dt = {run.dt:<9.3g} bound {run.error_bound:.3e}"
            f" (discretization {run.discretization_error:.1e}, integration {run.integration_error:.1e};"
            f" error {run.error:.1e}) work {run.cost:.4g}, {run.wall_time_s * 1e3:.3f} ms"
        )
    pick = result.recommendation
    if pick is not None:
        line = _recommendation_line(pick, pick.time_s)
        if pick.found:
            line += f" `springlab run` at that setting: {pick.details['verdict']}."
        print(f"  tol {pick.tolerance:g}: {line}")
    print(f"  work: {COST_BASIS}")
    if output:
        print(f"  wrote {pathlib.Path(output) / 'refine.json'} and refine.png")
