"""The exact motion of a block under a spring, a constant force and Coulomb (dry) friction.

    m x'' + k x = f_c - F sgn(x'),   and at rest the block sticks while |f_c - k x| <= F

x [m] along the surface, m [kg], k [N/m] (0: no spring), f_c [N] a constant force along x
(gravity's m g sin(theta) on an incline), F [N] the friction force's bound (joint dry friction,
or mu times the normal force). Static and kinetic friction are the same F (Coulomb's model, as
MuJoCo's).

The motion is piecewise, each piece in closed form:

* a slide in direction s = +-1 feels the constant force f_c - s F, so with a spring it is
  harmonic about the centre c = (f_c - s F) / k at omega = sqrt(k / m), and without one it
  is uniformly accelerated; it ends when the velocity reaches 0 (a turning point), which a
  spring always brings and an accelerating slide never does;
* at rest the block sticks for good if the net force |f_c - k x| is within F (nothing changes
  any more: no input varies in time), otherwise it slides off in the direction of the net force.

Released from rest the spring's slides are half periods pi / omega, and each turning point is
the last one reflected through the centre: x_{n+1} = 2 c - x_n. About the equilibrium
x_eq = f_c / k the amplitude |x_n - x_eq| therefore falls by 2 F / k per half cycle, linearly,
not by a constant factor as under viscous damping, and the block stops for good at the first
turning point inside the stick zone |x - x_eq| <= F / k: after a finite number of half cycles,
at a finite time, at a position that is known in closed form (`CoulombMotion`).

The same solver gives the hold on an incline (k = 0, |f_c| <= F: no motion at all) and the
slide (k = 0, |f_c| > F: x = x0 + v0 t + (f_c - F) t^2 / (2 m) down the slope).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

#: most slide segments one motion is followed through (a frictionless spring would never stop)
MAX_SEGMENTS = 1_000_000


@dataclasses.dataclass(frozen=True)
class Segment:
    """One piece of the motion: a slide in one direction, or the final stick.

    Attributes
    ----------
    start, end
        its time span [s]; `end` is inf for a piece that lasts for ever.
    direction
        +1 or -1 for a slide (the sign of the velocity), 0 for the stick.
    x, v
        position [m] and velocity [m/s] at `start`.
    force
        the constant net force f_c - direction F [N] acting during a slide (0 for the stick).
    """

    start: float
    end: float
    direction: int
    x: float
    v: float
    force: float


class CoulombMotion:
    """The exact motion from (x0, v0) at t = 0, followed until `horizon` [s] (see the module docstring).

    Parameters
    ----------
    mass
        m [kg] (> 0).
    stiffness
        k [N/m] (>= 0).
    friction
        F [N] (>= 0), the bound of the dry-friction force.
    force
        f_c [N], the constant force along x.
    x0, v0
        initial position [m] and velocity [m/s].
    horizon
        the motion is resolved at least up to this time [s].
    """

    def __init__(
        self, mass: float, stiffness: float, friction: float, force: float, x0: float, v0: float, horizon: float
    ):
        if not mass > 0 or stiffness < 0 or friction < 0:
            raise ValueError("mass must be > 0, stiffness and friction >= 0")
        self.mass, self.stiffness, self.friction, self.force = (
            float(mass),
            float(stiffness),
            float(friction),
            float(force),
        )
        self.omega = math.sqrt(self.stiffness / self.mass) if self.stiffness > 0 else 0.0
        self.segments: tuple[Segment, ...] = tuple(self._follow(float(x0), float(v0), float(horizon)))

    # -- the pieces ------------------------------------------------------------------

    def sticks_at(self, x: float) -> bool:
        """Whether a block at rest at x [m] stays there: |f_c - k x| <= F."""
        return abs(self.force - self.stiffness * x) <= self.friction

    def _follow(self, x: float, v: float, horizon: float) -> list[Segment]:
        segments: list[Segment] = []
        t = 0.0
        while len(segments) < MAX_SEGMENTS:
            if v == 0.0:
                if self.sticks_at(x):
                    segments.append(Segment(t, math.inf, 0, x, 0.0, 0.0))
                    return segments
                direction = 1 if self.force - self.stiffness * x > 0 else -1
            else:
                direction = 1 if v > 0 else -1
            net = self.force - direction * self.friction
            duration, x_end = self._slide(x, v, net)
            segments.append(Segment(t, t + duration, direction, x, v, net))
            if not math.isfinite(duration) or t + duration > horizon:
                return segments
            t, x, v = t + duration, x_end, 0.0
        raise ValueError(f"the motion has more than {MAX_SEGMENTS} slides before t = {horizon:g} s")

    def _slide(self, x: float, v: float, net: float) -> tuple[float, float]:
        """(duration [s], position at its end [m]) of a slide from (x, v) under the constant force `net` [N]."""
        k, m = self.stiffness, self.mass
        if k == 0.0:
            acceleration = net / m
            if v == 0.0 or acceleration * v >= 0:
                return math.inf, math.nan  # pushed along its motion: it never comes to rest
            duration = -v / acceleration
            return duration, x + v * duration / 2.0  # uniformly decelerated: the mean velocity is v / 2
        centre = net / k
        if v == 0.0:
            # released from rest: half a period, ending at the reflection through the centre
            return math.pi / self.omega, 2.0 * centre - x
        # x = c + A cos(w tau) + B sin(w tau), v = -w R sin(w tau - psi) with A = R cos psi, B = R sin psi:
        # the velocity keeps its sign until w tau reaches psi modulo pi
        a, b = x - centre, v / self.omega
        phase = math.atan2(b, a) % math.pi
        return phase / self.omega, centre + a * math.cos(phase) + b * math.sin(phase)

    # -- the motion at given times ------------------------------------------------------

    def state(self, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x [m], v [m/s]) at `time` [s] (t >= 0, within the horizon or after the final stick)."""
        time = np.asarray(time, dtype=float)
        x, v = np.empty_like(time), np.empty_like(time)
        starts = np.array([s.start for s in self.segments])
        index = np.clip(np.searchsorted(starts, time, side="right") - 1, 0, len(self.segments) - 1)
        for i, segment in enumerate(self.segments):
            mask = index == i
            if not mask.any():
                continue
            tau = time[mask] - segment.start
            x[mask], v[mask] = self._on(segment, tau)
        return x, v

    def _on(self, segment: Segment, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if segment.direction == 0:
            return np.full_like(tau, segment.x), np.zeros_like(tau)
        if self.stiffness == 0.0:
            acceleration = segment.force / self.mass
            return segment.x + segment.v * tau + 0.5 * acceleration * tau**2, segment.v + acceleration * tau
        w = self.omega
        centre = segment.force / self.stiffness
        a, b = segment.x - centre, segment.v / w
        cos, sin = np.cos(w * tau), np.sin(w * tau)
        return centre + a * cos + b * sin, w * (b * cos - a * sin)

    # -- what a textbook asks -------------------------------------------------------------

    @property
    def stops(self) -> bool:
        """Whether the block comes to rest for good within the followed motion."""
        return self.segments[-1].direction == 0

    @property
    def stop_time(self) -> float:
        """When the block comes to rest for good [s] (inf: within the horizon it does not)."""
        return self.segments[-1].start if self.stops else math.inf

    @property
    def stop_position(self) -> float:
        """Where it rests for good [m] (nan: it does not)."""
        return self.segments[-1].x if self.stops else math.nan

    @property
    def turning_times(self) -> list[float]:
        """Times [s] at which a slide ends at rest (the velocity reaches 0) within the followed motion, in order:
        a slide still under way at the horizon has not turned yet (its end lies beyond the run)."""
        return [s.end for s, _ in zip(self.segments, self.segments[1:]) if s.direction != 0]

    @property
    def turning_points(self) -> list[float]:
        """Positions [m] at the turning times."""
        out = []
        for s, nxt in zip(self.segments, self.segments[1:]):
            if s.direction != 0:
                out.append(nxt.x)
        return out

    @property
    def half_cycles(self) -> int:
        """Slides that end at rest within the followed motion (with a spring: its half cycles)."""
        return len(self.turning_times)
