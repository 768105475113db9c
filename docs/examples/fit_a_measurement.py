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
# # From a measurement back to the model
#
# Chapter 5.4's experiment: a block of 2 kg on a spring and a damper, let go, its position recorded.
# "The amplitude decays exponentially, while the frequency remains constant." `springlab.fit` finds
# the spring and the damper behind a record, with MuJoCo in the loop and 95 % intervals.
#
# The record is made here, so the truth is known: k = 800 N/m, d = 4 N s/m, released from 50 mm at
# t = 0.3 s, sampled unevenly at about 200 Hz in millimetres with 0.3 mm of sensor noise, written as
# the CSV a lab exports (the shipped `docs/examples/decay_mm.csv` is one like it).

# %%
# %matplotlib inline
import math
import pathlib
import tempfile

import numpy as np
from IPython.display import Image

import springlab
from springlab.exact.analytic import free_response
from springlab.plots.fit import plot_fit

MASS, STIFFNESS, DAMPING = 2.0, 800.0, 4.0  # [kg], [N/m], [N s/m]
NOISE_MM = 0.3  # [mm]
rng = np.random.default_rng(2)
time = np.cumsum(rng.uniform(0.004, 0.006, 600))  # [s]
x, _ = free_response(np.clip(time - 0.3, 0, None), MASS, STIFFNESS, DAMPING, 0.05, 0.0)  # [m]
position_mm = 1e3 * x + rng.normal(0, NOISE_MM, time.size)
# the files this notebook writes go to a folder of their own, never into the folder it runs in (a checkout,
# opened as the README says): a fresh temporary one, or name yours, e.g. pathlib.Path("my-results")
output = pathlib.Path(tempfile.mkdtemp(prefix="fit-a-measurement-"))
record = output / "decay.csv"
record.write_text("t,x_mm\n" + "".join(f"{t:.6f},{p:.4f}\n" for t, p in zip(time, position_mm)))
print(record.read_text()[:60])

# %% [markdown]
# `_mm` in the column's name is read as millimetres; the part before the release is found and left
# out (a change-point test); the free parameters are ω_n, ζ, x0, v0 and an offset, and with the mass
# given, the stiffness and the damper follow.

# %%
fit = springlab.fit("slider", record, map={"t": "time", "x_mm": "slider_pos"}, mass=MASS)
print(fit.verdict)
print("\n".join(fit.record.notes))
fit.to_pandas()

# %%
{name: fit.derived[name] for name in ("stiffness", "damping")}

# %%
plot_fit(fit, output / "fit.png")
Image(output / "fit.png")

# %% [markdown]
# *Check* against what the record was made from. The residual is the sensor's noise: its RMS over n
# samples with p fitted parameters is 0.3 mm √((n - p)/n), within a few times its spread 1/√(2n). The
# truth lies inside the 95 % intervals' neighbourhood: within two half-widths (about four standard
# errors) for the stiffness and for ζ = d / (2 √(k m)).

# %%
n, p = fit.record.time.size, len(fit.free)
rms_mm = 1e3 * fit.residual_rms
expected_mm = NOISE_MM * math.sqrt((n - p) / n)
print(f"residual RMS {rms_mm:.4f} mm, the noise's {expected_mm:.4f} mm ({n} samples)")
assert abs(rms_mm / expected_mm - 1) <= 4 / math.sqrt(2 * n)
for estimate, truth in (
    (fit.derived["stiffness"], STIFFNESS),
    (fit.estimates["zeta"], DAMPING / (2 * math.sqrt(STIFFNESS * MASS))),
):
    low, high = estimate["ci95"]
    print(f"{estimate['value']:.6g} in [{low:.6g}, {high:.6g}] {estimate['unit']}, truth {truth:.6g}")
    assert abs(estimate["value"] - truth) <= (high - low)
assert fit.success
