"""Chapter 5.4: the same mass and spring in every damping regime (Fig. 5.17-5.19).

Run: python scenarios/damping_regimes.py
"""

import springlab

for scenario in ("undamped", "underdamped", "critical", "overdamped"):
    result = springlab.run("slider", scenario)
    q = result.quantities
    error = result.max_rel_error
    print(
        f"{scenario:<12} zeta = {q['damping_ratio']:<6.3g} regime = {q['regime']:<12}"
        f" x(end) = {result.pos['slider'][-1]: .3e} m   max rel error {error:.1e}"
    )
