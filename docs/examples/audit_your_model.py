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
# # Audit a model you bring
#
# `springlab.audit` points springlab's measuring machinery at any MJCF: the model's modes, the
# timestep at which each of MuJoCo's integrators goes unstable, the error against cost of all five,
# and the cheapest setting that meets a tolerance, verified by a run. Here the model is written in
# the notebook: two 1 kg blocks in a chain, each on a 400 N/m spring (the second one's measured from
# the first), simulated with MuJoCo's default Euler at 2 ms. Point `audit` at your own file instead
# (or at an `MjModel`).

# %%
# %matplotlib inline
import math
import pathlib
import tempfile

import numpy as np
import pandas as pd
from IPython.display import Image

import springlab
from springlab.plots.audit import plot_audit

MJCF = """
<mujoco model="two blocks in a chain">
  <option timestep="0.002" integrator="Euler" gravity="0 0 0"/>
  <worldbody>
    <body name="first">
      <joint name="first" type="slide" axis="1 0 0" stiffness="400"/>
      <geom type="box" size="0.05 0.05 0.05" mass="1"/>
      <body name="second" pos="0.3 0 0">
        <joint name="second" type="slide" axis="1 0 0" stiffness="400"/>
        <geom type="box" size="0.05 0.05 0.05" mass="1"/>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
# the files this notebook writes go to a folder of their own, never into the folder it runs in (a checkout,
# opened as the README says): a fresh temporary one, or name yours, e.g. pathlib.Path("my-results")
output = pathlib.Path(tempfile.mkdtemp(prefix="audit-your-model-"))
model = output / "two_blocks.xml"
model.write_text(MJCF)
print(f"{model.name}: {len(MJCF.splitlines())} lines of MJCF, in {output}")

# %%
audit = springlab.audit(model, tol=1e-3, duration=1.0)
pick, own = audit.recommendation, audit.own
print(f"your setting: {own.integrator} at {own.dt:g} s, error {own.error:.2g} over {audit.duration:g} s")
print(
    f"cheapest meeting {pick.tolerance:g}: {pick.integrator} at {pick.dt:.3g} s, error {pick.error:.2g} (verified: {pick.verified})"
)

# %%
plot_audit(audit, output / "audit.png")
Image(output / "audit.png")

# %%
pd.DataFrame(
    [
        {
            "integrator": name,
            "predicted [s]": limit.limit_dt_predicted_s,
            "measured [s]": limit.limit_dt_measured_s,
            "confirmed": limit.confirmed,
            "margin at 2 ms": limit.margin,
        }
        for name, limit in audit.stability.items()
    ]
)

# %% [markdown]
# *Check* the modes and the limits by hand. In absolute positions the chain has M = m I and
# K = k [[2, -1], [-1, 1]], so ω² = (k/m)(3 ∓ √5)/2. MuJoCo's Euler (semi-implicit, springs explicit)
# is stable for dt < 2/ω_max, RK4 for dt < 2√2/ω_max (where its stability region meets the imaginary
# axis). The audit finds its measured limits by bisection to a ratio of 1 + 1e-4.

# %%
k_over_m = 400.0
omegas = np.sqrt(k_over_m * np.array([(3 - math.sqrt(5)) / 2, (3 + math.sqrt(5)) / 2]))  # [rad/s]
modes = sorted(mode.frequency_hz for mode in audit.linear.modes)
print("modes [Hz]:", np.round(modes, 6), "exact:", np.round(omegas / (2 * math.pi), 6))
# the modes come from MuJoCo's finite-difference linearization: accurate to ~sqrt(eps)
assert np.allclose(modes, omegas / (2 * math.pi), rtol=1e-6)
for name, exact in (("euler", 2 / omegas[1]), ("rk4", 2 * math.sqrt(2) / omegas[1])):
    limit = audit.stability[name]
    print(f"{name}: limit {limit.limit_dt_measured_s:.6g} s (exact {exact:.6g} s), confirmed {limit.confirmed}")
    assert math.isclose(limit.limit_dt_predicted_s, exact, rel_tol=1e-6)
    assert abs(limit.limit_dt_measured_s / exact - 1) <= 1e-4 and limit.confirmed
assert audit.recommendation.verified and audit.recommendation.error <= 1e-3
