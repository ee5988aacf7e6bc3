"""What the HTTP server takes from a client before any route, token or Host check runs: slow
and oversized requests end early, so that no client can hold the server's connections, memory
or file descriptors (docs/services.md, "Security").

- **A request's head** (request line and headers) is at most `MAX_HEAD_BYTES` (h11's bound on
  an incomplete event: 400 beyond) and must arrive whole within `REQUEST_TIMEOUT` s of the
  connection opening or of the previous response; so must a body. A connection that has not
  sent its request by then is closed (`DeadlineH11Protocol`, on uvicorn's h11 protocol).
- **A refused request is answered, then the connection closed gracefully**: for up to
  `LINGER` s the server reads and discards what the client still sends (the rest of its head,
  or the body of a refused upload) until the client closes, as Apache and nginx do; closing at
  once with bytes unread makes the kernel reset the connection, and the client's then drops
  the answer before it is read.
- **A body** is at most `MAX_BODY_BYTES` (413, the connection closed unread) and declares
  its length: a chunked body (no length to check first) gets 411. Every request body of the
  API is a small JSON object.
- **One Host header** (RFC 9112, 3.2: two are answered 400).
- At most `MAX_CONNECTIONS` connections are served at once (uvicorn's `limit_concurrency`:
  503 beyond); the HTTP process may open as many files as its hard limit allows.

`http_config` makes the uvicorn Config with all of these; `RequestLimits` is the ASGI
middleware for the body and Host rules, outermost in the app (`webapp.create_app`).
"""

from __future__ import annotations

import json

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

MAX_HEAD_BYTES = 16 * 1024
"""bytes of a request line and its headers (a browser's are under 8 KiB with cookies)."""
MAX_BODY_BYTES = 64 * 1024
"""bytes of a request body (the API's JSON bodies are under 200 bytes)."""
REQUEST_TIMEOUT = 10.0
"""s a client has to send a whole request (head and body) once connected or answered."""
KEEP_ALIVE_TIMEOUT = 5
"""s an idle keep-alive connection stays open (uvicorn's default)."""
MAX_CONNECTIONS = 512
"""Connections and requests served at once; more get 503 (each dashboard holds one event
stream and polls on a second)."""
LINGER = 2.0
"""s a refused request's connection stays half closed, its input read and discarded, before
it is closed (the answer has long reached a client on the loopback or a LAN by then)."""
_STILL_SENDING = (h11.ERROR, h11.SEND_BODY)
"""h11's states of a client whose request was answered before it was all read."""


class _LingeringTransport:
    """A connection's transport whose `close`, while the client may still be sending
    (`_STILL_SENDING`), half closes it and lets `protocol` discard its input for `LINGER` s
    (`DeadlineH11Protocol._linger`); everything else is the transport's."""

    def __init__(self, transport, protocol):
        self._transport, self._protocol = transport, protocol

    def __getattr__(self, name):
        return getattr(self._transport, name)

    def close(self) -> None:
        if self._protocol.lingering or self._transport.is_closing():
            return
        if self._protocol.conn.their_state in _STILL_SENDING:
            self._protocol._linger()
        else:
            self._transport.close()

    def is_closing(self) -> bool:
        return self._protocol.lingering or self._transport.is_closing()

    def close_now(self) -> None:
        """Closes the connection without lingering."""
        self._transport.close()


class DeadlineH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with a deadline for each request: a client that has not sent a
    whole request (head and body) `request_timeout` s after connecting, or after its previous
    response, is disconnected. (uvicorn bounds only the idle time between requests: a client
    sending its headers a byte at a time was held for ever.) A request answered before it was
    all read is closed lingering (`_LingeringTransport`)."""

    request_timeout = REQUEST_TIMEOUT

    lingering = False
    """Whether the connection is half closed, its input discarded (`_LingeringTransport`)."""

    def connection_made(self, transport) -> None:
        super().connection_made(_LingeringTransport(transport, self))
        self._deadline = self._linger_end = None
        self._arm_deadline()

    def data_received(self, data: bytes) -> None:
        if not self.lingering:  # else the request was answered: what follows is dropped
            super().data_received(data)

    def _linger(self) -> None:
        # Ends when the client closes (asyncio closes a transport whose protocol's
        # `eof_received` returns nothing, as uvicorn's does) or at `LINGER`.
        self.lingering = True
        if self._deadline is not None:
            self._deadline.cancel()
        if self.transport.can_write_eof():
            self.transport.write_eof()  # the answer, then the end of what the server sends
        self.flow.resume_reading()  # paused for a large body: read it now, to drop it
        self._linger_end = self.loop.call_later(LINGER, self.transport.close_now)

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self.lingering:
            self._arm_deadline()  # the next request on this connection has its own

    def connection_lost(self, exc) -> None:
        for timer in (self._deadline, self._linger_end):
            if timer is not None:
                timer.cancel()
        super().connection_lost(exc)

    def _arm_deadline(self) -> None:
        if self._deadline is not None:
            self._deadline.cancel()
        self._deadline = self.loop.call_later(self.request_timeout, self._deadline_passed)

    def _deadline_passed(self) -> None:
        self._deadline = None
        if self.conn.their_state in (h11.IDLE, h11.SEND_BODY) and not (
                self.transport.is_closing()):
            # The request is not all here: the client is too slow (no lingering for it).
            self.transport.close_now()


def http_config(app, *, log_level: str = "warning",
                request_timeout: float = REQUEST_TIMEOUT, **kwargs):
    """A uvicorn Config serving `app` within the limits above (`request_timeout`: shorter in
    tests); `kwargs` go to the Config."""
    import uvicorn

    protocol = type("DeadlineH11Protocol", (DeadlineH11Protocol,),
                    {"request_timeout": request_timeout})
    return uvicorn.Config(app, http=protocol, h11_max_incomplete_event_size=MAX_HEAD_BYTES,
                          timeout_keep_alive=KEEP_ALIVE_TIMEOUT,
                          limit_concurrency=MAX_CONNECTIONS, log_level=log_level,
                          access_log=False, lifespan="off", **kwargs)


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
