"""Speed of springlab's simulate path, side by side in one run.

1. springlab.sim.simulate vs raw mujoco.rollout on the same compiled slider model
   and integrator (steps/s and their ratio; the target is >= 0.9); euler's and
   implicitfast's are rows of `make bench`'s table (rk4's is the table's own
   `simulate slider`).
2. The slider's default validated setting (rk4, 2 ms) on `free` against
   scipy's solve_ivp methods tuned to the same accuracy (max relative error
   <= 1e-6 against the exact solution): wall time of each.

Run: python benchmarks/bench_simulate.py
"""

from __future__ import annotations

import mujoco
import numpy as np
from mujoco import rollout

import measure
import springlab
from springlab import scenes
from springlab.exact import analytic
from springlab.sim.simulate import configured, initial_state, simulate
from timing import best_of


def simulate_vs_rollout() -> None:
    scene = scenes.get("slider")
    case = scene.case("free")
    model = case.model
    duration, dt = 20.0, scene.dt
    steps = round(duration / dt)
    setup = case.setup(steps, dt)
    print(f"1) simulate vs raw rollout, slider, {steps} steps per run")
    print(f"   {'integrator':<13}{'springlab steps/s':>20}{'raw rollout steps/s':>22}{'ratio':>8}")
    for integrator in ("rk4", "euler", "implicitfast"):

        def path(integrator=integrator):
            simulate(
                model,
                integrator=integrator,
                dt=dt,
                duration=duration,
                qpos=setup.qpos,
                qvel=setup.qvel,
                control=setup.control,
            )

        # the raw side gets its own model with the same setting (simulate never modifies its input)
        raw = configured(model, integrator, dt)
        data = mujoco.MjData(raw)
        state0 = initial_state(raw, setup.qpos, setup.qvel)
        control = np.zeros((1, steps, raw.nu))

        def floor(raw=raw, data=data, state0=state0, control=control):
            rollout.rollout(raw, data, state0[None], control, nstep=steps)

        (springlab_time, springlab_cpu), (raw_time, raw_cpu) = measure.side_by_side([path, floor], 7)
        print(
            f"   {integrator:<13}{steps / springlab_time:>20,.0f}{steps / raw_time:>22,.0f}"
            f"{raw_time / springlab_time:>8.2f}"
        )
        if integrator != "rk4":  # rk4's row is the table's own `simulate slider`
            measure.emit(
                measure.Row(
                    f"simulate slider {integrator}",
                    f"{steps} steps {integrator} dt={dt:g} s",
                    springlab_time,
                    springlab_cpu,
                    "rollout",
                    raw_time,
                    raw_cpu,
                    measure.SIMULATE_BUDGET,
                    "issue 37",
                    "bench_simulate.py: springlab.sim.simulate against a plain rollout of the same steps on the same"
                    " configured model, in turn, best of 7",
                )
            )


def default_setting_vs_scipy() -> None:
    from scipy.integrate import solve_ivp

    result = springlab.run("slider", "free")
    m, k, d = (result.parameters[n] for n in ("mass", "stiffness", "damping"))
    x0, v0 = result.parameters["x0"], result.parameters["v0"]
    duration = result.duration
    t_eval = result.time
    x_exact, _ = analytic.free_response(t_eval, m, k, d, x0, v0)
    scale = np.max(np.abs(x_exact))

    springlab_error = result.errors["slider_pos"].max_rel
    whole_time = best_of(lambda: springlab.run("slider", "free"), repeat=15)
    # the simulate path on the compiled model: the counterpart of solve_ivp given its right-hand side
    case = scenes.get("slider").case("free")
    model = case.model
    dt = result.dt
    setup = case.setup(result.steps, dt)
    path_time = best_of(
        lambda: simulate(
            model, integrator="rk4", dt=dt, duration=duration, qpos=setup.qpos, qvel=setup.qvel, control=setup.control
        ),
        repeat=15,
    )
    print("\n2) slider 'free' to max relative error <= 1e-6 (default validated setting vs scipy)")
    print(
        f"   springlab rk4 dt={dt:g}: simulate path {path_time * 1e3:6.2f} ms; whole springlab.run call"
        f" {whole_time * 1e3:6.2f} ms (MJCF parse + compile + exact reference + tolerance); error {springlab_error:.2e}"
    )

    def rhs(t, y):
        return [y[1], -(k * y[0] + d * y[1]) / m]

    fastest = None
    for method in ("RK45", "DOP853", "LSODA", "Radau", "BDF"):
        # loosen rtol until the error just meets 1e-6: the cheapest honest setting per method
        chosen = None
        for rtol in 10.0 ** -np.arange(4, 13.5, 0.5):
            sol = solve_ivp(rhs, (0, duration), [x0, v0], method=method, rtol=rtol, atol=rtol * 1e-3, dense_output=True)
            error = np.max(np.abs(sol.sol(t_eval)[0] - x_exact)) / scale
            if error <= 1e-6:
                chosen = rtol
                break
        if chosen is None:
            print(f"   scipy {method:<7}: could not reach 1e-6")
            continue
        elapsed = best_of(
            lambda: solve_ivp(
                rhs, (0, duration), [x0, v0], method=method, rtol=chosen, atol=chosen * 1e-3, dense_output=True
            ).sol(t_eval),
            repeat=5,
        )
        print(f"   scipy {method:<7} rtol={chosen:.0e}: {elapsed * 1e3:8.2f} ms, error {error:.2e}")
        fastest = elapsed if fastest is None else min(fastest, elapsed)
    print(
        f"   fastest scipy / springlab simulate path = {fastest / path_time:.2f}"
        f"   (/ whole springlab.run call = {fastest / whole_time:.2f})"
    )


if __name__ == "__main__":
    simulate_vs_rollout()
    default_setting_vs_scipy()
