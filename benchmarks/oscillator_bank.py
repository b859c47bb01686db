"""Throughput of the Matsuoka bank: oscillator-steps per second (RK4, dt = 1 ms).

Run: ``python benchmarks/oscillator_bank.py [--steps 1000] [--repeat 3]``

For bank sizes 1, 100, 1 000, 10 000, 100 000 (uncoupled copies of docs/design.md §7's example
oscillator, output ``y`` recorded at every step) it prints the best of ``--repeat`` runs of
the compiled (numba) path and of the NumPy reference path, next to a baseline measured in the
same run: a Python loop calling ``scipy.integrate.solve_ivp`` (RK45, rtol 1e-6, atol 1e-9,
output on the same 1 ms grid) once per oscillator.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
import warnings

import numpy as np
from results import add_flag, recording
from scipy.integrate import solve_ivp

from gdimitate.oscillator import MatsuokaBank, MatsuokaParams

P = MatsuokaParams(tau_r=0.1, tau_a=0.2, b=2.5, w=2.5, s=1.0)


def rhs(t, z):
    xe, xf, ve, vf = z
    ye, yf = max(xe, 0.0), max(xf, 0.0)
    return [(-xe - 2.5 * yf - 2.5 * ve + 1.0) / 0.1, (-xf - 2.5 * ye - 2.5 * vf + 1.0) / 0.1,
            (ye - ve) / 0.2, (yf - vf) / 0.2]


def baseline_rate(t: np.ndarray, n_osc: int = 10) -> float:
    """Oscillator-steps/s of a per-oscillator solve_ivp loop."""
    rng = np.random.default_rng(0)
    t0 = time.perf_counter()
    for _ in range(n_osc):
        x0 = [0.1 + 0.01 * rng.random(), 0.0, 0.0, 0.0]
        solve_ivp(rhs, (t[0], t[-1]), x0, method="RK45", rtol=1e-6, atol=1e-9, t_eval=t)
    return n_osc * (t.size - 1) / (time.perf_counter() - t0)


def bank_rate(n: int, t: np.ndarray, backend: str, repeat: int) -> float:
    bank = MatsuokaBank(P, shape=(n, 1))
    bank.simulate(t[:3], backend=backend, record="y")  # compile / warm up
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        bank.simulate(t, backend=backend, record="y")
        best = min(best, time.perf_counter() - t0)
    return n * (t.size - 1) / best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--repeat", type=int, default=3)
    add_flag(ap)
    args = ap.parse_args()
    warnings.simplefilter("ignore")
    t = np.arange(args.steps + 1) * 1e-3
    base = baseline_rate(t)
    print(f"Matsuoka bank, RK4, dt = 1 ms, {args.steps} steps, {os.cpu_count()} CPU cores")
    print(f"baseline (solve_ivp loop, per oscillator): {base:,.0f} oscillator-steps/s")
    print(f"{'oscillators':>12} {'numba [osc-steps/s]':>20} {'numpy [osc-steps/s]':>20} "
          f"{'numba/baseline':>15}")
    for n in (1, 100, 1_000, 10_000, 100_000):
        r_nb = bank_rate(n, t, "numba", args.repeat)
        r_np = bank_rate(n, t[: min(t.size, 201)], "numpy", 1) if n <= 10_000 else float("nan")
        print(f"{n:>12,} {r_nb:>20,.0f} {r_np:>20,.0f} {r_nb / base:>15,.0f}x")


if __name__ == "__main__":
    with recording("oscillator_bank", "--results" in sys.argv[1:]):
        main()
