"""Shared timing helper of the benchmark scripts (run as `python benchmarks/bench_*.py`)."""

import time


def best_of(fn, repeat=7):
    """Shortest wall time [s] of `repeat` calls of fn(): the least disturbed by other load."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)
