"""Entry point of the meshcat server process that :class:`gdimitate.viz.MeshcatServer` manages.

Run as a plain script (``python _serve.py --zmq-url tcp://127.0.0.1:P --port W``), not as a
module of the package, so the child process imports only meshcat, not Pinocchio. Unlike
``python -m meshcat.servers.zmqserver`` it takes the web port as an argument, and its web
server listens on ``--host`` only (default 127.0.0.1; meshcat's own listens on every
interface). It prints ``zmq_url=...`` and ``web_url=...`` on two lines of stdout (which the
parent sends to a file and reads), or, when a port cannot be bound, a ``cannot bind`` line,
and exits with status 3. With ``--parent-pid`` it exits as soon as that process is gone (so
it is never left running when its owner is killed, even with SIGKILL), deleting the files
named by ``--owned-files`` (its temporary log and ready file) on the way out.
"""

from __future__ import annotations

import argparse
import os
import sys

#: How often the server checks that its parent is alive [ms].
PARENT_POLL_MS = 500


def _parent_alive(pid: int) -> bool:
    if os.getppid() != pid:  # reparented: the parent has exited
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--zmq-url", required=True)
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--host", default="127.0.0.1", help="web server address")
    parser.add_argument("--parent-pid", type=int, default=None)
    parser.add_argument("--owned-files", nargs="*", default=[],
                        help="temporary files of the parent to delete if it dies first")
    args = parser.parse_args()

    import tornado.ioloop
    import zmq
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    class Bridge(ZMQWebSocketBridge):
        """meshcat's bridge with its web server bound to ``host`` only."""

        def make_app(self):  # noqa: ANN202  (tornado Application)
            app = super().make_app()
            listen, host = app.listen, self.host

            def listen_on_host(port: int, **kwargs: object) -> object:
                return listen(port, address=host, **kwargs)

            app.listen = listen_on_host
            return app

    try:
        bridge = Bridge(zmq_url=args.zmq_url, host=args.host, port=args.port)
    except (OSError, zmq.error.ZMQError) as e:
        print(f"gdimitate-serve: cannot bind: {e}", flush=True)
        return 3
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    if args.parent_pid is not None:
        def watch() -> None:
            if not _parent_alive(args.parent_pid):
                for f in args.owned_files:
                    try:
                        os.unlink(f)
                    except OSError:
                        pass
                bridge.ioloop.stop()

        tornado.ioloop.PeriodicCallback(watch, PARENT_POLL_MS).start()
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
