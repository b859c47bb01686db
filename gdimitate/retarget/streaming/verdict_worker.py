"""The streaming mode's per-frame verdict, off the hot path (docs/design.md §6, §12, §13).

A frame's verdict is the trajectory audit's knot verdict (:func:`gdimitate.assess.audit.audit`,
``knot_feasible``), recomputed from the stream's own output: :func:`knot_verdicts` is its one
definition, whoever runs it. Knot k's checks read frames k − 1 (the step's length, for the
stance soles' velocity), k and k + 1 (forward differences of ``q``, the next velocity and
acceleration) and, for each foot in stance at k, the frame its stance began (slip is the
sole's drift since then) — nothing else: every other quantity of the audit is per knot. So
knots ``first..last`` are audited on those frames only (:func:`verdict_frames`), whatever the
stream's length, and each verdict equals the one the audit of the whole assembled motion gives
that knot. Frame k + 1's acceleration is final one frame later (it comes with frame k + 2's
step), and only knot k's ``velocity_consistency`` reads it: the allowance ``h·|a_{k+1} − a_k|
/ 2`` for a change of acceleration. Until it is known, knot k is judged without the allowance
(``a_{k+1}`` taken as ``a_k``, the strictest reading): a knot that passes so, or fails another
check, has its verdict; one that fails ``velocity_consistency`` alone is undecided (None) until
the acceleration comes, a frame later. On the streaming mode's exact integration the forward
difference is ``v_{k+1}`` to round-off, so that happens only where the robot jumps (a restart,
:meth:`~.adaptor.StreamingAdaptor._recover`).

Who runs it: :class:`InlineVerdicts` in the caller's thread (on the hot path: one audit a
frame, ~20 ms on Talos), or :class:`VerdictWorker`, a worker process forked from the caller
that audits every frame committed so far, in batches (one audit per batch: ~1.5 ms a frame on
Talos, most of it the self-collision distances), while the caller goes on — the verdict of
frame k arrives a few frames later (``StreamingAdaptor.step``'s ``FrameResult.verdicts``)
without slowing frame k + 1 (a thread would hold the interpreter's lock; the worker runs at
:data:`WORKER_NICE`). Forked, it inherits the limited robot, its convex collision hulls and
the soles, where pickling them would not do (coal's hulls have no serialisation, and Talos's
meshes alone made 350 MB and 25 s to pickle and load back); only the frames go through the
pipe. It ends when the caller closes (or loses) the pipe, and :meth:`VerdictWorker.close`
ends and reaps it (so do garbage collection and the interpreter's exit): no process is left
behind, no file written. Platforms without ``fork`` judge inline.
"""

from __future__ import annotations

import gc
import math
import os
import pickle
import select
import signal
import struct
import time
import traceback
import weakref
from collections.abc import Mapping, Sequence

import numpy as np

from ...errors import GdimitateError, InvalidInputError
from ...model.contact import SoleContact
from ...model.kinematics import robot_motion
from ...model.robot import SIDES, Robot
from ..threads import single_thread

__all__ = ["InlineVerdicts", "VerdictWorker", "VerdictWorkerError", "knot_verdicts",
           "verdict_frames", "can_fork"]

#: seconds :meth:`VerdictWorker.close` waits for the worker to exit before killing it
CLOSE_TIMEOUT_S = 5.0
#: the worker audits at most this often [s]: an audit's fixed cost (~17 ms on Talos: its
#: per-check bookkeeping) is paid once per period, not once per frame of a slow stream
BATCH_PERIOD_S = 0.05
#: the worker's niceness above the caller's: where the cores are busy the frames go first (on
#: an idle machine with two cores or more it changes nothing)
WORKER_NICE = 5
_HEADER = struct.Struct("<Q")
#: the parent-side pipe ends of the live workers (a new worker closes its copies of them)
_LIVE_FDS: set[int] = set()


class VerdictWorkerError(GdimitateError):
    """The verdict worker failed (its traceback in the message), exited, or did not answer
    within the time asked."""


def can_fork() -> bool:
    """Whether this platform runs :class:`VerdictWorker` (``os.fork``)."""
    return hasattr(os, "fork")


# ---------------------------------------------------------------------- the verdict
def verdict_frames(c: Sequence[Mapping[str, bool]], first: int, last: int) -> list[int]:
    """The frames knots ``first..last``'s verdicts read, sorted: ``first − 1 .. last + 1``
    (within the ``len(c)`` frames) and, for each foot in stance at ``first`` (``c[k][side]``:
    frame k's stance flags), the frame its stance began and the one before (which marks the
    start). A foot in stance at a later knot of the range but not at ``first`` began it within
    the range."""
    n = len(c)
    if not 0 <= first <= last < n:
        raise InvalidInputError(f"knots {first}..{last} are not among the {n} frames")
    keep = set(range(max(first - 1, 0), min(last + 2, n)))
    for s in SIDES:
        if c[first][s]:
            b = first
            while b > 0 and c[b - 1][s]:
                b -= 1
            keep.update((b - 1, b) if b else (b,))
    return sorted(keep)


