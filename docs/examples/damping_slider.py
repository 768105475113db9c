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
# # The mass-spring-damper and its damping ratio
#
# Chapter 5.4 in MuJoCo: the slider (a block on a spring and a damper, `models/slider.xml`), the
# textbook's exercise, the family of damping ratios, and the chapter's interactive figure: a slider
# for ζ between 0 and 1. Every run is checked against its exact solution by springlab; the cells
# marked *check* hold the numbers to closed forms written here, independently of springlab.

# %%
# %matplotlib inline
import math

import ipywidgets
import numpy as np
from IPython.display import display

import springlab
from springlab.plots import run as plots
from springlab.studies.families import run_zeta_family

# %% [markdown]
# ## The exercise: under- or overdamped?
#
# d/m = 3 1/s and k/m = 2 1/s², released from x(0) = 5 m at rest. The damping ratio is
# ζ = d / (2 √(k m)) = 3 / (2 √2) > 1: overdamped, and x(t) = A e^(-t) + B e^(-2t) with
# A + B = 5 and -A - 2B = 0, so A = 10 m and B = -5 m.

# %%
exercise = springlab.run("slider", "exercise")
print(exercise.message)
{name: exercise.quantities[name] for name in ("regime", "damping_ratio", "coefficient_A_m", "coefficient_B_m")}

# %% [markdown]
# *Check* against the closed form. On this linear system one RK4 step multiplies each mode by the
# degree-4 Taylor polynomial of e^z (z = λ dt, λ = -1 and -2 1/s), which differs from e^z by at most
# |z|⁵ / 5! e^|z|; neither grows, so after n steps each mode is off by at most n |z|⁵ / 120 e^|z| of
# its coefficient (10 m and -5 m).

# %%
m, d, k = (exercise.parameters[name] for name in ("mass", "damping", "stiffness"))
assert math.isclose(exercise.quantities["damping_ratio"], d / (2 * math.sqrt(k * m)), rel_tol=1e-12)
assert math.isclose(d / (2 * math.sqrt(k * m)), 3 / (2 * math.sqrt(2)), rel_tol=1e-12)
assert exercise.quantities["regime"] == "overdamped"
t = exercise.time
x_exact = 10 * np.exp(-t) - 5 * np.exp(-2 * t)
bound = sum(exercise.steps * z**5 / 120 * math.exp(z) * c for z, c in ((exercise.dt, 10.0), (2 * exercise.dt, 5.0)))
error = np.abs(exercise.pos["slider"] - x_exact).max()
print(f"max |x - (10 e^-t - 5 e^-2t)| = {error:.2e} m <= {bound:.2e} m")
assert error <= bound

# %%
exercise.to_pandas().head()

# %% [markdown]
# ## The damping family
#
# The same block and spring at several damping ratios, each run with its exact curve dashed inside
# (what `springlab plot slider free --kind zeta` draws).

# %%
family = run_zeta_family("slider", "free", zetas=(0.0, 0.1, 0.25, 0.5, 1.0, 2.0))
plots.zeta_family(family)

# %%
family.to_pandas().groupby("zeta")["slider_pos"].min()  # the deepest swing below 0 [m]

# %% [markdown]
# ## Move the slider: ζ between 0 and 1
#
# The chapter's interactive figure: the displacement x(t) of the block for a damping ratio you
# choose. `show(zeta)` runs the scene with the damper d = 2 ζ √(k m); the slider calls it (run the
# notebook in Jupyter with ipywidgets, `pip install 'springlab[notebooks]'`, to move it).

# %%
MASS, STIFFNESS = 1.0, 100.0  # [kg], [N/m]: omega_n = 10 rad/s


def show(zeta: float) -> springlab.Result:
    """Run the slider at damping ratio `zeta` [-] for 3 s at 1 ms and draw x(t) against the exact curve."""
    damping = 2 * zeta * math.sqrt(STIFFNESS * MASS)
    result = springlab.run(
        "slider", "free", integrator="rk4", dt=1e-3, duration=3.0, mass=MASS, stiffness=STIFFNESS, damping=damping
    )
    display(plots.time_series(result))
    print(f"ζ = {result.quantities['damping_ratio']:.3g}: {result.quantities['regime']}; {result.message}")
    return result


slider = ipywidgets.FloatSlider(value=0.1, min=0.0, max=1.0, step=0.05, description="ζ", continuous_update=False)
figure = ipywidgets.interactive(show, zeta=slider)  # calls show(0.1) now, then on every move
display(figure)

# %% [markdown]
# *Check* one position of the slider: ζ = 0.2. Successive peaks of a damped vibration are one damped
# period T_d = 2π / (ω_n √(1 - ζ²)) apart and shrink by the same factor, the logarithmic decrement
# δ = ln(x_n / x_(n+1)) = 2π ζ / √(1 - ζ²). The sample nearest a peak is at most dt/2 from it,
# where x'' = -ω_n² x, so it misses the peak by at most (ω_n dt / 2)² / 2 of its height.

# %%
zeta = 0.2
result = show(zeta)
x, omega_n, dt = result.pos["slider"], math.sqrt(STIFFNESS / MASS), result.dt
peaks = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]) & (x[1:-1] > 0)) + 1
decrements = np.log(x[peaks[:-1]] / x[peaks[1:]])
periods = np.diff(result.time[peaks])
delta = 2 * math.pi * zeta / math.sqrt(1 - zeta**2)
peak_miss = (omega_n * dt / 2) ** 2 / 2
print(f"{peaks.size} peaks: decrement {decrements.mean():.6f} (exact {delta:.6f}), period {periods.mean():.4f} s")
assert math.isclose(result.quantities["damping_ratio"], zeta, rel_tol=1e-12)
assert math.isclose(figure.result.quantities["damping_ratio"], slider.value, rel_tol=1e-12)  # the slider's own run
assert peaks.size >= 3
assert np.all(np.abs(decrements - delta) <= 2 * peak_miss)
assert np.all(np.abs(periods - 2 * math.pi / (omega_n * math.sqrt(1 - zeta**2))) <= dt)
