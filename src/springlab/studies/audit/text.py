"""The audit in words: the lines `springlab audit` prints (`Audit.message`), all of them here.

`message(audit)` is one line per finding, in this order: the modes and whether the motion is linear; what
holds the operating point and the motion; warnings about the point (not at rest, constraints active, dry
friction); the model's own setting (stable or not, its margin, its error against tol); what the start did
not move; the cheapest setting meeting tol; then notes (unconfirmed limits, solref time constants shorter
than 2 dt, an unconverged reference). Each line comes from one function below, reading only the facts that
`AuditFacts` names.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

from springlab.exact.linearize import Linearization, Mode
from springlab.studies.settings import Recommendation, Run

from .limits import ConstraintFlag, Limit
from .parts import Excitation, OwnSetting, PointReport, ReferenceUsed

#: the line (and the recommendation's text) when the start moves nothing
NO_MOTION = "no motion: nothing was verified (the fine run from the start barely moves)"
#: the recommendation's text when no swept setting meets tol
NO_PICK = "no swept setting meets tol {tol:g} (verified runs); try --dt lower or a longer grid"


class AuditFacts(Protocol):
    """What the text reads of an audit (`springlab.studies.audit.results.Audit` has all of it)."""

    @property
    def model(self) -> str: ...
    @property
    def linear(self) -> Linearization: ...
    @property
    def duration(self) -> float: ...
    @property
    def tol(self) -> float: ...
    @property
    def perturb(self) -> float: ...
    @property
    def stability(self) -> Mapping[str, Limit]: ...
    @property
    def own(self) -> OwnSetting: ...
    @property
    def constraints(self) -> Sequence[ConstraintFlag]: ...
    @property
    def is_linear(self) -> bool: ...
    @property
    def reference(self) -> ReferenceUsed: ...
    @property
    def recommendation(self) -> Recommendation[Run]: ...
    @property
    def point_state(self) -> PointReport: ...
    @property
    def excitation(self) -> Excitation: ...


def mode_count(modes: Sequence[Mode]) -> str:
    """'6 modes (2 rigid)': how the text and audit.png count the modes (a complex pair is one mode)."""
    rigid = sum(m.kind == "rigid" for m in modes)
    return f"{len(modes)} mode{'s' if len(modes) != 1 else ''}" + (f" ({rigid} rigid)" if rigid else "")


def message(audit: AuditFacts) -> str:
    """A few lines for people (what `springlab audit` prints): modes, what holds the operating point, the own
    setting's margin and error, the recommendation, warnings (not at rest, no motion, broken constraints, an
    unconverged reference)."""
    lines = [headline(audit), *point_lines(audit), own_line(audit)]
    lines += excitation_lines(audit.excitation)
    lines += recommendation_lines(audit)
    lines += notes(audit)
    return "\n".join(lines)


def headline(audit: AuditFacts) -> str:
    """'MODEL: N modes, fastest F Hz (kind, zeta Z); U physically unstable ...; linear along the motion'."""
    modes = audit.linear.modes
    fastest = audit.linear.fastest
    unstable = sum(m.physically_unstable for m in modes)
    head = f"{audit.model}: {mode_count(modes)}"
    if fastest is not None:
        zeta = "" if fastest.damping_ratio is None else f", zeta {fastest.damping_ratio + 0.0:.3g}"  # no -0
        head += f", fastest {fastest.frequency_hz:.4g} Hz ({fastest.kind}{zeta})"
    else:
        head += ", all rigid"
    if unstable:
        head += f"; {unstable} physically unstable (the model's own dynamics, not the integrator)"
    return f"{head}; {'linear' if audit.is_linear else 'nonlinear'} along the motion"


def point_lines(audit: AuditFacts) -> list[str]:
    """What holds the operating point and the motion, and the warnings about them."""
    state = audit.point_state
    where = audit.linear.point.label
    lines = [f"at {where}: {state.at_point.describe()}; along the motion: {state.along_motion.describe()}"]
    if not state.at_rest:
        lines.append(
            f"warning: the operating point is not at rest (it drifts {state.drift_m:.2g} m or rad over"
            f" {audit.duration:g} s, more than --perturb {audit.perturb:g}): the modes are those of the motion"
            f" through it, not of an equilibrium{settling_advice(audit)}"
        )
        lines += creep_lines(audit)
    if not state.linear_map:
        lines.append(
            "constraints, contacts or dry friction are active, so the linear map is not the dynamics:"
            " the stability limits come from nonlinear runs (bisection of blow-up), the predictions are estimates"
        )
    dry = state.along_motion.dry_friction
    if dry:
        lines.append(
            f"dry friction ({len(dry)}: {dry[0]}...): sticking and slipping are not in the modes; limits and errors"
            " are measured by runs"
        )
    return lines


def settling_advice(audit: AuditFacts) -> str:
    """'; settling longer may bring it to rest (...)' only where a run from the point shows its motion dying out."""
    state = audit.point_state
    if state.creep:
        return "; settling longer does not bring it to rest: it creeps (below)"
    if state.settling_helps is None:
        return ""
    if not state.settling_helps:
        return (
            f"; settling longer does not help: a {audit.duration:g} s run from it moves as much over its second half"
            " as over its first"
        )
    how = "settling longer" if state.settle_s else "--settle SECONDS"
    return f"; {how} may bring it to rest (a {audit.duration:g} s run from it moves less than half as much over its second half)"


def creep_lines(audit: AuditFacts) -> list[str]:
    """One line per creeping body: its speed, its Coulomb margin, that it is MuJoCo's model error, what to run."""
    lines = []
    for finding in audit.point_state.creep:
        lost = f"; it leaves its grip at t = {finding.lost_at_s:.3g} s" if finding.lost_at_s is not None else ""
        lines.append(
            f"friction creep: {finding.body!r} slides at {_speed(finding.speed_m_s)} under dry friction though Coulomb"
            f" friction holds it (margin {finding.coulomb_margin:.3g}x){lost}. That is MuJoCo's soft-friction model"
            " error: the integrator and timestep do not remove it; `springlab friction-settings"
            f" {_model_argument(audit.model)}` measures it and finds the settings that stop it"
        )
    return lines


