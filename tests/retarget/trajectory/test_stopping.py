"""The adaptor's stopping rule (gdimitate.retarget.trajectory.stopping.Plateau) on synthetic iterate
traces with known answers, and ``stop="settled"`` against IPOPT's own convergence test on a
real problem, both judged by the independent audit."""

from __future__ import annotations

import numpy as np
import pytest

import gdimitate as gd
from gdimitate.retarget.trajectory.stopping import PLATEAU, Plateau
from tests.helpers import shared


def _rule(**kw) -> Plateau:
    # two rows: g0 in [0, 0] scaled by 1000 (a base row in N), g1 <= 1
    return Plateau(np.array([0.0, -np.inf]), np.array([0.0, 1.0]), np.array([1000.0, 1.0]),
                   **kw)


def test_keeps_the_best_feasible_iterate_and_stops_when_it_settles():
    p = _rule(viol_tol=1e-8, rel_tol=1e-3, window=3)
    # (cost, g0 [N], g1): infeasible, feasible, better but infeasible, feasible and best, ...
    trace = [(5.0, 1.0, 0.0), (2.0, 5e-6, 0.5), (1.5, 0.0, 1.1), (1.9, 9e-6, 1.0),
             (1.8995, 0.0, 0.0), (1.8992, 0.0, 0.0), (1.8991, 0.0, 0.0)]
    stops = [p.update(f, np.array([f]), np.array([g0, g1])) for f, g0, g1 in trace]
    # 5e-6 N / 1000 = 5e-9 ≤ 1e-8: feasible; 1.1 > 1: not. Improvement over the last 3
    # iterations at the 7th: 1.9 → 1.8991, 4.7e-4 ≤ 1e-3 → stop there and not before.
    assert stops == [False] * 6 + [True]
    assert p.best_f == pytest.approx(1.8991) and p.best_x[0] == pytest.approx(1.8991)
    assert p.violation(np.array([2e-5, 0.0])) == pytest.approx(2e-8)


def test_never_stops_without_a_feasible_iterate():
    p = _rule(window=2)
    assert not any(p.update(1.0, np.zeros(1), np.array([1.0, 0.0])) for _ in range(20))
    assert p.best_x is None


@pytest.mark.slow
def test_settled_and_converged_give_motions_the_audit_accepts():
    # 30 knots/s: at 20 the body-over-feet cost carries G1's body far enough that the one-step
    # scheme's stance-foot velocity exceeds the audit's 1e-3 m/s (docs/design.md §13)
    h, m, f = shared.walk_3d()
    demo, fs = gd.gait.one_stride(m, f, "left")
    robot = shared.library_robot("g1")
    out = {stop: gd.adapt(demo, h, robot, "optimal", force="measured", forces=fs, rate=30,
                          verbose=False, stop=stop) for stop in ("settled", "converged")}
    for r in out.values():
        assert r.audit.feasible, r.audit.binding
        assert r.audit.base_residual.value <= 1e-6
    s, c = out["settled"], out["converged"]
    assert s.solver.iterations <= c.solver.iterations
    assert s.solver.status in (PLATEAU, c.solver.status)
    # the same motion to within a fraction of the joints' range of motion
    dq = np.abs(s.motion.q[:, 7:] - c.motion.q[:, 7:]).max()
    assert dq <= 0.05, dq


def test_stall_is_recognised_and_a_falling_violation_is_not():
    """No feasible iterate and < 10 % fall of the least violation over 20 iterations (after
    40): stop with reason 'stalled', keeping the least-violating iterate; a violation that
    keeps falling (12 → 3 over 25 iterations, Talos's trace) never stalls."""
    p = _rule()
    flat = [0.30 - 0.0005 * i for i in range(60)]  # 0.30 → 0.27: < 10 % over any 20
    stop_at = next(i for i, v in enumerate(flat)
                   if p.update(1.0, np.array([float(i)]), np.array([0.0, 1.0 + v])))
    assert stop_at == 39 and p.reason == "stalled"  # the 40th iterate
    assert p.least_x[0] == 39.0 and p.least_viol == pytest.approx(flat[39])
    q = _rule()
    falling = [12.0 * 0.95 ** i for i in range(100)]  # 5 % per iteration: 64 % over 20
    assert not any(q.update(1.0, np.zeros(1), np.array([0.0, 1.0 + v])) for v in falling)


