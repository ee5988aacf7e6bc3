"""What the HTTP server takes from a client before any route, token or Host check runs: slow
and oversized requests end early, so that no client can hold the server's connections, memory
or file descriptors (docs/services.md, "Security").

Libraries hold most of it: uvicorn and h11 the size of a request head (h11's bound on an
incomplete event, `h11_max_incomplete_event_size`: 400 beyond), two Host headers (h11: 400) and
the idle time between requests (uvicorn's `timeout_keep_alive`); `RequestLimits`, an ASGI
middleware outermost in the app (`webapp.create_app`), a body's size. What none of them does
is `GuardedProtocol`'s, which wraps uvicorn's h11 protocol through uvicorn's `http=` option
(it reads nothing of uvicorn's but the asyncio Protocol interface, and follows each request
with an h11 connection of its own):

- **A request must arrive whole** (head and body) within `REQUEST_TIMEOUT` s of the connection
  opening or of its first byte, else the connection is closed. (uvicorn bounds only the idle
  time between requests: a client sending its headers a byte at a time was held for ever.)
- **A refused request is answered, then the connection closed gracefully**: for up to
  `LINGER` s the server reads and discards what the client still sends (the rest of its head,
  or the body of a refused upload) until the client closes, as Apache and nginx do; closing at
  once with bytes unread makes the kernel reset the connection, and the client's then drops
  the answer before it is read.
- **At most `connection_cap()` connections are open at once**: `MAX_CONNECTIONS`, fewer when
  the process may open fewer files (`ulimit -n`). A connection beyond takes the place of the
  one that has waited longest for its request to arrive (slow clients cannot lock others
  out); when every one is being served it gets 503 and is closed. (uvicorn's
  `limit_concurrency` answers 503 to requests beyond its limit but accepts their connections
  all the same, so slow clients still exhaust the descriptors.)

`http_config` makes the uvicorn Config with all of these.
"""

from __future__ import annotations

import asyncio
import json
import logging
import math
import time

import h11

MAX_HEAD_BYTES = 16 * 1024
"""bytes of a request line and its headers (a browser's are under 8 KiB with cookies)."""
MAX_BODY_BYTES = 64 * 1024
"""bytes of a request body (the API's JSON bodies are under 200 bytes)."""
REQUEST_TIMEOUT = 10.0
"""s a client has to send a whole request (head and body) once connected or once it starts."""
KEEP_ALIVE_TIMEOUT = 5
"""s an idle keep-alive connection stays open (uvicorn's default)."""
MAX_CONNECTIONS = 512
"""Connections open at once, at most (each dashboard holds one event stream and polls on a
second)."""
FILES_RESERVED = 64
"""Files the HTTP process keeps for itself, not for connections (it holds about 20 idle)."""
FILES_PER_CONNECTION = 2
"""Files a connection may hold: its socket and, while a static file is sent on it, that file."""
MIN_CONNECTIONS = 8
"""The fewest connections served, however low the file limit."""
LINGER = 2.0
"""s a refused request's connection stays half closed, its input read and discarded, before
it is closed (the answer has long reached a client on the loopback or a LAN by then)."""
_BUSY = (b"HTTP/1.1 503 Service Unavailable\r\ncontent-type: application/json\r\n"
         b"connection: close\r\ncontent-length: %d\r\n\r\n%s")
_BUSY_DETAIL = json.dumps({"detail": "the server is serving all the connections it can: try "
                           "again"}).encode()

log = logging.getLogger("uvicorn.error")


def connection_cap() -> int:
    """The connections the server holds at once: `MAX_CONNECTIONS`, or as many as this
    process's file limit leaves room for (`FILES_RESERVED`, `FILES_PER_CONNECTION`), at
    least `MIN_CONNECTIONS`."""
    import resource

    soft, _ = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft == resource.RLIM_INFINITY:
        return MAX_CONNECTIONS
    room = (soft - FILES_RESERVED) // FILES_PER_CONNECTION
    return max(MIN_CONNECTIONS, min(MAX_CONNECTIONS, room))


def file_limit() -> int:
    """The files this process may open (its soft limit; -1: no limit)."""
    import resource

    return resource.getrlimit(resource.RLIMIT_NOFILE)[0]


def raise_file_limit() -> None:
    """Lets this process open as many files as its hard limit allows (the soft limit is
    often 1024: as many connections as the server could hold)."""
    import contextlib
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft != hard:
        # (an infinite hard limit some kernels refuse as a soft one: then it stays)
        with contextlib.suppress(ValueError, OSError):
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))


