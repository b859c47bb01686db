"""``gdimitate stream``: a live mocap stream adapted frame by frame, the robot shown following
it, and — when it stops — the same outputs as ``adapt`` for the frames streamed
(docs/guide/streaming.md).

Each frame that arrives goes through :meth:`gdimitate.retarget.StreamingAdaptor.step` (the
default constructor: its verdicts from the worker process, off the hot path). The loop always
takes the newest frame: the ones that arrived while it was busy are dropped and counted
(:mod:`gdimitate.io.live.source`), so it never falls behind. A frame's latency runs from its
arrival (a BVH file: the moment its frame is due; LSL: its push time stamp, on this machine's
clock) to the step's return — the robot's command (``q``, ``v``). The meshcat view, if asked
for, is drawn by a thread from the newest command (:class:`LiveView`), off the loop.

It stops at the end of the source, after ``frames`` frames adapted or ``seconds`` [s], or at
Ctrl-C / SIGTERM, then collects every frame's verdict, audits the assembled motion and writes
:data:`gdimitate.apps.outputs.ADAPT_FILES` (report.json with a ``"stream"`` entry: frames,
drops, latency, verdicts). Exit status 0 when every frame's verdict is feasible, 3 if not.
"""

from __future__ import annotations

import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..assess.result import AdaptedMotion
from ..assess.verdict import EXIT_NOT_FEASIBLE
from ..errors import InvalidInputError
from ..io.live.layout import LiveSourceError
from ..io.live.source import LiveSource
from ..model.kinematics import robot_motion
from ..model.legs import hip_height
from ..model.motion import Motion
from ..model.robot import SIDES, Robot
from .signals import handling_signals

__all__ = ["LiveView", "StreamLog", "open_source", "run_stream", "stream_command",
           "stream_lines"]

#: the console's progress line comes this often [s]
PROGRESS_S = 1.0
#: the longest wait for the verdicts still on their way after the last frame [s]
VERDICT_WAIT_S = 120.0


@dataclass
class StreamLog:
    """What the loop kept of each adapted frame (K of them): source times ``t`` [s], the
    demonstrator's ``q_demo`` ``(nq_d,)``, stance, the imitator's ``q``, ``v``, ``a`` (``a``
    and ``w`` one frame late: :class:`~gdimitate.retarget.FrameResult`), the wrenches ``w``
    ``{side: (6,)}``, latencies and the steps' own durations [s]; frames received, dropped
    and, among those, not numbers (``invalid``); verdicts ``{frame: ok}``; ``own``: the
    imitator's stance flags (:attr:`~gdimitate.retarget.FrameResult.contact`); ``waited``:
    the first frame, shown but not adapted (the stream starts at the second, with the
    velocity estimated from both: :class:`~gdimitate.retarget.StreamingAdaptor`)."""

    t: list[float] = field(default_factory=list)
    q_demo: list[np.ndarray] = field(default_factory=list)
    contact: list[dict[str, bool]] = field(default_factory=list)
    own: list[dict[str, bool]] = field(default_factory=list)
    q: list[np.ndarray] = field(default_factory=list)
    v: list[np.ndarray] = field(default_factory=list)
    a: list[np.ndarray] = field(default_factory=list)
    w: list[dict] = field(default_factory=list)
    latency: list[float] = field(default_factory=list)
    step: list[float] = field(default_factory=list)
    received: int = 0
    dropped: int = 0
    invalid: int = 0
    waited: int = 0
    t_waited: float | None = None
    verdicts: dict[int, bool] = field(default_factory=dict)


