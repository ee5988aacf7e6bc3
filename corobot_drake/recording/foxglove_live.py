"""The run's topics served live to Foxglove (`--foxglove [PORT]`): foxglove-sdk's WebSocket
server on a foxglove Context that the publishers (`publishers.py`) log on.

In Foxglove, open a connection to `ws://127.0.0.1:PORT` (Foxglove WebSocket). The server
listens on the loopback interface unless told otherwise, like `--serve`; port 0 picks a free
one. The simulation's time is broadcast with the messages, so Foxglove's clock follows it.
"""

import foxglove

DEFAULT_PORT = 8765
"""Foxglove's own default."""


class FoxgloveLive:
    """A running Foxglove WebSocket server on `context` (a new one unless given); `stop()`
    stops it (also on leaving a `with` block)."""

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1",
                 context: foxglove.Context | None = None, name: str = "corobot_drake"):
        self.context = context or foxglove.Context()
        self._server = foxglove.start_server(name=name, host=host, port=port,
                                             context=self.context)
        self.host = host

    @property
    def port(self) -> int:
        return self._server.port

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    def stop(self) -> None:
        """Stops the server (idempotent)."""
        if self._server is not None:
            self._server.stop()
            self._server = None

    def __enter__(self) -> "FoxgloveLive":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()
