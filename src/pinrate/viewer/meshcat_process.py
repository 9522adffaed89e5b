"""A Meshcat server process that binds its web port to one address and dies with its parent.

meshcat 0.3.2's server listens on every interface (tornado ``app.listen(port)`` without an
address) and outlives a parent that is killed. This entry point (run as
``python -m pinrate.viewer.meshcat_process --host 127.0.0.1 --parent PID``) binds the web port to
``--host`` only and exits as soon as the parent process is gone.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys

from meshcat.servers import zmqserver
from tornado.ioloop import PeriodicCallback

PARENT_CHECK_MS = 500


class _BoundBridge(zmqserver.ZMQWebSocketBridge):
    """The Meshcat bridge with its web port bound to ``self.host`` only."""

    def make_app(self):
        app = super().make_app()
        listen = app.listen
        host = self.host

        def listen_on_host(port: int, **kwargs: object) -> object:
            return listen(port, address=host, **kwargs)

        app.listen = listen_on_host
        return app


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--host", default="127.0.0.1", help="address the web and ZMQ ports bind to")
    parser.add_argument("--parent", type=int, default=None, help="exit when this process is gone")
    args = parser.parse_args(argv)

    bridge = _BoundBridge(host=args.host)
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)

    if args.parent is not None:

        def exit_if_orphaned() -> None:
            if os.getppid() != args.parent:
                os._exit(0)

        PeriodicCallback(exit_if_orphaned, PARENT_CHECK_MS).start()
    with contextlib.suppress(KeyboardInterrupt):
        bridge.run()
    sys.exit(0)


if __name__ == "__main__":
    main()
