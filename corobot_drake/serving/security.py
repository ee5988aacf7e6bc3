"""Who may drive the robot: the live server's access rules (docs/services.md, "Security").

- **Loopback by default.** `--host` picks another address; any address but loopback needs a
  token (`--token`, or one made here and printed with the URL).
- **A token**, when there is one, is sent as `Authorization: Bearer <token>` on every request
  but the pages' shells (`PUBLIC_PATHS`: the dashboard, the webcam page, the API docs and
  static files, none of which holds state). The pages read it from their URL's fragment
  (`/dashboard#token=...`, which browsers never send to a server) and send it themselves.
- **The Host header** must name the served host (DNS rebinding: a page on an attacker's domain
  re-pointed at this address sends the attacker's domain as Host).
- **State-changing requests carry JSON** (`Content-Type: application/json`): what a cross-site
  form or a bare POST cannot send, and what a cross-site script may only send after a CORS
  preflight, which this server does not answer.

`AccessGuard` is the ASGI middleware that enforces them, before any route runs.
"""

from __future__ import annotations

import dataclasses as dc
import hmac
import ipaddress
import json
import re
import secrets
import socket

LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
"""Host names a loopback server answers to (besides any 127.x.y.z address)."""
PUBLIC_PATHS = ("/", "/dashboard", "/docs", "/docs/oauth2-redirect", "/redoc", "/openapi.json",
                "/favicon.ico")
"""Paths served without the token: page shells and documents that hold no state."""
PUBLIC_PREFIXES = ("/static/", "/static-offline-docs/")
PUBLIC_PATTERNS = (re.compile(r"/robots/[^/]+/(camera|cameras/[^/]+)/page"),)
STATE_CHANGING = ("POST", "PUT", "PATCH", "DELETE")
TOKEN_BYTES = 24
"""Entropy of a generated token (192 bits, URL-safe base64)."""


def is_loopback(host: str) -> bool:
    """Whether `host` (a name or an address, IPv6 with or without brackets) is this machine's
    loopback."""
    host = host.strip("[]").lower()
    if host in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dc.dataclass(frozen=True)
class Access:
    """The rules for one served address: `host` as given to --host, the `token` (None: none
    needed, loopback only)."""

    host: str = "127.0.0.1"
    token: str | None = None

    @classmethod
    def for_host(cls, host: str, token: str | None = None) -> Access:
        """The rules for serving on `host`: `token` if given; else none on loopback, a new
        random one on any other address."""
        if token is not None and not token.strip():
            raise ValueError("--token must not be empty")
        if token is None and not is_loopback(host):
            token = secrets.token_urlsafe(TOKEN_BYTES)
        return cls(host, token)

    @property
    def wildcard(self) -> bool:
        """Serving on every address (0.0.0.0 or ::)."""
        return self.host.strip("[]") in ("0.0.0.0", "::", "")

    def host_allowed(self, name: str) -> bool:
        """Whether a request's Host header (its name, without the port) names this server:
        the served address itself; for loopback, its names; for every address (0.0.0.0),
        any IP address literal (an address cannot be re-pointed by DNS) or this machine's
        own names."""
        name = name.strip("[]").lower()
        if not name:
            return False
        if name == self.host.strip("[]").lower():
            return True
        if (is_loopback(self.host) or self.wildcard) and is_loopback(name):
            return True
        if self.wildcard:
            if _is_address(name):
                return True
            return name in _machine_names()
        return False

    def token_ok(self, authorization: str | None) -> bool:
        if self.token is None:
            return True
        scheme, _, value = (authorization or "").partition(" ")
        return scheme.lower() == "bearer" and hmac.compare_digest(value.strip().encode(),
                                                                  self.token.encode())

    def page_url(self, base: str, path: str = "/dashboard") -> str:
        """A page's URL carrying the token in its fragment (as the pages read it)."""
        return f"{base}{path}" + (f"#token={self.token}" if self.token else "")


def reachable_host(host: str) -> str:
    """`host` as a URL names it for a client on this machine: a wildcard (0.0.0.0, ::), which
    no client can connect to, becomes the loopback address of its family; an IPv6 address is
    bracketed."""
    host = host.strip("[]")
    if host in ("0.0.0.0", ""):
        host = "127.0.0.1"
    elif host == "::":
        host = "::1"
    return f"[{host}]" if ":" in host else host



def other_machines_line(access: Access, url_on) -> str | None:
    """For a server on every address (0.0.0.0, ::): the line naming its URL on this machine's
    name (`url_on(name)`, the token in it), which other machines may reach it by, as any of
    its addresses; None on one address (its printed URL is the one to use)."""
    if not access.wildcard:
        return None
    return (f"  from other machines {url_on(socket.gethostname())}  (or any of this machine's "
            "addresses)")

def _is_address(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


def _machine_names() -> set[str]:
    names = {socket.gethostname().lower(), socket.getfqdn().lower()}
    return {n for n in names if n}


def public(path: str) -> bool:
    return (path in PUBLIC_PATHS or path.startswith(PUBLIC_PREFIXES)
            or any(p.fullmatch(path) for p in PUBLIC_PATTERNS))


def host_header_name(host_header: str) -> str:
    """The name in a Host header, without its port ("[::1]:8000" -> "::1")."""
    if host_header.startswith("["):
        return host_header[1:].partition("]")[0]
    return host_header.rpartition(":")[0] if host_header.count(":") == 1 else host_header


class AccessGuard:
    """ASGI middleware enforcing `access` (the module docstring) on every HTTP request: 421 a
    Host that is not this server, 401 a missing or wrong token, 415 a state-changing request
    without a JSON body. Answers are the API's `{"detail": "..."}`."""

    def __init__(self, app, access: Access):
        self.app = app
        self.access = access

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", ())}
        refusal = self.refusal(scope["method"], scope["path"], headers)
        if refusal is None:
            return await self.app(scope, receive, send)
        status, detail, extra = refusal
        body = json.dumps({"detail": detail}).encode()
        await send({"type": "http.response.start", "status": status, "headers": [
            (b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
            *extra]})
        await send({"type": "http.response.body", "body": body})

    def refusal(self, method: str, path: str, headers: dict[str, str]):
        """(status, detail, extra headers) for a request to refuse; None to let it through."""
        host = host_header_name(headers.get("host", ""))
        if not self.access.host_allowed(host):
            return 421, (f"this server does not answer to host {host!r} (DNS rebinding "
                         "protection; use the address it printed)"), []
        if not public(path) and not self.access.token_ok(headers.get("authorization")):
            return 401, ("a token is required: send the header 'Authorization: Bearer "
                         "<token>' (printed when the server started)"), [
                (b"www-authenticate", b"Bearer")]
        if method in STATE_CHANGING:
            content_type = headers.get("content-type", "").split(";")[0].strip().lower()
            if content_type != "application/json":
                return 415, (f"{method} needs a JSON body (Content-Type: application/json); "
                             f"got {content_type or 'no Content-Type'}"), []
        return None
