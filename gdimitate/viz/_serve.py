"""Entry point of the meshcat server process that :class:`gdimitate.viz.MeshcatServer` manages.

Run as a plain script (``python _serve.py --zmq-url tcp://127.0.0.1:P --port W``), not as a
module of the package, so the child process imports only meshcat, not Pinocchio. Unlike
``python -m meshcat.servers.zmqserver`` it takes the web port as an argument. It prints
``zmq_url=...`` and ``web_url=...`` on two lines of stdout (which the parent sends to a file
and reads), or, when a port cannot be bound, a ``cannot bind`` line, and exits with status 3.
"""

from __future__ import annotations

import argparse
import sys


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--zmq-url", required=True)
    parser.add_argument("--port", type=int, required=True)
    args = parser.parse_args()

    import zmq
    from meshcat.servers.zmqserver import ZMQWebSocketBridge

    try:
        bridge = ZMQWebSocketBridge(zmq_url=args.zmq_url, port=args.port)
    except (OSError, zmq.error.ZMQError) as e:
        print(f"gdimitate-serve: cannot bind: {e}", flush=True)
        return 3
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    try:
        bridge.run()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
