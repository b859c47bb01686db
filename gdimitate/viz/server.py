"""A meshcat server process that we own, and a connection to it that cannot hang.

``meshcat.Visualizer()`` spawns its server with stdout/stderr piped and never read: once a
browser disconnects mid-transfer the server's tracebacks fill the pipe and every later call
blocks forever. Here the server's output goes to a log file (or ``/dev/null``), the ports are
chosen by us (a free one, or the one asked for, with a clear error if it is taken), every
request on the zmq socket has a timeout, and :meth:`MeshcatServer.close` (also run at
interpreter exit) terminates the process and deletes its temporary log.

Both sockets listen on 127.0.0.1 only (meshcat's own server puts its web page on every
interface); ``host=`` opens the web page to other machines on purpose. The server process
watches its parent and exits when the parent is gone, so it never outlives us, even after a
SIGKILL; a start interrupted by Ctrl-C or SIGTERM stops the half-started process.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import weakref
from collections.abc import Iterator
from pathlib import Path

import meshcat
import umsgpack
import zmq
from meshcat.visualizer import ViewerWindow

from ..errors import ViewerError

__all__ = ["MeshcatServer", "PortInUseError", "check_port", "connect", "free_port",
           "port_in_use"]

_SERVE_SCRIPT = Path(__file__).with_name("_serve.py")
_LOCALHOST = "127.0.0.1"


class PortInUseError(ViewerError):
    """A port asked for is already taken by another process."""

    def __init__(self, port: int, what: str = "web"):
        self.port = port
        super().__init__(
            f"{what} port {port} is already in use; pass another port, or port=None to let "
            "gdimitate choose a free one"
        )


def check_port(port: object, what: str = "web") -> int:
    """``port`` as an int if it is a TCP port number 1–65535, else :class:`ViewerError`."""
    if isinstance(port, bool) or not isinstance(port, int | str) and not hasattr(port,
                                                                                 "__index__"):
        raise ViewerError(f"{what} port must be an integer 1-65535; got {port!r}")
    try:
        p = int(port)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ViewerError(f"{what} port must be an integer 1-65535; got {port!r}") from None
    if not 1 <= p <= 65535:
        raise ViewerError(f"{what} port must be in 1-65535; got {p}")
    return p


def port_in_use(port: int, host: str = _LOCALHOST) -> bool:
    """Whether TCP ``port`` cannot be bound on ``host`` (and on 127.0.0.1)."""
    port = check_port(port)
    for h in dict.fromkeys((host, _LOCALHOST)):
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
            s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            try:
                s.bind((h, port))
            except OSError:
                return True
    return False


def free_port() -> int:
    """A TCP port that is free right now (the OS picks it; another process may still take it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((_LOCALHOST, 0))
        return int(s.getsockname()[1])


class _Window(ViewerWindow):
    """meshcat's ``ViewerWindow`` talking to an existing server, with a timeout on every reply.

    A request that gets no reply within ``timeout_s`` raises :class:`ViewerError` (and the
    socket is replaced, since a zmq REQ socket is unusable after an unanswered request).
    """

    def __init__(self, zmq_url: str, web_url: str | None = None, timeout_s: float = 30.0):
        self.server_proc = None
        self.zmq_url = zmq_url
        self.timeout_s = float(timeout_s)
        self.connect_zmq()
        self.web_url = web_url if web_url is not None else self.request_web_url()

    def connect_zmq(self) -> None:
        sock = self.context.socket(zmq.REQ)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.RCVTIMEO, int(self.timeout_s * 1000))
        sock.setsockopt(zmq.SNDTIMEO, int(self.timeout_s * 1000))
        sock.connect(self.zmq_url)
        self.zmq_socket = sock

    def _recv(self, what: str) -> bytes:
        try:
            return self.zmq_socket.recv()
        except zmq.Again:
            self.zmq_socket.close(linger=0)
            self.connect_zmq()
            raise ViewerError(
                f"the meshcat server at {self.zmq_url} did not answer {what!r} within "
                f"{self.timeout_s:g} s (is it still running?)"
            ) from None

    def _send(self, frames: list[bytes], what: str) -> bytes:
        try:
            self.zmq_socket.send_multipart(frames)
        except zmq.Again:
            raise ViewerError(f"could not send {what!r} to the meshcat server at "
                              f"{self.zmq_url}") from None
        return self._recv(what)

    def request_web_url(self) -> str:
        return self._send([b"url"], "url").decode("utf-8")

    def send(self, command) -> None:  # noqa: ANN001  (meshcat command object)
        data = command.lower()
        reply = self._send(
            [data["type"].encode("utf-8"), data["path"].encode("utf-8"), umsgpack.packb(data)],
            data["type"],
        )
        if reply.startswith(b"error"):
            raise ViewerError(f"meshcat server refused {data['type']!r}: {reply.decode()}")

    def get_scene(self) -> str:
        return self._send([b"get_scene"], "get_scene").decode("utf-8")

    def wait(self) -> str:  # blocks until a browser connects: only with a timeout
        return self._send([b"wait"], "wait").decode("utf-8")

    def close(self) -> None:
        self.zmq_socket.close(linger=0)