class Connections:
    """A server's open connections (`GuardedProtocol`s) and their cap; those whose request
    has not all arrived (or that linger) by how long they have waited, longest first."""

    def __init__(self, cap: int):
        self.cap = cap
        self.open: set[GuardedProtocol] = set()
        self.waiting: dict[GuardedProtocol, None] = {}  # insertion-ordered
        self._warned = -math.inf

    def admit(self, connection: GuardedProtocol) -> bool:
        """Whether `connection` may be served: yes below the cap; at the cap, in the place
        of the connection that has waited longest for its request (closed here); no when
        every one is being served."""
        if len(self.open) >= self.cap:
            if not self.waiting:
                self._warn("every one is being served: new ones get 503")
                return False
            self._warn("the one waiting longest for its request is closed for each new one")
            oldest = next(iter(self.waiting))
            self.discard(oldest)
            oldest.transport.abort()
        self.open.add(connection)
        return True

    def _warn(self, what: str) -> None:
        """Says that the connections ran out, and `what` follows (at most once a minute)."""
        now = time.monotonic()
        if now - self._warned >= 60:
            self._warned = now
            log.warning("%d connections are open, the most this server holds: %s", self.cap,
                        what)

    def wait(self, connection: GuardedProtocol) -> None:
        """`connection` starts waiting for a request (the newest to wait)."""
        if connection in self.open:
            self.waiting.pop(connection, None)
            self.waiting[connection] = None

    def served(self, connection: GuardedProtocol) -> None:
        self.waiting.pop(connection, None)

    def discard(self, connection: GuardedProtocol) -> None:
        self.open.discard(connection)
        self.waiting.pop(connection, None)


class _LingeringTransport:
    """The transport uvicorn's protocol is given: its `close`, while the client may still be
    sending (`GuardedProtocol.unread`), half closes the connection and lets the guard discard
    its input for `LINGER` s; a protocol switch (a WebSocket upgrade) replaces the protocol
    the guard forwards to. Everything else is the transport's."""

    def __init__(self, transport, guard: GuardedProtocol):
        self._transport, self._guard = transport, guard

    def __getattr__(self, name):
        return getattr(self._transport, name)

    def close(self) -> None:
        if self._guard.lingering or self._transport.is_closing():
            return
        if self._guard.unread:
            self._guard.linger()
        else:
            self._transport.close()

    def is_closing(self) -> bool:
        return self._guard.lingering or self._transport.is_closing()

    def set_protocol(self, protocol) -> None:
        self._guard.inner = protocol


