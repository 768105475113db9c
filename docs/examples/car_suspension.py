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
# # The car on its suspension
#
# Chapter 5.3, "Car suspension": a car of m = 1000 kg (with its passengers) on four springs,
# k = 1e6 N/m together, no damping; four passers-by (250 kg) push it down and let go at t = 0.
# The textbook asks for the extra sag, x(t) = x_s + A cos(ω t), and the phase plane. `heave` is
# the height of the car bottom above the ground [m]. Then the same car with dampers.

# %%
# %matplotlib inline
import math

import numpy as np

import springlab
from springlab.plots import run as plots

# %%
car = springlab.run("car", "push_release")
print(car.message)
car.quantities

# %% [markdown]
# *Check* the three answers against the textbook's own arithmetic: the push's weight over the springs
# is the extra sag, x_s is the rest height (the clearance), A = -sag (the car starts below x_s), and
# ω = √(k/m). Then the whole run against x_s + A cos(ω t), written here. On this linear system one RK4
# step multiplies the state by the degree-4 Taylor polynomial of e^z (z = iω dt), which differs from e^z
# by at most |z|⁵ / 5! e^|z|; neither grows the amplitude, so after n steps the error is at most
# n |z|⁵ / 120 e^|z| |A|.

# %%
m, k, push, clearance = (car.parameters[name] for name in ("mass", "stiffness", "push_mass", "clearance"))
g = 9.81  # [m/s^2], models/car.xml's gravity
sag = push * g / k
omega = math.sqrt(k / m)
q = car.quantities
assert math.isclose(q["static_sag_m"], sag, rel_tol=1e-12)
assert math.isclose(q["height_before_release_m"], clearance - sag, rel_tol=1e-12)
assert math.isclose(q["amplitude_m"], -sag, rel_tol=1e-12)
assert math.isclose(q["omega_rad_s"], omega, rel_tol=1e-12)
height = clearance - sag * np.cos(omega * car.time)
error = np.abs(car.pos["heave"] - height).max()
z = omega * car.dt
bound = car.steps * z**5 / 120 * math.exp(z) * sag
print(f"sag {1e3 * sag:.4f} mm, omega {omega:.4f} rad/s; max |x - (x_s + A cos wt)| = {error:.1e} m <= {bound:.1e} m")
assert error <= bound

# %% [markdown]
# The phase plane: an ellipse around (x_s, 0) with semi-axes |A| and ω|A|, run clockwise.

# %%
plots.phase_plane(car)

# %% [markdown]
# ## With dampers
#
# `damped_release` puts dampers in at a damping ratio of 0.3 (passenger cars: 0.2 to 0.4).

# %%
damped = springlab.run("car", "damped_release", dt=2.5e-4)
plots.time_series(damped)

# %% [markdown]
# *Check* the damper and the decay: d = 2 ζ √(k m), and successive peaks shrink by the logarithmic
# decrement 2π ζ / √(1 - ζ²), measured here from the first peaks of the simulated heave (run at 0.25 ms).
# The sample nearest a peak is at most dt/2 from it, where the acceleration is -ω² (x - x_s), so it
# misses the peak's height above x_s by at most (ω dt / 2)² / 2 of it; RK4's own error (as above,
# n |z|⁵ / 120 e^|z| |A| ≈ 1e-12 m) is under 1e-6 of the third peak.

# %%
zeta = damped.parameters["damping_ratio"]
assert math.isclose(damped.parameters["damping"], 2 * zeta * math.sqrt(k * m), rel_tol=1e-12)
above = damped.pos["heave"] - clearance
peaks = np.flatnonzero((above[1:-1] > above[:-2]) & (above[1:-1] >= above[2:]) & (above[1:-1] > 0)) + 1
decrements = np.log(above[peaks[:2]] / above[peaks[1:3]])
delta = 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
print(f"decrement {decrements.round(6)} (exact {delta:.6f})")
assert peaks.size >= 3
assert np.all(np.abs(decrements - delta) <= 2 * (omega * damped.dt / 2) ** 2 / 2 + 1e-6)
