"""The run's topics served live to Foxglove (`--foxglove [PORT]`): foxglove-sdk's WebSocket
server on a foxglove Context that the publishers (`publishers.py`) log on.

In Foxglove, open a connection to the printed URL (Foxglove WebSocket). Clients reach
foxglove-sdk's server, which listens on loopback only, through a gateway (a `websockets` server
in a thread of its own) that holds the connection to the live HTTP server's rules
(`serving.security.Access`): it listens on loopback unless told otherwise; any other address
needs a token (given, or one made here), sent as `?token=...` in the URL (a browser's WebSocket
cannot send a header) or as `Authorization: Bearer <token>`; the Host header must name the
served host. The gateway also accepts clients that offer only `foxglove.websocket.v1`, the
protocol's name before foxglove-sdk renamed it `foxglove.sdk.v1` (the same protocol, under
its new name): what older Foxglove apps, Lichtblick releases and roslibjs-foxglove offer.
Port 0 picks a free one. The simulation's time is broadcast with the messages, so Foxglove's
clock follows it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
from http import HTTPStatus
from urllib.parse import parse_qs, urlsplit

import foxglove

from corobot_drake.serving.security import Access, host_header_name, reachable_host

DEFAULT_PORT = 8765
"""Foxglove's own default."""

SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")
"""The names a client may offer, in the gateway's order of preference: foxglove-sdk's and the
older name of the same protocol. The gateway speaks the first to foxglove-sdk's server."""

CLIENT_MESSAGE_LIMIT = 1 << 20
"""bytes: the largest message a client may send (it sends subscriptions: small JSON)."""

START_TIMEOUT = 10.0
"""s the gateway has to start listening."""


class FoxgloveLive:
    """A running Foxglove WebSocket server on `context` (a new one unless given), reached on
    `host`:`port` through the gateway (module docstring); `token`: the one clients must send
    (None: none on loopback, a new random one elsewhere; `self.token`). `stop()` stops it
    (also on leaving a `with` block). A port that cannot be had raises RuntimeError."""

    def __init__(self, port: int = DEFAULT_PORT, host: str = "127.0.0.1",
                 context: foxglove.Context | None = None, name: str = "corobot_drake",
                 token: str | None = None):
        self.access = Access.for_host(host, token)
        self.context = context or foxglove.Context()
        self._server = foxglove.start_server(name=name, host="127.0.0.1", port=0,
                                             context=self.context)
        self.host = host
        try:
            self._gateway = _Gateway(self.access, port, f"ws://127.0.0.1:{self._server.port}")
        except BaseException:
            self._server.stop()
            raise

    @property
    def token(self) -> str | None:
        """The token clients must send, or None (none needed)."""
        return self.access.token

    @property
    def port(self) -> int:
        """The port clients connect to (the one picked, when asked for port 0)."""
        return self._gateway.port

    @property
    def url(self) -> str:
        """The URL to open, with the token when there is one (on every address, 0.0.0.0:
        its loopback address)."""
        return self.url_on(reachable_host(self.host))

    def url_on(self, name: str) -> str:
        """The URL to open on the host `name` (this machine's name, for other machines), with
        the token when there is one."""
        return f"ws://{name}:{self.port}" + (f"/?token={self.token}" if self.token else "")

    def stop(self) -> None:
        """Stops the server (idempotent): its clients are disconnected, its port freed."""
        if self._server is not None:
            self._gateway.stop()
            self._server.stop()
            self._server = None

    def __enter__(self) -> FoxgloveLive:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


class _Gateway:
    """The WebSocket server clients connect to: checks each handshake against `access`, then
    relays every message both ways between the client and foxglove-sdk's server at `inner`."""

    def __init__(self, access: Access, port: int, inner: str):
        self.access, self.inner = access, inner
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="foxglove-gateway",
                                        daemon=True)
        self._thread.start()
        try:
            self._server = asyncio.run_coroutine_threadsafe(self._serve(port), self._loop
                                                            ).result(START_TIMEOUT)
        except OSError as e:
            self._halt()
            raise RuntimeError(f"cannot listen on {access.host}:{port}: {e.strerror}") from None
        except BaseException:
            self._halt()
            raise
        self.port = self._server.sockets[0].getsockname()[1]

    async def _serve(self, port: int):
        from websockets.asyncio.server import serve

        return await serve(self._relay, self.access.host, port, subprotocols=list(SUBPROTOCOLS),
                           select_subprotocol=_select_subprotocol,
                           process_request=self._check, compression=None,
                           max_size=CLIENT_MESSAGE_LIMIT, server_header=None,
                           logger=_QUIET)

    def _check(self, connection, request):
        """The HTTP server's rules (`security.AccessGuard`) on the opening handshake."""
        host = request.headers.get_all("Host")
        if len(host) != 1:
            return connection.respond(HTTPStatus.BAD_REQUEST, "exactly one Host header\n")
        name = host_header_name(host[0])
        if not self.access.host_allowed(name):
            return connection.respond(HTTPStatus.MISDIRECTED_REQUEST,
                                      f"this server does not answer to host {name!r}\n")
        given = parse_qs(urlsplit(request.path).query).get("token", [None])[0]
        if not (self.access.token_ok(request.headers.get("Authorization"))
                or (given is not None and self.access.token_ok(f"Bearer {given}"))):
            return connection.respond(HTTPStatus.UNAUTHORIZED,
                                      "a token is required: open the URL the server printed "
                                      "(ws://...?token=...)\n")
        return None

    async def _relay(self, client) -> None:
        from websockets.asyncio.client import connect

        async with connect(self.inner, subprotocols=[SUBPROTOCOLS[0]], compression=None,
                           max_size=None, proxy=None, logger=_QUIET) as server:
            pipes = [asyncio.create_task(_pipe(client, server)),
                     asyncio.create_task(_pipe(server, client))]
            _, pending = await asyncio.wait(pipes, return_when=asyncio.FIRST_COMPLETED)
            for pipe in pending:
                pipe.cancel()

    def stop(self) -> None:
        async def close():
            self._server.close()
            await self._server.wait_closed()

        asyncio.run_coroutine_threadsafe(close(), self._loop).result(START_TIMEOUT)
        self._halt()

    def _halt(self) -> None:
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join()
        self._loop.close()


_QUIET = logging.getLogger("corobot_drake.foxglove_gateway")
"""The gateway's log: a refused or dropped client is the client's business (nothing printed
unless the application configures logging)."""
_QUIET.addHandler(logging.NullHandler())
_QUIET.propagate = False


def _select_subprotocol(connection, offered):
    """The first of `SUBPROTOCOLS` the client offers; none of them: 400, naming them."""
    from websockets.exceptions import NegotiationError

    for name in SUBPROTOCOLS:
        if name in offered:
            return name
    raise NegotiationError(f"offer one of the subprotocols {', '.join(SUBPROTOCOLS)}")


async def _pipe(source, sink) -> None:
    """Every message from `source` to `sink`, until either closes."""
    from websockets.exceptions import ConnectionClosed

    with contextlib.suppress(ConnectionClosed):
        async for message in source:
            await sink.send(message)
