"""How cost grows with the work (issue 37): sweep and design against their configurations, the drill string's run
against its elements, each on a log-log plot with the fitted exponent, and the sweep's peak Python memory.

For each size: CPU time [s] of the call (best of `--repeat`), and for the sweep the peak of tracemalloc's traced
memory (numpy's arrays included) during it. The exponent is the least-squares slope of log(CPU) on log(size)
over the sizes at or above the middle one (small sizes carry a fixed cost that bends the line).

Rows of `make bench`'s table: `sweep slider free, growth`, `design printer_head, growth` and `run drill_string
modes, growth` (the largest size's CPU against the middle size's scaled linearly; the sweep's memory in its note).
`make bench` runs it with --quick (the sizes are in each row's work).

Run: PYTHONPATH=src python benchmarks/bench_growth.py [--figure docs/images/cost_growth.png] [--quick]
"""

from __future__ import annotations

import argparse
import math
import time
import tracemalloc
from collections.abc import Callable

import numpy as np

import springlab
from measure import Row, emit, forget_cases
from springlab.studies.design import run_study

#: the largest size's CPU against the middle one's scaled linearly: sweep and design are linear in their runs (no
#: per-run cost grows with the study), the drill string's first run at most linear in its elements at these sizes
#: (its fixed cost, the compile and the exact reference, still dominates); 1.3 is an exponent of about 1.1 over the
#: full run's 16x and 1.2 over --quick's 4x: a per-run cost that grows with the work shows
GROWTH_BUDGET = 1.3


def cpu_of(fn: Callable[[], object], repeat: int) -> float:
    """Shortest CPU time [s] of `repeat` calls (CPU: the least disturbed on a shared machine)."""
    best = math.inf
    for _ in range(repeat):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def peak_memory(fn: Callable[[], object]) -> float:
    """Peak traced memory [MB] during one call."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 1e6
    finally:
        tracemalloc.stop()


def exponent(sizes: list[int], costs: list[float]) -> float:
    """Slope of log(cost) on log(size) over the upper half of the sizes."""
    half = len(sizes) // 2
    x, y = np.log(sizes[half:]), np.log(costs[half:])
    return float(np.polyfit(x, y, 1)[0])


def growth_row(name: str, sizes: list[int], costs: list[float], extra: str = "") -> Row:
    """The largest size's CPU against the middle size's scaled linearly: over GROWTH_BUDGET, cost grows faster than
    the work."""
    half = len(sizes) // 2
    path, unit = name.split(" (")
    return Row(
        f"{path}, growth",
        f"{unit.rstrip(')')} {', '.join(map(str, sizes))}: CPU at {sizes[-1]}",
        float("nan"),
        costs[-1],
        f"linear from {sizes[half]}",
        float("nan"),
        costs[half] * sizes[-1] / sizes[half],
        GROWTH_BUDGET,
        "(set)",
        f"bench_growth.py: fitted exponent {exponent(sizes, costs):.2f} over the upper half of the sizes{extra}",
    )


def sweep_growth(sizes: list[int], repeat: int) -> tuple[list[float], list[float]]:
    def call(n: int) -> Callable[[], object]:
        return lambda: springlab.sweep("slider", "free", vary={"stiffness": (10.0, 1000.0, n, "log")})

    return [cpu_of(call(n), repeat) for n in sizes], [peak_memory(call(n)) for n in sizes]


def design_growth(levels: list[int], repeat: int) -> tuple[list[int], list[float]]:
    """(configurations, CPU [s]) of the printer head's design study at `levels` per property (4 properties)."""
    runs = [run_study("printer_head", levels=n, plane_levels=0).size for n in levels]
    costs = [cpu_of(lambda n=n: run_study("printer_head", levels=n, plane_levels=0), repeat) for n in levels]
    return runs, costs


def drill_growth(sizes: list[int], repeat: int) -> list[float]:
    """CPU [s] of a first run of the drill string at each size (its compile and exact precomputations included)."""

    def first_run(n: int) -> None:
        forget_cases()
        springlab.run("drill_string", "modes", n_elements=n)

    return [cpu_of(lambda n=n: first_run(n), repeat) for n in sizes]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--figure", help="write the log-log plot here (PNG)")
    parser.add_argument("--quick", action="store_true", help="smaller sizes, one repeat")
    args = parser.parse_args()
    repeat = 1 if args.quick else 3
    sweep_sizes = [16, 64, 256] if args.quick else [16, 64, 256, 1024, 4096]
    design_levels = [3, 5, 7] if args.quick else [3, 5, 7, 9, 11]
    drill_sizes = [8, 16, 32] if args.quick else [8, 16, 32, 64, 128]

    rows = []
    sweep_cpu, sweep_mb = sweep_growth(sweep_sizes, repeat)
    rows.append(("sweep slider free (configurations)", sweep_sizes, sweep_cpu))
    design_runs, design_cpu = design_growth(design_levels, repeat)
    rows.append(("design printer_head (configurations)", design_runs, design_cpu))
    drill_cpu = drill_growth(drill_sizes, repeat)
    rows.append(("run drill_string modes (elements)", drill_sizes, drill_cpu))

    print(f"{'path':<40}{'size':>8}{'CPU [s]':>12}")
    for name, sizes, costs in rows:
        for size, cost in zip(sizes, costs):
            print(f"{name:<40}{size:>8}{cost:>12.4g}")
        print(f"{name:<40}  fitted exponent {exponent(list(sizes), costs):.2f}")
    print("sweep peak traced memory [MB]: " + ", ".join(f"{n}: {m:.1f}" for n, m in zip(sweep_sizes, sweep_mb)))
    print(f"  memory exponent {exponent(sweep_sizes, sweep_mb):.2f} (0: flat in the number of runs)")
    memory = f"; the sweep's peak traced memory {sweep_mb[0]:.1f} MB at {sweep_sizes[0]}, {sweep_mb[-1]:.1f} MB at"
    memory += f" {sweep_sizes[-1]} (exponent {exponent(sweep_sizes, sweep_mb):.2f})"
    for (name, sizes, costs), extra in zip(rows, (memory, "", "")):
        emit(growth_row(name, list(sizes), costs, extra))

    if args.figure:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        for (name, sizes, costs), marker in zip(rows, "osd"):
            ax.loglog(sizes, costs, marker=marker, label=f"{name}: exponent {exponent(list(sizes), costs):.2f}")
        ax.set_xlabel("work (configurations or elements)")
        ax.set_ylabel("CPU time [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(args.figure, dpi=110)
        print(f"wrote {args.figure}")


if __name__ == "__main__":
    main()
