"""What a frequency response cannot say about the model at its operating point, as the audit warns of it.

A linearization is the model's response to small motions about one state. It says nothing reliable when that
state is not at rest (the response is then of a motion through it, not of an equilibrium), and where contacts,
limits or dry friction act it holds only while the motion keeps them as they are: no contact made or broken, no
slip, no limit reached. `point_warnings(at, band)` names each such case in one sentence, for the terminal and
frequency.json's `warnings`.
"""

from __future__ import annotations

from springlab.exact.model_at_point import ModelAtPoint

#: the drift [m or rad] over the band's longest period above which the point is not at rest (the size of the
#: audit's default start perturbation, 1 mm or 1 mrad: a linearization probes motions of about that size)
REST_DRIFT = 1e-3


def _listed(elements: tuple[str, ...], most: int = 3) -> str:
    """'a, b, c and 2 more'."""
    shown = ", ".join(elements[:most])
    return shown + (f" and {len(elements) - most} more" if len(elements) > most else "")


def point_warnings(at: ModelAtPoint, band_hz: tuple[float, float]) -> tuple[str, ...]:
    """The warnings about `at`'s operating point for a response over `band_hz` [Hz] (empty: none).

    Parameters
    ----------
    at
        the model at its operating point (its forward pass there: `at.constraints`).
    band_hz
        (fmin, fmax) [Hz]: the drift that makes a point "not at rest" is measured over 1 / fmin.
    """
    state = at.constraints
    where = at.point.label
    period = 1.0 / band_hz[0]
    drift = state.max_abs_qvel * period + 0.5 * state.max_abs_qacc * period**2
    out = []
    if drift > REST_DRIFT:
        out.append(
            f"the operating point ({where}) is not at rest: max |qvel| {state.max_abs_qvel:.3g} m/s or rad/s and"
            f" max |qacc| {state.max_abs_qacc:.3g} m/s^2 or rad/s^2 move it {drift:.2g} m or rad over the band's"
            f" longest period, {period:.3g} s; this is the response of the motion through it, not of an equilibrium"
        )
    contacts = tuple(e for e in state.elements if e.startswith("contact"))
    if contacts:
        out.append(f"{len(contacts)} contact{'s' if len(contacts) > 1 else ''} active at {where} ({_listed(contacts)})")
    held = tuple(e.removeprefix("dry friction: ") for e in state.dry_friction)
    if held:
        out.append(
            f"dry friction holds {_listed(held)} at {where}: the response is of the stuck state; sticking and"
            " slipping are not in the linearization"
        )
    others = tuple(e for e in state.elements if not e.startswith(("contact", "dry friction")))
    if others:
        out.append(f"constraints active at {where}: {_listed(others)}")
    if not state.smooth:
        out.append(
            "the linearization is valid only for small motions that keep the contact state: no contact made or"
            " broken, no slip, no limit reached"
        )
    return tuple(out)