class GuardedProtocol(asyncio.Protocol):
    """uvicorn's HTTP protocol (`inner_class`, made with the arguments uvicorn gives) inside
    the guards of the module docstring: the connection cap (`connections`), the request
    deadline (`request_timeout` s) and the lingering close. It follows each request through
    an h11 connection of its own, fed the bytes uvicorn's is fed."""

    inner_class: type[asyncio.Protocol]
    connections: Connections
    request_timeout: float = REQUEST_TIMEOUT

    def __init__(self, **kwargs):
        self.inner = self.inner_class(**kwargs)
        self.transport = None
        self.admitted = self.lingering = False
        self.unread = False
        """Whether the client may be sending what the server will not read: a request whose
        head came but not all its body, or one h11 refused."""
        self._request: h11.Connection | None = None
        self._deadline = self._linger_end = None

    # asyncio's Protocol interface

    def connection_made(self, transport) -> None:
        self.transport = transport
        if not self.connections.admit(self):
            transport.write(_BUSY % (len(_BUSY_DETAIL), _BUSY_DETAIL))
            transport.close()
            return
        self.admitted = True
        self._request = self._new_request()
        self._wait()  # for the first request
        self.inner.connection_made(_LingeringTransport(transport, self))

    def data_received(self, data: bytes) -> None:
        if not self.admitted or self.lingering:  # the request was answered: the rest dropped
            return
        self._follow(data)
        self.inner.data_received(data)

    def eof_received(self):
        if self.admitted and not self.lingering:
            return self.inner.eof_received()
        return None

    def connection_lost(self, exc) -> None:
        for timer in (self._deadline, self._linger_end):
            if timer is not None:
                timer.cancel()
        if self.admitted:
            self.connections.discard(self)
            self.inner.connection_lost(exc)

    def pause_writing(self) -> None:
        if self.admitted:
            self.inner.pause_writing()

    def resume_writing(self) -> None:
        if self.admitted:
            self.inner.resume_writing()

    # the guards

    @staticmethod
    def _new_request() -> h11.Connection:
        return h11.Connection(h11.SERVER, max_incomplete_event_size=MAX_HEAD_BYTES)

    def _follow(self, data: bytes) -> None:
        """Follows the client's requests in `data`: the deadline runs from a request's first
        byte to its end."""
        request = self._request
        if request is None:  # h11 refused the request, or the protocol switched
            return
        if self._deadline is None and data:
            self._wait()
        request.receive_data(data)
        while True:
            try:
                event = request.next_event()
            except h11.RemoteProtocolError:  # uvicorn's h11 refuses it too: 400, then close
                self._request, self.unread = None, True
                return
            if event is h11.NEED_DATA or isinstance(event, h11.ConnectionClosed):
                return
            if isinstance(event, h11.Request):
                self.unread = True
            elif event is h11.PAUSED:  # an upgrade or CONNECT: its head is all there is
                self._request, self.unread = None, False
                self._served()
                return
            elif isinstance(event, h11.EndOfMessage):  # the request is all here
                self.unread = False
                self._served()
                if request.their_state is h11.MIGHT_SWITCH_PROTOCOL:  # an upgrade: no more
                    self._request = None  # HTTP follows if it is taken
                    return
                rest, _ = request.trailing_data
                request = self._request = self._new_request()
                if rest:  # the next request (pipelined) has begun
                    self._wait()
                    request.receive_data(rest)

    def _wait(self) -> None:
        """A request is awaited: it must arrive by the deadline."""
        if self._deadline is not None:
            self._deadline.cancel()
        loop = asyncio.get_running_loop()
        self._deadline = loop.call_later(self.request_timeout, self._deadline_passed)
        self.connections.wait(self)

    def _served(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        self.connections.served(self)

    def _deadline_passed(self) -> None:
        self._deadline = None
        if not (self.lingering or self.transport.is_closing()):
            # The request is not all here: the client is too slow (no lingering for it).
            self.transport.close()

    def linger(self) -> None:
        """Half closes the connection after the answer and discards the client's input until
        it closes (asyncio closes a transport whose protocol's `eof_received` returns
        nothing), or for `LINGER` s."""
        self.lingering = True
        if self._deadline is not None:
            self._deadline.cancel()
            self._deadline = None
        self.connections.wait(self)  # the first to go if the connections run out
        if self.transport.can_write_eof():
            self.transport.write_eof()  # the answer, then the end of what the server sends
        self.transport.resume_reading()  # paused for a large body: read it now, to drop it
        self._linger_end = asyncio.get_running_loop().call_later(LINGER, self.transport.close)


def http_config(app, *, log_level: str = "warning", request_timeout: float = REQUEST_TIMEOUT,
                max_connections: int | None = None, **kwargs):
    """A uvicorn Config serving `app` within the limits above (`request_timeout`: shorter in
    tests; `max_connections`: default `connection_cap()`); `kwargs` go to the Config."""
    import uvicorn
    from uvicorn.config import HTTP_PROTOCOLS
    from uvicorn.importer import import_from_string

    protocol = type("GuardedProtocol", (GuardedProtocol,), {
        "inner_class": import_from_string(HTTP_PROTOCOLS["h11"]),
        "connections": Connections(max_connections or connection_cap()),
        "request_timeout": request_timeout})
    return uvicorn.Config(app, http=protocol, h11_max_incomplete_event_size=MAX_HEAD_BYTES,
                          timeout_keep_alive=KEEP_ALIVE_TIMEOUT, log_level=log_level,
                          access_log=False, lifespan="off", **kwargs)


class RequestLimits:
    """ASGI middleware: 400 for two Host headers, 411 for a body without a length, 413 for a
    body over `max_body` bytes; each answered at once, the connection then closed (the body
    is never read). Answers are the API's `{"detail": "..."}`."""

    def __init__(self, app, max_body: int = MAX_BODY_BYTES):
        self.app = app
        self.max_body = max_body

    async def __call__(self, scope, receive, send):
        if scope["type"] == "http":
            refusal = self.refusal(scope["headers"])
            if refusal is not None:
                return await _answer(send, *refusal)
        return await self.app(scope, receive, send)

    def refusal(self, headers) -> tuple[int, str] | None:
        """(status, detail) of a request to refuse (raw ASGI `headers`); None lets it in."""
        hosts = [v for k, v in headers if k == b"host"]
        if len(hosts) > 1:
            return 400, "a request has one Host header (RFC 9112)"
        if any(k == b"transfer-encoding" for k, _ in headers):
            return 411, "send a body with its Content-Length"
        length = next((v for k, v in headers if k == b"content-length"), b"0")
        if not length.isdigit():  # h11 lets only digits through; another server may not
            return 400, "Content-Length must be a number of bytes"
        if int(length) > self.max_body:
            return 413, (f"the body is {int(length)} bytes; at most {self.max_body} are "
                         "taken")
        return None


async def _answer(send, status: int, detail: str) -> None:
    body = json.dumps({"detail": detail}).encode()
    await send({"type": "http.response.start", "status": status, "headers": [
        (b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
        (b"connection", b"close")]})
    await send({"type": "http.response.body", "body": body})