def _speed(value: float) -> str:
    return f"{value * 1e3:.3g} mm/s" if abs(value) >= 1e-4 else f"{value * 1e6:.3g} um/s"


def _model_argument(model: str) -> str:
    """The model as friction-settings takes it: the path of a model file, else MODEL.xml."""
    return model if model.lower().endswith((".xml", ".urdf", ".mjcf")) else "MODEL.xml"


def own_line(audit: AuditFacts) -> str:
    """'your setting, INTEGRATOR at DT ms, <stability>; its error over T s is E (meets tol)'."""
    own = audit.own
    error = "not compared" if own.error is None else f"{own.error:.2g}"
    meets = "" if own.error is None else (" (meets tol)" if own.error <= audit.tol else " (misses tol)")
    return (
        f"your setting, {own.integrator} at {own.dt * 1e3:.3g} ms, {own_stability(audit)};"
        f" its error over {audit.duration:g} s is {error}{meets}"
    )


def own_stability(audit: AuditFacts) -> str:
    """Whether the own setting is stable, and its margin where runs confirm the limit behind it."""
    own = audit.own
    limit = audit.stability[own.integrator]
    figure = limit.limit_dt_s
    how = f"{limit.method}, {'confirmed by runs' if limit.confirmed else 'UNCONFIRMED'}"
    if not own.stable:
        confirmed = f" (limit {figure:.3g} s, {how})" if figure is not None and limit.confirmed else ""
        shown = {
            "blows up": "blows up",
            "spins": "spins (a hinge turns over and keeps turning)",
            "saturates": f"saturates (it grows {own.growth or 0:.3g}-fold from its start, then stops growing)",
            "grows": f"grows ({own.growth or 0:.3g}-fold from its start, still growing at its end)",
            "bounded": "stays bounded over its steps, though runs just above the limit grow",
        }[own.behaviour]
        past = f", {own.dt / figure:.3g}x its limit" if figure is not None and limit.confirmed else ""
        return f"is UNSTABLE{past}: a run of it {shown}{confirmed}"
    if figure is None:
        bounded = limit.runs_bounded_dt_s
        text = "has no stability limit up to the duration"
        if limit.method == "nonlinear runs" and bounded is not None:
            text = f"has no stability limit: no run blew up up to {bounded:.3g} s"
        if audit.linear.fastest is None and limit.method != "nonlinear runs":
            text += " (every mode is rigid: no time scale for a timestep to miss)"
        return text
    if limit.confirmed:
        return f"is stable with margin {figure / own.dt:.3g}x (limit {figure:.3g} s, {how})"
    return f"is stable (its run stays bounded); limit {figure:.3g} s UNCONFIRMED by runs, no margin claimed"


def excitation_lines(excitation: Excitation) -> list[str]:
    """Nothing moved (nothing verified), or which degrees of freedom the start left still."""
    if not excitation.any_motion:
        return [NO_MOTION]
    if not excitation.still:
        return []
    names = ", ".join(excitation.still[:3]) + (" ..." if len(excitation.still) > 3 else "")
    count = len(excitation.still)
    return [
        f"note: {count} degree{'s' if count != 1 else ''} of freedom barely moved ({names}): no error covers"
        f" {'them' if count != 1 else 'it'}"
    ]


def recommendation_lines(audit: AuditFacts) -> list[str]:
    """The cheapest setting meeting tol and its counted work beside the own setting's, or that none does."""
    pick, own = audit.recommendation, audit.own
    if not audit.excitation.any_motion:
        return []
    if pick.integrator is None or pick.dt is None or pick.error is None or pick.cost is None:
        return [pick.text]
    ratio = f" at {pick.cost / own.cost:.2g}x the counted work of yours" if own.cost > 0 else ""
    verified = "verified by a run"
    if audit.point_state.creep:
        verified += (
            ", against a converged run of the same soft-friction model, which creeps just as much: this error does"
            " not see the creep, and this setting does not stop it"
        )
    return [
        f"cheapest meeting tol {audit.tol:g}: {pick.integrator} at {pick.dt * 1e3:.3g} ms, error"
        f" {pick.error:.2g}{ratio} ({verified})"
    ]


def notes(audit: AuditFacts) -> list[str]:
    """Unconfirmed limits, solref time constants shorter than 2 dt, an unconverged reference."""
    lines = []
    unconfirmed = [n for n, lim in audit.stability.items() if lim.limit_dt_s is not None and not lim.confirmed]
    if unconfirmed:
        lines.append(f"unconfirmed limits (not used for any verdict): {', '.join(unconfirmed)}")
    if audit.constraints:
        names = ", ".join(f"{c.element} ({c.timeconst_s:g} s)" for c in audit.constraints[:3])
        more = f" and {len(audit.constraints) - 3} more" if len(audit.constraints) > 3 else ""
        lines.append(f"solref time constants shorter than 2 dt (MuJoCo stiffens nothing, it clamps): {names}{more}")
    if not audit.reference.converged:
        lines.append(
            f"note: the RK4 reference did not converge to 1% of tol (estimate {audit.reference.error_estimate:.2g});"
            " errors below that are not resolved"
        )
    return lines