class LiveView:
    """The imitator in a :class:`~gdimitate.viz.Viewer`'s meshcat scene, following the
    stream: :meth:`offer` hands it the newest command ``q`` ``(nq,)``; a thread draws the
    newest one offered (each drawing is ~35 requests to the server for G1, 20–40 ms on a loaded
    machine: slower than 120 Hz, so it skips to the newest instead of queueing); ``updates``
    counts the drawings. :meth:`close` draws the last frame offered and stops the thread."""

    def __init__(self, viewer: Any, robot: Robot, q0: np.ndarray):
        from ..viz.animate import place_frame, sample_frames

        two = np.stack([q0, q0])
        stance = {s: np.ones(2, bool) for s in SIDES}
        self.name = viewer.show(robot, robot_motion(robot, np.array([0.0, 1.0]), two, stance),
                                foot_paths=False)
        track = viewer.tracks[self.name]
        self._nodes = [viewer.vis[self.name]["robot"][n] for n in track.nodes]
        self._com = viewer.vis[self.name]["com"]
        self._model, self._visual = track.model, track.visual_model
        self._sample, self._place = sample_frames, place_frame
        self._q: np.ndarray | None = None
        self._lock, self._wake, self._done = threading.Lock(), threading.Event(), False
        self.updates = 0
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="gdimitate-view", daemon=True)
        self._thread.start()

    def offer(self, q: np.ndarray) -> None:
        """The newest command to draw (replaces one not drawn yet)."""
        with self._lock:
            self._q = q.copy()
        self._wake.set()

    def _draw_newest(self) -> None:
        with self._lock:
            q, self._q = self._q, None
        if q is None:
            return
        f = self._sample(self._model, self._visual, np.zeros(1), q[None], 1.0)
        self._place(self._nodes, f.placements[0])
        pose = np.eye(4)
        pose[:3, 3] = f.com[0]
        self._com.set_transform(pose)
        self.updates += 1

    def _run(self) -> None:
        try:
            while not self._done:
                self._wake.wait(0.2)
                self._wake.clear()
                self._draw_newest()
        except BaseException as e:  # a server gone: said at close(), the stream goes on
            self.error = e

    def close(self) -> None:
        """Draw the last frame offered, stop the thread."""
        self._done = True
        self._wake.set()
        self._thread.join(30.0)
        if self.error is None:
            self._draw_newest()


@contextmanager
def _stop_on_signals() -> Iterator[dict[str, str | None]]:
    """Ctrl-C (SIGINT) and SIGTERM set ``["reason"]`` instead of interrupting (the loop
    stops and writes what it streamed); the previous handlers are back afterwards (a second
    Ctrl-C while writing interrupts: gdimitate.apps.cli's status 130, the outputs undone)."""
    state: dict[str, str | None] = {"reason": None}

    def on(signum: int, frame: object) -> None:
        state["reason"] = "Ctrl-C" if signum == signal.SIGINT else "SIGTERM"

    with handling_signals(on):
        yield state


def _stream_loop(source: LiveSource, sa: Any, log: StreamLog, stop: dict, *,
                 frames: int | None, seconds: float | None, delay_s: float,
                 view: LiveView | None, say: Callable[[str], None]) -> str:
    """Adapt the newest frame until a stop; ``log`` filled; returns why it stopped."""
    start = last_said = time.perf_counter()
    layout = source.layout
    while True:
        now = time.perf_counter()
        reason = (stop["reason"] or (f"{frames} frames (--frames)" if frames and len(log.t)
                                     >= frames else None)
                  or (f"{seconds:g} s (--seconds)" if seconds and now - start >= seconds
                      else None) or source.ended)
        if reason:
            return reason
        if now - last_said >= PROGRESS_S and log.t:
            say(_progress(log, now - start))
            last_said = now
        frame, skipped = source.newest(0.05)
        if frame is None:
            continue
        log.received += skipped + 1
        log.dropped += skipped
        last = log.t[-1] if log.t else log.t_waited
        if last is not None and frame.t <= last:  # no time passed since the last: not one
            log.dropped += 1
            continue
        try:
            q_demo, contact = layout.decode(frame.sample, frame.t)
        except LiveSourceError:  # not numbers (an occluded marker's NaN): dropped, counted
            log.dropped += 1
            log.invalid += 1
            continue
        t_step = time.perf_counter()
        r = sa.step(q_demo, contact, None if last is None else frame.t - last)
        log.step.append(time.perf_counter() - t_step)
        log.latency.append(source.now() - frame.arrived)
        if view is not None:
            view.offer(r.q)
        if r.status == "waiting":  # the first frame: a preview, not a frame of the motion
            log.waited, log.t_waited = log.waited + 1, frame.t
            continue
        for k, x in (("t", frame.t), ("q_demo", q_demo), ("contact", contact), ("q", r.q),
                     ("v", r.v), ("own", r.contact)):
            getattr(log, k).append(x)
        if r.previous_a is not None:
            log.a.append(r.previous_a)
            log.w.append(r.previous_wrenches)
        log.verdicts.update((f - sa.first_frame, ok) for f, ok in r.verdicts
                            if f >= sa.first_frame)
        if delay_s:
            time.sleep(delay_s)


