"""Eq. (1) adaptor throughput: vectorised NumPy vs a per-frame pure-Python baseline, and the
whole analytic ``adapt()`` (Pinocchio FK for grounding and the report included).

Run: ``python benchmarks/eq1.py``. Prints frames per second (median of 7 repeats).
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from gdimitate import adapt, paper_case
from gdimitate.planar import eq1


def scalar_eq1(th1, th2, lm, lr):
    """Baseline: the same formula, one frame at a time with the math module."""
    (lm1, lm2), (lr1, lr2) = lm, lr
    Lm, Lr = lm1 + lm2, lr1 + lr2
    arg = ((Lr * lm1 / Lm) * math.cos(th1) + ((Lr * lm2 / Lm) - lr2) * math.cos(th1 + th2)) / lr1
    r1 = math.copysign(math.acos(max(-1.0, min(1.0, arg))), th1 if th1 != 0 else 1.0)
    return r1, th1 + th2 - r1, abs(arg) <= 1


def rate(fn, n, repeats=7):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return n / statistics.median(times)


def main() -> None:
    rng = np.random.default_rng(0)
    n = 1_000_000
    th1, th2 = rng.uniform(-0.6, 0.6, n), rng.uniform(-1.2, 0, n)
    lm, lr = (0.4, 0.6), (0.1, 0.1)
    nb = 100_000
    base = rate(lambda: [scalar_eq1(a, b, lm, lr) for a, b in zip(th1[:nb], th2[:nb])], nb)
    vec = rate(lambda: eq1(th1, th2, lm, lr), n)
    demo, imit, motion = paper_case("I")
    full = rate(lambda: adapt(motion, demo, imit, "analytic"), motion.T, repeats=5)
    rows = [
        ("eq1, per-frame Python loop (baseline)", base, 1.0),
        ("eq1, vectorised NumPy (1e6 frames)", vec, vec / base),
        (f"adapt(method='analytic'), Case I, {motion.T} frames", full, full / base),
    ]
    print(f"{'what':<52} {'frames/s':>14} {'× baseline':>11}")
    for what, r, x in rows:
        print(f"{what:<52} {r:>14,.0f} {x:>11.1f}")


if __name__ == "__main__":
    main()
