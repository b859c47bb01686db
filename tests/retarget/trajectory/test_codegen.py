"""Compiled per-knot functions (gdimitate.retarget.trajectory.codegen): compiled once into the cache
folder, loaded afterwards without building or compiling, nothing written to the working
folder, the same numbers as CasADi's virtual machine; no C compiler → the virtual machine with
one warning."""

from __future__ import annotations

import os
import warnings

import casadi as ca
import numpy as np
import pytest

from gdimitate.retarget.trajectory import codegen


def _functions() -> list[ca.Function]:
    x = ca.SX.sym("x", 3)
    y = ca.vertcat(ca.sin(x[0]) * x[1], x[2] ** 3 - x[0])
    return [ca.Function("val", [x], [y]), ca.Function("dval", [x], [ca.jacobian(y, x)])]


def test_compiled_once_then_loaded(tmp_path, monkeypatch, capfd):
    cache, work = tmp_path / "cache", tmp_path / "work"
    work.mkdir()
    monkeypatch.setenv(codegen.ENV, str(cache))
    monkeypatch.chdir(work)
    if codegen._compiler() is None:
        pytest.skip("no C compiler on this machine")
    n = codegen.COMPILE_COUNT
    key = f"test-{os.getpid()}-{np.random.default_rng().integers(1 << 30)}"
    funs, compiled = codegen.compiled_functions(key, _functions, "the test's")
    assert compiled and codegen.COMPILE_COUNT == n + 1
    # the first run says what it compiles and roughly how long it takes, then how long it took
    # (issue 34: G1's first compile was 76 s of silence)
    said = capfd.readouterr().err
    total = sum(f.n_instructions() for f in _functions())
    assert (f"compiling the test's optimal-adaptor derivatives to C, once for this robot and "
            f"problem ({total / 1e6:.2f} M instructions in 2 files") in said
    assert "roughly 0 s" in said and "compiled in" in said
    assert list(work.iterdir()) == []  # nothing in the working folder
    assert any(p.suffix == ".so" for p in cache.iterdir())

    def must_not_build():
        raise AssertionError("a cached library must be loaded, not rebuilt")

    again, compiled2 = codegen.compiled_functions(key, must_not_build)
    assert compiled2 and codegen.COMPILE_COUNT == n + 1
    assert "compiling" not in capfd.readouterr().err  # a cache hit is silent
    ref = {f.name(): f for f in _functions()}
    x = np.array([0.3, -1.2, 0.7])
    for name in ("val", "dval"):
        np.testing.assert_allclose(np.array(again[name](x)), np.array(ref[name](x)),
                                   rtol=1e-14, atol=1e-15)


_RACER = """
import sys, time
from pathlib import Path
import casadi as ca
from gdimitate.retarget.trajectory import codegen
start, key = float(sys.argv[1]), sys.argv[2]
def make():
    x = ca.SX.sym("x", 40)
    y = x
    for _ in range(20):  # 65 k instructions: gcc takes about a second
        y = ca.sin(ca.mtimes(ca.DM.ones(40, 40) / 40, y)) + x
    return [ca.Function("racer", [x], [y])]
time.sleep(max(0.0, start - time.time()))  # both processes miss the cache together
funs, compiled = codegen.compiled_functions(key, make, "a racer's")
print("COMPILED", codegen.COMPILE_COUNT, compiled, float(funs["racer"](1.0)[0][0]))
"""