def knot_verdicts(robot: Robot, contacts: Mapping[str, SoleContact], cone_half_angle: float,
                  H: Mapping[str, Sequence], first: int, last: int,
                  tail: tuple[np.ndarray, dict] | None = None) -> list[bool | None]:
    """The audit's knot verdicts (``knot_feasible``) of frames ``first..last`` of a stream
    (module docstring): ``robot`` the limited imitator, ``contacts`` its soles,
    ``cone_half_angle`` [rad]; ``H`` the frames: ``t`` [s], ``q`` ``(nq,)``, ``v`` ``(nv,)``
    [rad/s, m/s] and ``c`` (``{side: bool}``) per frame; ``a`` ``(nv,)`` [rad/s², m/s²] and
    ``w`` (``{side: (6,)}`` [N, N·m], sole frames) per knot, as far as they are final.
    ``tail``: ``(a, w)`` of the last frame (its own QP, :meth:`StreamingAdaptor.final`),
    which ``last`` may then be. Knot ``last``'s verdict is None where it is undecided: the
    next frame's acceleration not known yet, and the knot failing ``velocity_consistency``
    alone without the allowance that acceleration may grant (module docstring)."""
    from ...assess.audit import audit

    n = len(H["t"])
    if tail is not None and len(H["a"]) == n - 1:
        H = {**H, "a": [*H["a"], tail[0]], "w": [*H["w"], tail[1]]}
    if last >= len(H["a"]):
        raise InvalidInputError(f"frame {last}'s acceleration is not known yet")
    keep = verdict_frames(H["c"], first, last)
    a = [H["a"][min(k, len(H["a"]) - 1)] for k in keep]  # unknown: the strictest reading
    w = [H["w"][min(k, len(H["w"]) - 1)] for k in keep]
    flags = {s: np.array([H["c"][k][s] for k in keep]) for s in SIDES}
    mo = robot_motion(robot, np.array([H["t"][k] for k in keep]),
                      np.array([H["q"][k] for k in keep]), flags).replace(
        v=np.array([H["v"][k] for k in keep]), a=np.array(a))
    rep = audit(robot, mo, {s: np.array([x[s] for x in w]) for s in SIDES}, contacts,
                cone_half_angle=cone_half_angle)
    at = keep.index(first)
    out: list[bool | None] = [bool(x) for x in rep.knot_feasible[at:at + last - first + 1]]
    if last + 1 < n and last + 1 >= len(H["a"]) and not out[-1]:
        k = at + last - first
        others = np.delete(rep.knot_checks[:, k], [c.name for c in rep.checks].index(
            "velocity_consistency"))
        if others.all():
            out[-1] = None
    return out


def _empty() -> dict[str, list]:
    return {k: [] for k in ("t", "q", "v", "c", "a", "w")}


def _judgeable(H: dict[str, list]) -> int:
    """The last knot whose verdict may be known: its next frame and its own ``a`` are in."""
    return min(len(H["t"]) - 2, len(H["a"]) - 1)


def _add(H: dict[str, list], frame: tuple) -> None:
    """Append one committed frame ``(t, q, v, c, a_prev, w_prev)`` (the previous knot's ``a``,
    ``w``, final with it; ``None`` at the first frame)."""
    t, q, v, c, a_prev, w_prev = frame
    for k, x in (("t", t), ("q", q), ("v", v), ("c", c)):
        H[k].append(x)
    if a_prev is not None:
        H["a"].append(a_prev)
        H["w"].append(w_prev)


class InlineVerdicts:
    """:func:`knot_verdicts` in the caller, frame by frame: frame k − 1's verdict as soon as
    frame k is added (where it is undecided, a frame later)."""

    def __init__(self, robot: Robot, contacts: Mapping[str, SoleContact],
                 cone_half_angle: float):
        self._args = (robot, dict(contacts), float(cone_half_angle))
        self._H: dict[str, list] = _empty()
        self._done = 0
        self._new: list[tuple[int, bool]] = []

    def reset(self) -> None:
        """Forget the frames."""
        self._H, self._done, self._new = _empty(), 0, []

    def add(self, frame: tuple) -> None:
        """Add one committed frame ``(t, q, v, c, a_prev, w_prev)`` and judge what it
        completes."""
        _add(self._H, frame)
        for j in range(self._done, _judgeable(self._H) + 1):
            ok = knot_verdicts(*self._args, self._H, j, j)[0]
            if ok is None:
                break
            self._new.append((j, ok))
            self._done = j + 1

    def collect(self, wait: bool = False, timeout: float | None = None) -> list[tuple[int, bool]]:
        """``[(frame, feasible), ...]`` judged since the last call (all of them already)."""
        out, self._new = self._new, []
        return out

    def close(self) -> None:
        """Nothing to stop."""