def connect(zmq_url: str, web_url: str | None = None, timeout_s: float = 30.0
            ) -> meshcat.Visualizer:
    """A ``meshcat.Visualizer`` on a running server at ``zmq_url`` (e.g. ``tcp://127.0.0.1:6000``).

    Every request times out after ``timeout_s`` seconds with :class:`ViewerError` instead of
    blocking. Prints nothing (unlike ``meshcat.Visualizer(zmq_url)``).
    """
    return meshcat.Visualizer(window=_Window(zmq_url, web_url, timeout_s))


def _stop(proc: subprocess.Popen, log: Path | None = None) -> None:
    """Stop the server process (terminate, then kill after 5 s) and delete ``log``, the
    automatic log it owns (also when the server is garbage-collected or the interpreter
    exits without :meth:`MeshcatServer.close`)."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=5)
    if log is not None:
        log.unlink(missing_ok=True)



@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Ctrl-C and SIGTERM that arrive within the block act after it, through the handlers
    that were there: while ``subprocess.Popen`` creates the server (it runs once forked, and
    an interrupt then would leave no handle to stop it with). Outside the main thread nothing
    changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    got: list[int] = []
    old = {}
    for sig in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(sig) not in (signal.SIG_IGN, None):
            old[sig] = signal.signal(sig, lambda signum, frame: got.append(signum))
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        for signum in got:
            signal.raise_signal(signum)

class MeshcatServer:
    """A meshcat server (web page + zmq command socket) running as our own child process.

    Create one with :meth:`start`; stop it with :meth:`close` (or use it as a context
    manager; it is also stopped when garbage-collected or at interpreter exit).

    Attributes:
        web_url: the page to open in a browser, e.g. ``http://127.0.0.1:7001/static/``.
        zmq_url: where drawing commands go, e.g. ``tcp://127.0.0.1:6001``.
        port: the web port.
        log_path: the file that receives the server's output (``None`` for ``/dev/null``).
    """

    def __init__(self, proc: subprocess.Popen, web_url: str, zmq_url: str, port: int,
                 log_path: Path | None, owns_log: bool, host: str = _LOCALHOST):
        self.proc = proc
        self.host = host
        self.web_url = web_url
        self.zmq_url = zmq_url
        self.port = port
        self.log_path = log_path
        self._finalizer = weakref.finalize(self, _stop, proc, log_path if owns_log else None)
        self._owns_log = owns_log

    @classmethod
    def start(cls, port: int | None = None, *, zmq_port: int | None = None,
              host: str = _LOCALHOST, log: str | os.PathLike | None = "auto",
              timeout_s: float = 20.0) -> MeshcatServer:
        """Start a server and wait (at most ``timeout_s`` s) until it listens.

        Args:
            port: web port 1–65535; ``None`` picks a free one. If the port is taken,
                :class:`PortInUseError` is raised at once.
            zmq_port: port of the zmq command socket (always on 127.0.0.1); ``None`` picks a
                free one.
            host: address the web page listens on: ``"127.0.0.1"`` (default, this machine
                only); ``"0.0.0.0"`` or an interface's address serves other machines too.
            log: file for the server's output; ``"auto"`` (a temporary file, deleted by
                :meth:`close`) or ``None`` (``/dev/null``).
            timeout_s: how long to wait for the process to come up.
        """
        if port is not None:
            port = check_port(port, "web")
        if zmq_port is not None:
            zmq_port = check_port(zmq_port, "zmq")
        for p, what, h in ((port, "web", host), (zmq_port, "zmq", _LOCALHOST)):
            if p is not None and port_in_use(p, h):
                raise PortInUseError(p, what)
        attempts = 1 if (port is not None and zmq_port is not None) else 3
        last = ""
        for _ in range(attempts):
            web_p = port if port is not None else free_port()
            zmq_p = zmq_port if zmq_port is not None else free_port()
            server = cls._spawn(web_p, zmq_p, log, timeout_s, host)
            if isinstance(server, MeshcatServer):
                return server
            last = server
            if "cannot bind" in last and port is not None and port_in_use(port, host):
                raise PortInUseError(port)
        raise ViewerError(f"the meshcat server did not start: {last}")

    @classmethod
    def _spawn(cls, web_p: int, zmq_p: int, log: str | os.PathLike | None, timeout_s: float,
               host: str = _LOCALHOST) -> MeshcatServer | str:
        owns_log = log == "auto"
        log_path: Path | None = None if owns_log or log is None else Path(log)
        out = ready_path = proc = None
        ok = False
        try:
            if owns_log:
                fd, name = tempfile.mkstemp(prefix="gdimitate-meshcat-", suffix=".log")
                os.close(fd)
                log_path = Path(name)
            # The ready lines are read from a file, so output never fills a pipe.
            out = open(log_path, "wb") if log_path is not None else None  # noqa: SIM115
            fd, name = tempfile.mkstemp(prefix="gdimitate-meshcat-ready-")
            os.close(fd)
            ready_path = Path(name)
            with open(ready_path, "wb") as ready_out, _signals_held():
                proc = subprocess.Popen(
                    [sys.executable, "-u", str(_SERVE_SCRIPT),
                     "--zmq-url", f"tcp://{_LOCALHOST}:{zmq_p}", "--port", str(web_p),
                     "--host", str(host), "--parent-pid", str(os.getpid()),
                     "--owned-files", str(ready_path),
                     *([str(log_path)] if owns_log and log_path is not None else [])],
                    stdout=ready_out, stderr=out if out is not None else subprocess.DEVNULL,
                    stdin=subprocess.DEVNULL, start_new_session=True,
                )
            web_url = zmq_url = None
            deadline = time.monotonic() + timeout_s
            while time.monotonic() < deadline:
                text = ready_path.read_text(errors="replace")
                for line in text.splitlines():
                    if line.startswith("zmq_url="):
                        zmq_url = line.split("=", 1)[1].strip()
                    elif line.startswith("web_url="):
                        web_url = line.split("=", 1)[1].strip()
                if web_url and zmq_url:
                    break
                if proc.poll() is not None:
                    err = log_path.read_text(errors="replace")[-2000:] if log_path else ""
                    text = ready_path.read_text(errors="replace")
                    return (f"process exited with status {proc.returncode}: "
                            f"{text.strip()} {err.strip()}").strip()
                time.sleep(0.05)
            else:
                return f"no answer within {timeout_s:g} s"
            # Later output of the process (tornado's tracebacks) goes to the log only.
            server = cls(proc, web_url, zmq_url, web_p, log_path, owns_log, host)
            ok = True
            return server
        finally:  # a failed start, or Ctrl-C/SIGTERM while waiting: leave nothing behind
            if out is not None:
                out.close()
            if ready_path is not None:
                ready_path.unlink(missing_ok=True)
            if not ok:
                if proc is not None:
                    _stop(proc)
                if owns_log and log_path is not None:
                    log_path.unlink(missing_ok=True)

    @property
    def alive(self) -> bool:
        """Whether the server process is still running."""
        return self.proc.poll() is None

    def check_alive(self) -> None:
        """Raise :class:`ViewerError` (with the end of its log) if the server has exited."""
        if self.alive:
            return
        tail = ""
        if self.log_path is not None and self.log_path.is_file():
            tail = self.log_path.read_text(errors="replace").strip()[-1500:]
        raise ViewerError(f"the meshcat server (pid {self.proc.pid}) exited with status "
                          f"{self.proc.returncode}" + (f"; its log ends:\n{tail}" if tail else ""))

    def visualizer(self, timeout_s: float = 30.0) -> meshcat.Visualizer:
        """A new ``meshcat.Visualizer`` connected to this server (see :func:`connect`)."""
        if not self.alive:
            raise ViewerError(f"the meshcat server (pid {self.proc.pid}) is not running")
        return connect(self.zmq_url, self.web_url, timeout_s)

    def close(self) -> None:
        """Stop the process (terminate, then kill after 5 s) and delete an automatic log."""
        self._finalizer()

    def __enter__(self) -> MeshcatServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "running" if self.alive else "stopped"
        return f"MeshcatServer({self.web_url!r}, zmq={self.zmq_url!r}, {state})"