def test_processes_missing_the_same_library_compile_it_once(tmp_path):
    """Two processes that miss the same library at the same moment (a batch's workers, a
    parallel test run, on an empty cache) compile it once: the second waits on the build
    lock and loads what the first compiled. Both get the same numbers."""
    import subprocess
    import sys
    import time

    if codegen._compiler() is None:
        pytest.skip("no C compiler on this machine")
    env = {**os.environ, codegen.ENV: str(tmp_path / "cache")}
    start = time.time() + 4.0  # after both interpreters have imported casadi and gdimitate
    procs = [subprocess.Popen([sys.executable, "-c", _RACER, str(start), "race"], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    lines = [next(x for x in out.splitlines() if x.startswith("COMPILED")).split()
             for out, _ in outs]
    assert sorted(int(x[1]) for x in lines) == [0, 1], outs  # one compiled, one loaded
    assert all(x[2] == "True" for x in lines) and lines[0][3] == lines[1][3]
    assert sum("compiling a racer's" in err for _, err in outs) == 1


def test_no_compiler_falls_back_with_one_warning(tmp_path, monkeypatch):
    monkeypatch.setenv(codegen.ENV, str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    monkeypatch.setattr(codegen, "_WARNED", False)
    with pytest.warns(codegen.SlowDerivativesWarning, match="virtual machine"):
        funs, compiled = codegen.compiled_functions("nocc-a", _functions)
    assert not compiled
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # said once, not again
        codegen.compiled_functions("nocc-b", _functions)
    x = np.array([0.1, 0.2, 0.3])
    np.testing.assert_allclose(np.array(funs["val"](x)).ravel(),
                               [np.sin(0.1) * 0.2, 0.3**3 - 0.1], rtol=1e-14)


def test_cache_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv(codegen.ENV, str(tmp_path / "c"))
    assert codegen.cache_dir() == tmp_path / "c"
    monkeypatch.delenv(codegen.ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert codegen.cache_dir() == tmp_path / "xdg" / "gdimitate"


def test_source_digest_covers_every_module_the_compiled_expressions_import():
    """The compiled-derivative cache key digests the source of the modules the per-knot
    expressions are written in; a module they import from gdimitate but the digest leaves out
    (the cone rows moved to gdimitate/model/contact.py once) would let an edit load a stale
    library."""
    import ast
    from pathlib import Path

    from gdimitate.retarget.trajectory import problem

    root = Path(problem.__file__).parents[2]  # gdimitate/
    digested = set()
    for mod in problem.SOURCE_MODULES:
        p = Path(mod.__file__)
        digested |= set(p.parent.rglob("*.py")) if p.name == "__init__.py" else {p}
    writers = [root / "retarget" / "knot.py",
               root / "model" / "symbolic.py", *(root / "retarget" / "parts").glob("*.py")]
    missing = set()
    for f in writers:
        for node in ast.walk(ast.parse(f.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = f.parent
                for _ in range(node.level - 1):
                    base = base.parent
                parts = (node.module or "").split(".") if node.module else []
                target = base.joinpath(*parts)
                names = [target / f"{a.name}.py" for a in node.names] if not parts else []
                for cand in [target.with_suffix(".py"), target / "__init__.py", *names]:
                    if cand.exists() and cand.resolve() not in {d.resolve() for d in digested}:
                        missing.add(str(cand.relative_to(root)))
    missing.discard("errors.py")  # exception classes only: nothing of an expression
    assert not missing, f"imported by the compiled expressions but not digested: {missing}"


def test_split_rows_pieces_fit_and_give_the_whole():
    """Rows g_i = x_i·x_{i+1}² + sin(x_i) (closed-form Jacobian and Hessian of λᵀg): cut into
    pieces of at most 25 SX instructions, the stacked Jacobian pieces and the summed Hessian
    pieces equal the closed forms; pieces named name0, name1, … in row order."""
    n = 12
    x, lam = ca.SX.sym("x", n + 1), ca.SX.sym("lam", n)
    g = ca.vertcat(*[x[i] * x[i + 1] ** 2 + ca.sin(x[i]) for i in range(n)])
    jac = codegen.split_rows("j", n, np.ones(n), lambda a, b: [ca.jacobian(g[a:b], x)], [x],
                             limit=25)
    hes = codegen.split_rows("h", n, np.ones(n), lambda a, b: [ca.hessian(
        ca.dot(lam[a:b], g[a:b]), x)[0]], [x, lam], limit=25)
    assert len(jac) > 2 and len(hes) > 2
    assert all(f.n_instructions() <= 25 for f in jac)
    fun = {f.name(): f for f in jac + hes}
    assert codegen.pieces(fun, "j") == jac and codegen.pieces(fun, "h") == hes
    xv, lv = RNG.normal(size=n + 1), RNG.normal(size=n)
    J = np.vstack([np.array(f(xv)) for f in jac])
    H = sum(np.array(f(xv, lv)) for f in hes)
    Jref, Href = np.zeros((n, n + 1)), np.zeros((n + 1, n + 1))
    for i in range(n):
        a, b = xv[i], xv[i + 1]
        Jref[i, i], Jref[i, i + 1] = b**2 + np.cos(a), 2 * a * b
        Href[i, i] += -lv[i] * np.sin(a)
        Href[i, i + 1] += 2 * lv[i] * b
        Href[i + 1, i] += 2 * lv[i] * b
        Href[i + 1, i + 1] += 2 * lv[i] * a
    np.testing.assert_allclose(J, Jref, rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(H, Href, rtol=1e-14, atol=1e-14)
    # rows that share one long subexpression stay one piece (halves would recompute it)
    s = x[0]
    for i in range(200):
        s = ca.sin(s + x[i % (n + 1)])
    shared = ca.vertcat(*[s * x[i] for i in range(n)])
    one = codegen.split_rows("s", n, np.ones(n), lambda a, b: [shared[a:b]], [x], limit=25)
    assert len(one) == 1 and one[0].n_instructions() > 25


RNG = np.random.default_rng(11)


def test_knot_derivatives_in_pieces_match_finite_differences(tmp_path, monkeypatch, robot):
    """HOAP-2's knot (the default parts) with pieces of at most 3,000 instructions, compiled:
    ``kjac`` against central differences of ``kg``, the summed ``kh`` pieces (upper
    triangle) against central differences of the Lagrangian's gradient σ·kgrad + kjacᵀλ."""
    from gdimitate.retarget import parts as P
    from gdimitate.retarget.knot import Flags
    from gdimitate.retarget.trajectory import problem as pb

    if codegen._compiler() is None:
        pytest.skip("no C compiler on this machine")
    monkeypatch.setenv(codegen.ENV, str(tmp_path))
    monkeypatch.setattr(codegen, "PIECE_SIZE", 3000)
    r = robot("hoap2")
    pb.clear_cache()
    try:
        form = pb.formulation(r, Flags(), P.default_parts((), tuple(range(3, r.model.nq))))
    finally:
        pb.clear_cache()
    f = form.fun
    hes = codegen.pieces(f, "kh")
    assert form.compiled and len(hes) > 1
    x = RNG.normal(size=form.nx) * 0.3
    p = RNG.uniform(0.1, 1.0, size=form.knot.par.size)
    lam, sigma = RNG.normal(size=form.ngk), 0.7

    def grad(xv):
        J = np.array(f["kjac"](xv, p))
        return sigma * np.array(f["kgrad"](xv, p)).ravel() + J.T @ lam

    eps = 1e-6
    E = np.eye(form.nx)
    Jfd = np.column_stack([(np.array(f["kg"](x + eps * e, p)) - np.array(f["kg"](x - eps * e, p))
                            ).ravel() / (2 * eps) for e in E])
    np.testing.assert_allclose(np.array(f["kjac"](x, p)), Jfd, atol=2e-5, rtol=1e-5)
    Hfd = np.column_stack([(grad(x + eps * e) - grad(x - eps * e)) / (2 * eps) for e in E])
    H = sum(np.array(h(x, p, sigma, lam)) for h in hes)
    np.testing.assert_allclose(H, np.triu(Hfd), atol=2e-4, rtol=1e-5)


def test_the_solver_record_says_what_was_compiled(tmp_path, monkeypatch):
    """summary.json said `"cached": false` when the build took 0.8 s: the NLP was new to the
    process, its compiled derivatives came from the disk cache. The record now tells the three
    cases apart: compiled now; loaded from disk (compiled False, cached False); the process's
    own NLP again (cached True)."""
    from gdimitate.adaptation.adaptor import adapt
    from gdimitate.apps.cases import paper_case
    from gdimitate.retarget.trajectory import problem as pb

    if codegen._compiler() is None:
        pytest.skip("no C compiler on this machine")
    monkeypatch.setenv(codegen.ENV, str(tmp_path))
    d, i, m = paper_case("I")
    m = m.replace(t=m.t[:30], q=m.q[:30], contact={s: c[:30] for s, c in m.contact.items()})
    pb.clear_cache()
    try:
        runs = []
        for fresh in (True, True, False):
            if fresh:
                pb.clear_cache()
            s = adapt(m, d, i, method="optimal", rate=25, verbose=False).solver
            runs.append((s.compiled, s.cached))
    finally:
        pb.clear_cache()
    assert runs == [(True, False), (False, False), (False, True)]


def _wait_for_build(lib, timeout: float = 120.0) -> None:
    """Until the detached builder of ``lib`` has let go of its lock (it holds it to the end)."""
    import fcntl
    import time

    deadline = time.monotonic() + timeout
    with open(lib.with_suffix(".lock"), "a") as f:
        while True:
            try:
                fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
                fcntl.flock(f, fcntl.LOCK_UN)
                return
            except BlockingIOError:
                assert time.monotonic() < deadline, "the background build did not end"
                time.sleep(0.1)


@pytest.fixture
def background(tmp_path, monkeypatch):
    """The users' default: a cache miss solves in the virtual machine while a detached
    process compiles; an empty cache of its own."""
    if codegen._compiler() is None:
        pytest.skip("no C compiler on this machine")
    monkeypatch.setenv(codegen.MODE_ENV, "background")
    monkeypatch.setenv(codegen.ENV, str(tmp_path / "cache"))
    monkeypatch.setattr(codegen, "BACKGROUND_DELAY", 0.0)  # not waiting for this process
    return tmp_path / "cache"


def test_a_miss_runs_uncompiled_while_a_detached_process_compiles(background, tmp_path,
                                                                   monkeypatch, capfd):
    """Issue 37: the first run does not wait for the compiler. It gets the functions as CasADi
    builds them (the same numbers) at once; a process that is nobody's child (a batch's or a
    test's process tree does not hold it) compiles them into the cache; the next call loads
    the library without building anything; the build folder is gone and nothing was written
    to the working folder."""
    import psutil

    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    n = codegen.COMPILE_COUNT
    key = f"bg-{os.getpid()}-{np.random.default_rng().integers(1 << 30)}"
    funs, compiled = codegen.compiled_functions(key, _functions, "the test's")
    assert not compiled and codegen.COMPILE_COUNT == n + 1
    assert isinstance(funs["val"], ca.Function) and funs["val"].class_name() == "SXFunction"
    said = capfd.readouterr().err
    assert "the test's optimal-adaptor derivatives run in CasADi's virtual machine this " \
           "time" in said and "builds them in the background" in said
    builders = [p for p in psutil.Process().children(recursive=True)
                if "codegen" in " ".join(p.cmdline())]
    assert builders == []  # detached: not this process's child
    lib = codegen.library(key)
    _wait_for_build(lib)
    assert lib.exists() and not lib.with_suffix(".failed").exists()
    assert not [p for p in background.iterdir() if p.name.startswith(".build-")]

    def must_not_build():
        raise AssertionError("a cached library must be loaded, not rebuilt")

    again, compiled2 = codegen.compiled_functions(key, must_not_build)
    assert compiled2 and codegen.COMPILE_COUNT == n + 1
    x = np.array([0.3, -1.2, 0.7])
    for name in ("val", "dval"):
        assert again[name].class_name() == "External"
        np.testing.assert_array_equal(np.array(again[name](x)), np.array(funs[name](x)))
    assert list(work.iterdir()) == []


def test_a_miss_during_another_build_neither_waits_nor_builds_again(background, capfd):
    """A process that misses a library another process is compiling (it holds the build
    lock) solves uncompiled at once and starts no second build."""
    import fcntl

    key = f"busy-{os.getpid()}"
    lib = codegen.library(key)
    lib.parent.mkdir(parents=True)
    n = codegen.COMPILE_COUNT
    with open(lib.with_suffix(".lock"), "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)  # the other process's build
        funs, compiled = codegen.compiled_functions(key, _functions, "the test's")
    assert not compiled and codegen.COMPILE_COUNT == n
    assert "another process is compiling the test's derivatives" in capfd.readouterr().err
    assert not [p for p in background.iterdir() if p.name.startswith(".build-")]
    assert float(funs["val"](np.array([0.5, 2.0, 0.0]))[0]) == pytest.approx(np.sin(0.5) * 2)


def test_a_failed_background_build_is_said_and_not_tried_again(background, tmp_path,
                                                              monkeypatch):
    """The detached compiler fails (here a compiler that refuses every file): why is kept in
    ``<lib>.failed``, the next miss says it in a SlowDerivativesWarning and runs uncompiled
    without starting another build."""
    cc = tmp_path / "broken-cc"
    cc.write_text("#!/bin/sh\necho 'broken-cc: no code today' >&2\nexit 1\n")
    cc.chmod(0o755)
    monkeypatch.setenv("CC", str(cc))
    monkeypatch.setattr(codegen, "_WARNED", False)
    key = f"fail-{os.getpid()}"
    codegen.compiled_functions(key, _functions)
    lib = codegen.library(key)
    _wait_for_build(lib)
    assert "broken-cc: no code today" in lib.with_suffix(".failed").read_text()
    n = codegen.COMPILE_COUNT
    with pytest.warns(codegen.SlowDerivativesWarning, match="no code today"):
        funs, compiled = codegen.compiled_functions(key, _functions)
    assert not compiled and codegen.COMPILE_COUNT == n and not lib.exists()


def test_the_adaptor_loads_the_library_once_it_has_come(background):
    """In one process: the first adaptation of a problem runs its derivatives uncompiled
    (the solver record says so); once the background build has landed, the next call of the
    same problem runs the compiled library, to the same result."""
    from gdimitate.adaptation.adaptor import adapt
    from gdimitate.apps.cases import paper_case
    from gdimitate.retarget.trajectory import problem as pb

    d, i, m = paper_case("I")
    m = m.replace(t=m.t[:30], q=m.q[:30], contact={s: c[:30] for s, c in m.contact.items()})
    pb.clear_cache()
    try:
        first = adapt(m, d, i, method="optimal", rate=25, verbose=False)
        assert first.solver.derivatives == "virtual machine" and first.solver.compiled
        for lib in background.glob("*.lock"):
            _wait_for_build(lib.with_suffix(".so"))
        second = adapt(m, d, i, method="optimal", rate=25, verbose=False)
    finally:
        pb.clear_cache()
    assert second.solver.derivatives == "C" and not second.solver.compiled
    assert second.solver.iterations == first.solver.iterations
    np.testing.assert_allclose(second.motion.q, first.motion.q, rtol=0, atol=1e-9)


_FIRST_RUN = """
import sys, time
from pathlib import Path
import casadi as ca
from gdimitate.retarget.trajectory import codegen
x = ca.SX.sym("x", 2)
funs, compiled = codegen.compiled_functions(sys.argv[1], lambda: [ca.Function("sq", [x], [x * x])])
time.sleep(3.0)  # a small library compiles in under a second: it must not have, meanwhile
print("FIRST", compiled, codegen.library(sys.argv[1]).exists(), float(funs["sq"](3.0)[0]))
"""


def test_the_background_build_waits_for_the_run_that_started_it(background, monkeypatch):
    """By default the detached compiler starts when the process that missed the library has
    ended (a compiler beside the first demo doubled its numba compilation): nothing is
    compiled while that process runs; after it has ended the library comes and the next
    process loads it."""
    import subprocess
    import sys

    monkeypatch.setattr(codegen, "BACKGROUND_DELAY", 60.0)
    key = f"first-{os.getpid()}"
    out = subprocess.run([sys.executable, "-c", _FIRST_RUN, key], capture_output=True,
                         text=True, timeout=120, env={**os.environ})
    assert "FIRST False False 9.0" in out.stdout, out
    lib = codegen.library(key)
    _wait_for_build(lib)
    again, compiled = codegen.compiled_functions(key, lambda: [])
    assert compiled and float(again["sq"](3.0)[0]) == 9.0


def test_an_unknown_compile_mode_is_refused(monkeypatch):
    from gdimitate.errors import InvalidInputError

    monkeypatch.setenv(codegen.MODE_ENV, "later")
    with pytest.raises(InvalidInputError, match="'background'.*or 'wait'"):
        codegen.compiled_functions("never-built", _functions)
    monkeypatch.setenv(codegen.MODE_ENV, " Wait ")
    assert codegen.mode() == "wait"


def test_a_cache_folder_that_cannot_be_written_runs_uncompiled_with_a_warning(background,
                                                                               monkeypatch):
    """A cache path that is a file (or read-only): the miss says so once and solves in the
    virtual machine; nothing raises."""
    blocker = background.parent / "not-a-folder"
    blocker.write_text("")
    monkeypatch.setenv(codegen.ENV, str(blocker / "cache"))
    monkeypatch.setattr(codegen, "_WARNED", False)
    with pytest.warns(codegen.SlowDerivativesWarning, match="cannot be written"):
        funs, compiled = codegen.compiled_functions("ro", _functions)
    assert not compiled and float(funs["val"](np.array([0.5, 2.0, 0.0]))[0]) == \
        pytest.approx(np.sin(0.5) * 2)


def test_a_killed_builders_folder_is_removed_by_the_next_build(background):
    """A background build killed before it finished (a cluster's job scheduler ends every
    process of a job) leaves its build folder and no library; the next miss of that library
    removes the folder and builds again."""
    key = f"killed-{os.getpid()}"
    lib = codegen.library(key)
    stale = background / f".build-{lib.stem}-x1y2z3"
    stale.mkdir(parents=True)
    (stale / "val.c").write_text("/* half-written */")
    other = background / ".build-knot-someone-else-abc"
    other.mkdir()
    codegen.compiled_functions(key, _functions)
    assert not stale.exists() and other.exists()
    _wait_for_build(lib)
    assert lib.exists()