# ---------------------------------------------------------------------- the worker process
class _Pipe:
    """Length-prefixed pickles over a pair of pipe ends: ``send`` queues and writes what the
    pipe takes without blocking (the rest on the next call); ``recv`` reads what has
    arrived."""

    def __init__(self, rfd: int, wfd: int):
        self.rfd, self.wfd = rfd, wfd
        for fd in (rfd, wfd):
            os.set_blocking(fd, False)
        self._out, self._in = bytearray(), bytearray()
        self.eof = False

    def send(self, obj: object) -> None:
        data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
        self._out += _HEADER.pack(len(data)) + data
        self.flush()

    def flush(self) -> None:
        """Write what the pipe takes now."""
        while self._out:
            try:
                n = os.write(self.wfd, self._out)
            except BlockingIOError:
                return
            del self._out[:n]

    def recv(self) -> list:
        """The messages complete so far (reads without blocking; ``eof`` once closed)."""
        while not self.eof:
            try:
                chunk = os.read(self.rfd, 1 << 20)
            except BlockingIOError:
                break
            if not chunk:
                self.eof = True
            self._in += chunk
        out = []
        while len(self._in) >= _HEADER.size:
            (size,) = _HEADER.unpack_from(self._in)
            if len(self._in) < _HEADER.size + size:
                break
            out.append(pickle.loads(self._in[_HEADER.size:_HEADER.size + size]))
            del self._in[:_HEADER.size + size]
        return out

    def wait(self, timeout: float | None) -> None:
        """Block until there is something to read, or room to write what is queued
        (``timeout`` [s], None: no limit)."""
        p = select.poll()
        p.register(self.rfd, select.POLLIN)
        if self._out:
            p.register(self.wfd, select.POLLOUT)
        p.poll(None if timeout is None else max(math.ceil(timeout * 1000), 0))


def _serve(args: tuple[Robot, dict, float], pipe: _Pipe) -> None:
    """The worker's loop: frames in, ``("verdicts", epoch, first, [bool, ...], pending)`` out
    — every frame judgeable, at most once per :data:`BATCH_PERIOD_S`; ``pending``: the next
    knot is undecided (it waits for the next frame)."""
    H, done, epoch, since = _empty(), 0, 0, -np.inf
    undecided = -1  # len(H["a"]) when knot `done` was found undecided (it waits for more)
    while True:
        pipe.flush()
        for msg in pipe.recv():
            if msg[0] == "frame":
                _add(H, msg[1])
            else:  # "reset"
                H, done, epoch, undecided = _empty(), 0, msg[1], -1
        if pipe.eof:
            return
        last = _judgeable(H)
        ready = last >= done and len(H["a"]) != undecided
        left = since + BATCH_PERIOD_S - time.monotonic()
        if ready and left <= 0:
            since = time.monotonic()
            oks = knot_verdicts(*args, H, done, last)
            pending = oks[-1] is None  # only the newest can be
            if pending:
                oks.pop()
                undecided = len(H["a"])
            pipe.send(("verdicts", epoch, done, oks, pending))
            done += len(oks)
        else:  # nothing to judge yet: wait for frames (or for the period to pass)
            pipe.wait(left if ready else None)


def _child(args: tuple[Robot, dict, float], rfd: int, wfd: int, others: set[int]) -> None:
    """The forked worker: never returns (``os._exit``)."""
    code = 1
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the caller's to handle
        try:
            os.nice(WORKER_NICE)
        except OSError:
            pass
        gc.freeze()  # the inherited objects stay shared with the caller (copy-on-write)
        for fd in others:
            try:
                os.close(fd)
            except OSError:
                pass
        pipe = _Pipe(rfd, wfd)
        try:
            with single_thread():
                _serve(args, pipe)
            code = 0
        except BaseException:
            pipe.send(("error", traceback.format_exc()))
            os.set_blocking(wfd, True)
            pipe.flush()
    finally:
        os._exit(code)