def _progress(log: StreamLog, elapsed: float) -> str:
    lat = np.asarray(log.latency) * 1e3
    ok = sum(log.verdicts.values())
    return (f"  {elapsed:5.1f} s: {len(log.t)} frames adapted, {log.dropped} dropped; latency "
            f"median {np.median(lat):.2f} ms, max {lat.max():.2f} ms; verdicts so far {ok} of "
            f"{len(log.verdicts)} feasible")


def _assembled(sa: Any, log: StreamLog) -> tuple[Motion, AdaptedMotion]:
    """The demonstration received and the motion streamed as :func:`gdimitate.adapt`'s
    ``mode="per_frame"`` result (``frame_feasible``: the audit of the assembled motion knot
    by knot — what the stream's verdicts are, frame for frame)."""
    from ..assess.audit import audit
    from ..assess.result import compare
    from ..model.footsteps import compare_gait
    from ..retarget.streaming.adaptor import streamed_info

    t = np.asarray(log.t) - log.t[0]
    contact = {s: np.array([c[s] for c in log.contact], bool) for s in SIDES}
    own = {s: np.array([c[s] for c in log.own], bool) for s in SIDES}
    demonstrator, imitator = sa.demonstrator, sa.imitator
    demo = robot_motion(demonstrator, t, np.stack(log.q_demo), contact)
    motion = robot_motion(imitator, t, np.stack(log.q), own).replace(
        v=np.stack(log.v), a=np.stack(log.a))
    W = {s: np.stack([w[s] for w in log.w]) for s in SIDES}
    aud = audit(sa._audit_robot, motion, W, sa.contacts,
                cone_half_angle=sa.contact.cone_half_angle)
    ok = np.asarray(aud.knot_feasible, bool)
    report = compare(demonstrator, demo, imitator, motion, "optimal",
                     {s: ok.copy() for s in SIDES}, sa.force)
    info = streamed_info("streamed", ok, float(np.sum(log.step)))
    result = AdaptedMotion(motion=motion, report=report, robot=imitator, wrenches=W,
                           contacts=dict(sa.contacts), audit=aud, solver=info,
                           force_model=sa.force, frame_feasible=ok,
                           gait=compare_gait(demonstrator, demo, imitator, motion))
    return demo, result


def _record(source: LiveSource, log: StreamLog, reason: str, wall_s: float,
            verdicts: np.ndarray, audit_ok: np.ndarray, view: LiveView | None) -> dict:
    """report.json's ``"stream"`` entry (latencies in ms)."""
    lat, step = np.asarray(log.latency) * 1e3, np.asarray(log.step) * 1e3
    return {"source": source.description, "stopped": reason, "seconds": wall_s,
            "frames_received": log.received, "frames_adapted": len(log.t),
            "frames_dropped": log.dropped, "frames_invalid": log.invalid,
            "frames_waited": log.waited,
            "frame_period_ms": 1e3 / source.rate,
            "latency_ms": {"median": float(np.median(lat)),
                           "p95": float(np.percentile(lat, 95)), "max": float(lat.max())},
            "step_ms": {"median": float(np.median(step)), "max": float(step.max())},
            "verdicts": {"feasible": int(verdicts.sum()), "frames": int(verdicts.size),
                         "per_frame": [int(x) for x in verdicts]},
            "verdicts_are_the_audit": bool(np.array_equal(verdicts, audit_ok)),
            "view_updates": None if view is None else view.updates,
            "view_error": None if view is None or view.error is None else str(view.error)}


