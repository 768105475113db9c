"""Chapter 5.4: a recorded free decay "decays exponentially, while the frequency remains constant".

A student records the block of a mass-spring-damper (m = 2 kg) with a position
sensor in millimetres at an uneven ~200 Hz, starting before letting go. What are
the damping ratio, the natural frequency, and the spring and damper behind it?
springlab fits the record with MuJoCo in the loop and answers the textbook way
(logarithmic decrement, damped period), each number with its 95 % interval.

Run: python scenarios/fit_decay.py
"""

import math
import pathlib
import tempfile

import numpy as np

import springlab

# the "measurement": k = 800 N/m, d = 4 N s/m, released from 50 mm at t = 0.3 s, 0.3 mm noise
rng = np.random.default_rng(2)
time = np.cumsum(rng.uniform(0.004, 0.006, 600))
x, _ = springlab.exact.analytic.free_response(np.clip(time - 0.3, 0, None), 2.0, 800.0, 4.0, 0.05, 0.0)
position_mm = 1e3 * x + rng.normal(0, 0.3, time.size)

with tempfile.TemporaryDirectory() as folder:
    record = pathlib.Path(folder) / "decay.csv"
    record.write_text("t,x_mm\n" + "".join(f"{t:.6f},{p:.4f}\n" for t, p in zip(time, position_mm)))
    fit = springlab.fit("slider", record, map={"t": "time", "x_mm": "slider_pos"}, scale=1e-3, mass=2.0)

est, der = fit.estimates, fit.derived


def pm(q):
    """'value ± half' to two significant digits of the 95 % half-width."""
    half = (q["ci95"][1] - q["ci95"][0]) / 2
    decimals = max(0, 1 - math.floor(math.log10(half)))
    return f"{q['value']:.{decimals}f} ± {half:.{decimals}f}"


zeta = est["zeta"]["value"]
decrement = 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
print(f"record: {fit.record.time.size} samples; {'; '.join(fit.record.notes)}")
print(f"damped period T_d = {pm(der['damped_period_s'])} s (constant: the frequency does not decay)")
print(f"logarithmic decrement delta = ln(x_n / x_n+1) = {decrement:.4f}")
print(f"damping ratio zeta = delta / sqrt(4 pi^2 + delta^2) = {pm(est['zeta'])}")
print(f"natural frequency omega_n = omega_d / sqrt(1 - zeta^2) = {pm(est['omega_n'])} rad/s")
print(f"with m = 2 kg: k = m omega_n^2 = {pm(der['stiffness'])} N/m, d = 2 zeta m omega_n = {pm(der['damping'])} N s/m")
print(f"answer: {fit.verdict}")