def _stop(pid: int, owner: int, fds: tuple[int, ...]) -> None:
    """Close the caller's pipe ends, end the worker (SIGTERM; SIGKILL after
    :data:`CLOSE_TIMEOUT_S`) and reap it. In a process forked from the caller (not the
    worker's parent), only the pipe ends are closed."""
    for fd in fds:
        _LIVE_FDS.discard(fd)
        try:
            os.close(fd)
        except OSError:
            pass
    if os.getpid() != owner:
        return
    try:
        os.kill(pid, signal.SIGTERM)  # unreaped, the pid cannot have been reused
        end = time.monotonic() + CLOSE_TIMEOUT_S
        while os.waitpid(pid, os.WNOHANG) == (0, 0):
            if time.monotonic() > end:
                os.kill(pid, signal.SIGKILL)
                os.waitpid(pid, 0)
                return
            time.sleep(0.002)
    except ChildProcessError:  # already reaped
        pass


class VerdictWorker:
    """:func:`knot_verdicts` in a worker process forked from the caller (module docstring):
    :meth:`add` hands it each committed frame without waiting, :meth:`collect` returns the
    verdicts it has sent since (in frame order), :meth:`close` stops it. Raises
    :class:`VerdictWorkerError` where the platform has no ``fork`` and when the worker
    fails."""

    def __init__(self, robot: Robot, contacts: Mapping[str, SoleContact],
                 cone_half_angle: float):
        if not can_fork():
            raise VerdictWorkerError("this platform cannot fork a verdict worker; use "
                                     "audit='inline'")
        from ...assess.audit import audit  # noqa: F401  (loaded once, before the fork)

        args = (robot, dict(contacts), float(cone_half_angle))
        down_r, down_w = os.pipe()  # caller -> worker
        up_r, up_w = os.pipe()  # worker -> caller
        pid = os.fork()
        if pid == 0:  # the worker
            os.close(down_w)
            os.close(up_r)
            _child(args, down_r, up_w, set(_LIVE_FDS))
        os.close(down_r)
        os.close(up_w)
        _LIVE_FDS.update((down_w, up_r))
        self.pid = pid
        self._pipe = _Pipe(up_r, down_w)
        self._epoch, self._sent, self._got, self._pending = 0, 0, 0, False
        self._stop = weakref.finalize(self, _stop, pid, os.getpid(), (down_w, up_r))

    @property
    def alive(self) -> bool:
        """Whether the worker has not been stopped."""
        return self._stop.alive

    def add(self, frame: tuple) -> None:
        """Hand the worker one committed frame ``(t, q, v, c, a_prev, w_prev)`` (queued when
        its pipe is full: never waits)."""
        self._check()
        try:
            self._pipe.send(("frame", frame))
        except OSError as e:  # the worker is gone: say why
            self.collect()  # raises with its traceback, or that it exited
            raise VerdictWorkerError(f"the verdict worker takes no frames: {e}") from e
        self._sent += 1

    def reset(self) -> None:
        """Forget the frames (verdicts still on their way are dropped)."""
        self._check()
        self._epoch += 1
        self._sent = self._got = 0
        self._pending = False
        self._pipe.send(("reset", self._epoch))

    def collect(self, wait: bool = False, timeout: float | None = None) -> list[tuple[int, bool]]:
        """``[(frame, feasible), ...]`` arrived since the last call; ``wait``: first wait until
        every frame but the newest has one, or but the newest two where the one before the
        newest is undecided (it waits for the newest's acceleration: :func:`knot_verdicts`)
        (``timeout`` [s], None: no limit; raises :class:`VerdictWorkerError` when it
        passes)."""
        self._check()
        out: list[tuple[int, bool]] = []
        end = None if timeout is None else time.monotonic() + timeout
        while True:
            self._pipe.flush()
            for msg in self._pipe.recv():
                if msg[0] == "error":
                    self.close()
                    raise VerdictWorkerError(f"the verdict worker failed:\n{msg[1]}")
                _, epoch, first, oks, pending = msg
                if epoch == self._epoch:
                    out.extend((first + i, ok) for i, ok in enumerate(oks))
                    self._got, self._pending = first + len(oks), pending
            if self._pipe.eof:
                self.close()
                raise VerdictWorkerError("the verdict worker exited")
            if not wait or self._got >= self._sent - 1 or (
                    self._pending and self._got == self._sent - 2):
                return out
            left = None if end is None else end - time.monotonic()
            if left is not None and left <= 0:
                raise VerdictWorkerError(f"verdicts of frames {self._got}..{self._sent - 2} "
                                         f"did not arrive within {timeout} s")
            self._pipe.wait(left)

    def close(self) -> None:
        """Stop the worker and reap it (idempotent); later calls raise."""
        self._stop()

    def _check(self) -> None:
        if not self._stop.alive:
            raise VerdictWorkerError("the verdict worker has been closed")