def stream_lines(report: dict) -> list[str]:
    """The console's summary of a stream, from report.json's ``"stream"`` entry."""
    s = report["stream"]
    lat, v = s["latency_ms"], s["verdicts"]
    share = 100.0 * v["feasible"] / max(v["frames"], 1)
    lines = [f"streamed {s['frames_adapted']} frames from {s['source']}; stopped: "
             f"{s['stopped']} ({s['seconds']:.2f} s)",
             f"received {s['frames_received']} frames, dropped {s['frames_dropped']} (the "
             "loop takes the newest frame: those that arrived while it was busy"
             + (f"; {s['frames_invalid']} not numbers" if s["frames_invalid"] else "") + ")"
             + (f"; the first {s['frames_waited']} shown, not adapted (the stream starts "
                "moving with the velocity estimated from it)" if s["frames_waited"] else ""),
             f"latency receive → command: median {lat['median']:.2f} ms, p95 {lat['p95']:.2f} "
             f"ms, max {lat['max']:.2f} ms (frame period {s['frame_period_ms']:.2f} ms; the "
             f"adaptor's step alone: median {s['step_ms']['median']:.2f} ms, max "
             f"{s['step_ms']['max']:.2f} ms)",
             f"verdicts: {v['feasible']} of {v['frames']} frames feasible ({share:.1f} %)"
             + ("" if s["verdicts_are_the_audit"] else
                "; NOT the audit of the written motion frame for frame")]
    if s["view_updates"] is not None:
        lines.append(f"meshcat view drawn {s['view_updates']} times" + (
            f"; it stopped: {s['view_error']}" if s["view_error"] else ""))
    return lines


def run_stream(source: LiveSource, imitator: Robot, out: Path, *, frames: int | None = None,
               seconds: float | None = None, delay_s: float = 0.0, viewer: Any = None,
               say: Callable[[str], None] = print) -> tuple[int, dict]:
    """Stream ``source`` onto ``imitator`` (module docstring) and write the outputs into the
    folder ``out``; ``viewer``: a :class:`~gdimitate.viz.Viewer` to draw in (None: no view);
    ``delay_s`` [s]: a wait after each frame (a slower consumer: frames dropped). Returns
    ``(exit status 0 or 3, the written report.json as a dict)``."""
    import json

    from ..retarget import StreamingAdaptor
    from .outputs import write_adapted

    if frames is not None and frames < 2 or delay_s < 0:
        raise InvalidInputError("--frames must be ≥ 2 and --delay ≥ 0")
    sa = StreamingAdaptor(source.layout.robot, imitator, dt=1.0 / source.rate)
    view = None
    try:
        _warm_up(sa, source)
        if viewer is not None:
            view = LiveView(viewer, imitator, _rest_pose(imitator))
        log = StreamLog()
        say(f"streaming {source.description} onto {imitator.name} (Ctrl-C stops and writes)")
        t0 = time.perf_counter()
        with _stop_on_signals() as stop:
            reason = _stream_loop(source, sa, log, stop, frames=frames, seconds=seconds,
                                  delay_s=delay_s, view=view, say=say)
        wall = time.perf_counter() - t0
        if len(log.t) < 2:
            raise LiveSourceError(f"{len(log.t)} frame(s) received before the stop "
                                  f"({reason}): a motion needs 2")
        a, w, _ = sa.final()
        log.a.append(a)
        log.w.append(w)
        verdicts = sa.verdicts(wait=True, timeout=VERDICT_WAIT_S)[sa.first_frame:]
    finally:
        sa.close()
        if view is not None:
            view.close()
    demo, result = _assembled(sa, log)
    audit_ok = np.asarray(result.frame_feasible, bool)
    extra = {"stream": _record(source, log, reason, wall, verdicts, audit_ok, view)}
    if verdicts.size != len(log.t):
        raise LiveSourceError(f"{verdicts.size} verdicts for {len(log.t)} frames")
    text = write_adapted(out, source.layout.robot, demo, result, extra)
    written = json.loads(text)
    return (0 if bool(np.all(verdicts)) else EXIT_NOT_FEASIBLE), written


