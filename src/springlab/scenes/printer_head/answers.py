"""How fast can the printer head be positioned, with control? One table, every entry verified by a run.

For a carriage (the default inkjet, or the documented 3D-printer-frame preset `PRESETS["printer_frame"]`), the
time from the start of a move of move_distance until the carriage stays within +-positioning_band of the
target, for each way of moving it:

* the minimum-time bang-bang move (`move`), its belt ringing down as the damped belt does;
* the quietest bang-bang move: the shortest duration T_q beyond which no bang-bang move rings outside the band,
  whatever its phase on the belt (springlab.exact.positioning.quietest_move_time), run as `move` with the force
  lowered to 4 D M / T_q^2 (its halves rounded up to whole steps: at least T_q);
* each input shaper on the minimum-time move (`move_zv`, `move_mzv`, `move_zvd`, `move_ei`);
* the sampled PD loop on each encoder along its planned path (`feedback_motor`, `feedback_carriage`).

Each entry is a MuJoCo run of the scenario (at the scene's validated rk4, 0.1 ms) and its exact value beside
it, verified when the two agree to VERIFIED_S: for the moves
the exact ring-down of the command the run applies (positioning.positioning_time), for the loops the exact
sampled loop continued until its decay certifies it. The answer is printed as sentences, and `to_dict()` has
`question` and `answer` with the rows.

Presets (SI): `inkjet`, the MJCF's defaults (models/printer_head.xml says where each comes from);
`printer_frame`, an illustrative desktop 3D printer's toolhead axis, its values chosen, not measured:
a 0.5 kg toolhead; the motor side a 40 mm NEMA 17 stepper's rotor (about 54 g cm^2, the 17HS4401 class of
datasheets) on a 20-tooth GT2 pulley (pitch radius 6.37 mm): J / r^2 = 5.4e-6 / 6.37e-3^2 = 0.133 kg; a belt
stiffness of 10.4 kN/m, which puts the belt mode at 50 Hz (3D printers' measured resonances lie at 30-100 Hz,
the range Klipper's resonance test sweeps); damping ratio 0.1, Klipper's default `damping_ratio` for its input
shapers ("a good all-round value for most printers", Klipper's Config_Reference); and 5 m/s^2 of acceleration
(3.17 N on the 0.633 kg), a printer's `max_accel` of 5000 mm/s^2. The move and the band stay the inkjet's, so
the two columns answer the same question.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from springlab.exact import events, positioning

from .moves import belt_damping_for, belt_damping_ratio, belt_omega

__all__ = ["PRESETS", "VERIFIED_S", "PositioningTable", "Row", "positioning_table", "preset_parameters"]

#: how close MuJoCo's positioning time must come to the exact one [s] for an entry to count as verified: a
#: microsecond, against runs whose positions agree with the exact motion to about 1e-10 m at carriage speeds of
#: mm/s or more where the band is crossed (the scenarios' tests derive each case's bound)
VERIFIED_S = 1e-6


def _printer_frame() -> dict[str, float]:
    """The 3D-printer-frame preset (module docstring): masses, belt, damping for zeta = 0.1, force for 5 m/s^2."""
    carriage, motor, stiffness = 0.5, 0.133, 10.4e3
    return {
        "carriage_mass": carriage,
        "motor_mass": motor,
        "belt_stiffness": stiffness,
        "belt_damping": float(belt_damping_for(0.1, stiffness, carriage, motor)),
        "drive_force": 5.0 * (carriage + motor),
    }


#: preset name -> (what it is, parameter overrides SI)
PRESETS: dict[str, tuple[str, dict[str, float]]] = {
    "inkjet": ("the default inkjet carriage (models/printer_head.xml)", {}),
    "printer_frame": ("an illustrative 3D-printer toolhead axis (answers.py's docstring)", _printer_frame()),
}


def preset_parameters(preset: str) -> dict[str, float]:
    """The parameter overrides [SI] of a preset.

    Raises
    ------
    ValueError
        An unknown preset (the message lists them).
    """
    if preset not in PRESETS:
        raise ValueError(f"unknown preset {preset!r}; valid: {', '.join(PRESETS)}")
    return dict(PRESETS[preset][1])


@dataclasses.dataclass(frozen=True)
class Row:
    """One way to move the carriage, and its verified positioning time.

    Attributes
    ----------
    method
        What is done, in words.
    scenario
        The printer_head scenario that ran it (with `overrides`).
    overrides
        Its parameters beyond the preset's [SI].
    positioning_time_s
        MuJoCo's: the carriage inside the band for good from then on [s] (inf: not within the run).
    positioning_time_s_exact
        The exact value [s].
    note
        What else matters about it (the time it adds, a margin, a saturation), in words.
    """

    method: str
    scenario: str
    overrides: dict[str, float]
    positioning_time_s: float
    positioning_time_s_exact: float
    note: str

    @property
    def verified(self) -> bool:
        """MuJoCo's run and the exact answer agree: both finite and within VERIFIED_S of each other."""
        return (
            math.isfinite(self.positioning_time_s)
            and math.isfinite(self.positioning_time_s_exact)
            and abs(self.positioning_time_s - self.positioning_time_s_exact) <= VERIFIED_S
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON: the attributes and `verified`."""
        out = dataclasses.asdict(self)
        out["verified"] = self.verified
        for key in ("positioning_time_s", "positioning_time_s_exact"):
            out[key] = out[key] if math.isfinite(out[key]) else None
        return out


@dataclasses.dataclass(frozen=True)
class PositioningTable:
    """The answer table of one preset (module docstring).

    Attributes
    ----------
    preset
        The preset's name.
    description
        What the preset is.
    parameters
        Its resolved physical parameters [SI] (the `move` scenario's).
    belt_frequency_hz, damping_ratio
        The belt mode [Hz], [-].
    rows
        One per method, in the module docstring's order.
    """

    preset: str
    description: str
    parameters: dict[str, float]
    belt_frequency_hz: float
    damping_ratio: float
    rows: tuple[Row, ...]

    @property
    def question(self) -> str:
        """The question, with the preset's numbers."""
        p = self.parameters
        return (
            f"How fast can {self.description.split(' (')[0]} ({p['carriage_mass']:g} kg, a"
            f" {self.belt_frequency_hz:.3g} Hz belt mode with zeta = {self.damping_ratio:.2g},"
            f" {p['drive_force']:.3g} N) be positioned {p['move_distance'] * 1e3:.1f} mm away to"
            f" ±{p['positioning_band'] * 1e6:.0f} µm, by a bang-bang move, an input shaper or a feedback loop?"
        )

    @property
    def fastest(self) -> Row:
        """The verified row with the shortest positioning time."""
        return min((r for r in self.rows if r.verified), key=lambda r: r.positioning_time_s)

    def sentences(self) -> list[str]:
        """The answer, one sentence per row after the headline, times in ms."""
        best = self.fastest
        lines = [f"Fastest: {best.method}, positioned in {best.positioning_time_s * 1e3:.1f} ms."]
        for row in self.rows:
            time = (
                f"{row.positioning_time_s * 1e3:.1f} ms (exact {row.positioning_time_s_exact * 1e3:.2f} ms)"
                if math.isfinite(row.positioning_time_s)
                else "not positioned within the run"
            )
            check = "verified" if row.verified else "NOT verified"
            lines.append(f"{row.method}: {time}, {check}; {row.note}.")
        return lines

    @property
    def answer(self) -> str:
        """The sentences as one paragraph."""
        return " ".join(self.sentences())

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON: question, answer, preset, parameters, the belt mode and the rows."""
        return {
            "question": self.question,
            "answer": self.answer,
            "preset": self.preset,
            "description": self.description,
            "parameters": self.parameters,
            "belt_frequency_hz": self.belt_frequency_hz,
            "damping_ratio": self.damping_ratio,
            "rows": [row.to_dict() for row in self.rows],
        }


def _row(
    method: str, scenario: str, base: dict[str, float], overrides: dict[str, float], note: str, duration: float
) -> Row:
    """Run the scenario for `duration` [s] in MuJoCo at the scene's setting; its positioning times, exact beside."""
    from .scene import SCENE  # here: the scene module imports this package's variants, not the answers

    case = SCENE.case(scenario, base | overrides)
    run = case.simulate(SCENE.integrator, SCENE.dt, duration)
    q = case.quantities(run)
    measured, exact = q["positioning_time_s"], q.get("positioning_time_s_exact")
    if exact is None:
        # the plain move reports move + settling after it; here, as for the others, the last exit from the band
        # counted from t = 0 (a slow move's carriage is inside before its command ends), and its exact value
        exact = _move_exact(case.params, q)
        q_c, v_c = case.joint_columns(run)["carriage"]
        target, band = case.params["move_distance"], case.params["positioning_band"]
        measured = events.last_exit(run.time, q_c - target, v_c, band) if q["settled_for_good"] else math.inf
    extra = note.format(**_display_units(q)) if note else ""
    return Row(method, scenario, overrides, float(measured), float(exact), extra)


def _display_units(quantities: dict[str, Any]) -> dict[str, Any]:
    """The run's numeric quantities for the notes: times in ms (names ending _s), lengths in um (_m)."""
    scale = {"_s": 1e3, "_m": 1e6}
    return {
        name: float(value) * next((f for end, f in scale.items() if name.endswith(end)), 1.0)
        for name, value in quantities.items()
        if isinstance(value, float | int) and not isinstance(value, bool)
    }


def _move_exact(params: dict[str, float], q: dict[str, Any]) -> float:
    """The exact positioning time [s] of the `move` run's own bang-bang command (its grid-rounded time)."""
    omega, zeta = 2 * math.pi * q["natural_frequency_hz"], q["damping_ratio"]
    breaks, accelerations = positioning.bang_bang(params["move_distance"], q["move_time_s"])
    return positioning.positioning_time(omega, zeta, breaks, accelerations, params["positioning_band"])


def positioning_table(preset: str = "inkjet") -> PositioningTable:
    """Run every method on a preset and return the verified table (module docstring).

    Raises
    ------
    ValueError
        An unknown preset.
    """
    base = preset_parameters(preset)
    from .scene import SCENE  # here, as in _row

    params = SCENE.case("move", base).params
    m_c, m_m, k = params["carriage_mass"], params["motor_mass"], params["belt_stiffness"]
    total, distance, band = m_c + m_m, params["move_distance"], params["positioning_band"]
    omega = float(belt_omega(k, m_c, m_m))
    zeta = belt_damping_ratio(params["belt_damping"], k, m_c, m_m)
    quiet = positioning.quietest_move_time(omega, zeta, distance, band)
    # long enough for the slowest method to settle: the quiet move plus a few of the belt's decay times
    duration = max(0.3, 1.5 * quiet + 5.0 / (zeta * omega))
    rows = [
        _row(
            "the minimum-time bang-bang move, then the damped belt's ring-down",
            "move",
            base,
            {},
            "a move of {move_time_s:.2f} ms leaves {residual_amplitude_m:.3g} µm of ringing",
            duration,
        ),
        _row(
            f"the quietest bang-bang move (no phase rings beyond the band from T = {quiet * 1e3:.2f} ms on)",
            "move",
            base,
            {"drive_force": 4 * distance * total / quiet**2},
            "a move of {move_time_s:.2f} ms at {move_force_n:.3g} N leaves {residual_amplitude_m:.3g} µm",
            duration,
        ),
    ]
    for name in ("zv", "mzv", "zvd", "ei"):
        rows.append(
            _row(
                f"the minimum-time move shaped by {name.upper()}",
                f"move_{name}",
                base,
                {},
                "the shaper adds {shaper_duration_s:.2f} ms and leaves {residual_vibration:.2g} of the vibration",
                duration,
            )
        )
    for encoder in ("motor", "carriage"):
        rows.append(
            _row(
                f"the sampled PD loop on the {encoder} encoder along its planned path",
                f"feedback_{encoder}",
                base,
                {},
                "gain margin {gain_margin_db:.3g} dB, a path of {planned_move_time_s:.1f} ms, peak force"
                " {peak_force_n:.3g} N",
                duration,
            )
        )
    return PositioningTable(
        preset,
        PRESETS[preset][0],
        {name: params[name] for name in ("carriage_mass", "motor_mass", "belt_stiffness", "belt_damping")}
        | {name: params[name] for name in ("drive_force", "move_distance", "positioning_band")},
        omega / (2 * math.pi),
        zeta,
        tuple(rows),
    )