def test_budget_stops_the_solve():
    p = _rule(budget=7, settle=False)
    stops = [p.update(1.0, np.zeros(1), np.array([0.0, 0.0])) for _ in range(7)]
    assert stops == [False] * 6 + [True] and p.reason == "budget"


def test_feasible_iterates_count_only_once_the_barrier_parameter_is_small():
    """A feasible iterate at μ > mu_tol (1e-8) is no candidate: a monotone-μ trace whose
    cheapest feasible iterate comes at μ = 1.8e-7 (the paper's Case I, which it missed Eq. (1)
    by 1.96e-6 rad) settles only on the iterates after μ fell to 7.5e-11."""
    p = _rule(window=3)
    assert p.mu_tol == 1e-8
    # (cost, g0 [N], mu): feasible and cheapest but at a large μ, then μ small
    trace = [(1.6959, 0.0, 1.8e-7), (1.71, 0.0, 1.8e-7), (1.7227, 0.0, 7.5e-11),
             (1.72265, 0.0, 7.5e-11), (1.72264, 0.0, 7.5e-11), (1.72264, 0.0, 7.5e-11)]
    stops = [p.update(f, np.array([f]), np.array([g0, 0.0]), mu) for f, g0, mu in trace]
    assert stops == [False] * 5 + [True] and p.reason == "settled"
    assert p.best_f == pytest.approx(1.72264) and p.mu_trace[0] == 1.8e-7


def test_the_barrier_parameter_reaches_the_rule_from_ipopt():
    """The μ the stopping rule gets at each iteration is IPOPT's own (its statistics after
    the solve, iteration by iteration), on min (x−1)² + (y−2)² s.t. x + y ≤ 2.5."""
    import casadi as ca

    from gdimitate.retarget.trajectory.interrupt import Progress, guard

    x = ca.MX.sym("x", 2)
    cb = Progress("mu_probe", 2, 1, 0)
    s = ca.nlpsol("s", "ipopt", {"x": x, "f": (x[0] - 1) ** 2 + (x[1] - 2) ** 2,
                                 "g": x[0] + x[1]},
                  {"iteration_callback": cb, "ipopt.print_level": 0, "print_time": 0,
                   "ipopt.sb": "yes"})
    p = Plateau(np.array([-10.0]), np.array([2.5]), np.array([1.0]), settle=False)
    with guard(False, np.array([-10.0]), np.array([2.5]), "", p, s):
        s(x0=[0, 0], lbg=-10, ubg=2.5, lbx=-5, ubx=5)
    mu = s.stats()["iterations"]["mu"]
    assert len(mu) >= 3 and p.mu_trace == pytest.approx(list(mu), rel=0, abs=0)
    assert mu[-1] < 1e-8 < mu[0]


_KEPT_HEAP_PROBE = """
import ctypes, resource, sys
from gdimitate.retarget.trajectory.solve import kept_heap
libc = ctypes.CDLL("libc.so.6")
libc.malloc.restype = ctypes.c_void_p
libc.free.argtypes = [ctypes.c_void_p]
n = 64 << 20

def once():  # allocate, touch every page, free
    p = libc.malloc(ctypes.c_size_t(n))
    ctypes.memset(p, 1, n)
    libc.free(p)

def faults():
    once()
    once()
    n0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    once()
    return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - n0

before = faults()
with kept_heap():
    inside = faults()
print(before, inside, faults())
"""


def test_kept_heap_keeps_freed_blocks_in_the_process():
    """Inside :func:`kept_heap` a freed 64-MB block is reused without page faults (counted by
    the kernel, getrusage's minor faults): 16,384 faults (64 MB of 4-kB pages) when glibc
    unmaps it on free (a block of that size is mmap-ed by default), none when it is kept, and
    glibc's behaviour is back afterwards. Measured in a fresh interpreter: the suite's own
    process carries malloc state from earlier tests' solvers (its first measurement there
    once found the block already kept)."""
    import subprocess
    import sys

    if not sys.platform.startswith("linux"):
        pytest.skip("glibc's mallopt")
    out = subprocess.run([sys.executable, "-c", _KEPT_HEAP_PROBE], capture_output=True,
                         text=True, timeout=120, check=True).stdout.split()
    before, inside, after = map(int, out)
    pages = (64 << 20) // 4096
    assert before >= pages  # glibc's default: the block is unmapped on free
    assert inside < 100
    assert after >= pages  # glibc's defaults are back