def _warm_up(sa: Any, source: LiveSource, frames: int = 3) -> None:
    """A few steps on the skeleton file's first frames, then forgotten (``reset``): the first
    QP of a process costs ~0.2 s (its set-up), which would otherwise be the stream's first
    frame's latency and drop the frames behind it."""
    layout = source.layout
    for x in layout.warm_up_samples(frames):
        sa.step(*layout.decode(x))
    sa.reset()
    layout.reset()


def _rest_pose(robot: Robot) -> np.ndarray:
    """``(nq,)``: the robot's neutral configuration, its base a leg's length up (the view's
    first drawing, before the first frame)."""
    import pinocchio as pin

    q = pin.neutral(robot.model)
    if robot.base == "free":
        q[2] = hip_height(robot)
    return q


def open_source(spec: str, *, skeleton: str | None = None, osim: str | None = None,
                frames: int | None = None, timeout: float = 10.0,
                loopback: bool = False) -> LiveSource:
    """``gdimitate stream``'s SOURCE: a ``.bvh`` file (played at its own rate, its first
    ``frames``), or ``lsl:NAME`` (the LSL stream called NAME, in the channels of the BVH
    ``skeleton`` or of the OpenSim model ``osim``'s coordinates; ``timeout`` [s] to find it
    and of silence; ``loopback``: discovery on this machine only,
    :func:`gdimitate.io.live.lsl.configure`)."""
    from ..io.live.layout import BVHLayout, Layout
    from ..io.live.source import BVHFileSource

    if spec.startswith("lsl:"):
        from ..io.live.lsl import LSLSource

        if not spec[4:]:
            raise InvalidInputError("lsl:NAME needs the stream's name after 'lsl:'")
        if (skeleton is None) == (osim is None):
            raise InvalidInputError("an LSL stream needs its channel layout: --skeleton "
                                    "FILE.bvh (a BVH skeleton's channels) or --osim FILE.osim "
                                    "(an OpenSim model's coordinates), one of them "
                                    "(docs/guide/streaming.md)")
        if skeleton is not None:
            layout: Layout = BVHLayout(skeleton)
        else:
            from ..io.live.coordinates import OpenSimLayout

            layout = OpenSimLayout(str(osim))
        return LSLSource(spec[4:], layout, timeout=timeout, loopback=loopback)
    if not spec.lower().endswith(".bvh"):
        raise InvalidInputError(f"SOURCE {spec!r}: a .bvh file or lsl:NAME")
    return BVHFileSource(spec, frames=frames)


def stream_command(a: Any, out: Path, imitator: Callable[[], Robot]) -> int:
    """``gdimitate stream`` with its parsed arguments ``a`` (gdimitate.apps.cli), writing into
    ``out``; ``imitator()`` loads the robot (after the source is found: a missing stream
    fails at once); prints the summary from the written report.json; returns the exit
    status."""
    from ..assess.verdict import report_lines

    source = open_source(a.source, skeleton=a.skeleton, osim=a.osim, frames=a.frames,
                         timeout=a.timeout, loopback=a.loopback)
    viewer = None
    try:
        robot = imitator()
        if a.view:
            from ..viz import Viewer

            viewer = Viewer.start(a.port, a.open)
        status, written = run_stream(source, robot, out, frames=a.frames,
                                     seconds=a.seconds, delay_s=a.delay / 1e3, viewer=viewer,
                                     say=lambda line: print(line, flush=True))
    finally:
        source.close()
        if viewer is not None:
            viewer.close()
    print(f"wrote {out}/imitator_joints.csv, imitator_motion.npz, report.json, gait.png")
    for line in stream_lines(written) + report_lines(written):
        print(f"  {line}")
    if status:
        print(f"result written, but not every frame is feasible: exit status {status}")
    return status
