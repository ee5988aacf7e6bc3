"""The HTTP server against slow and oversized clients (`serving.http_limits`): the real uvicorn
server as `--serve` configures it, on a loopback socket, serving the app of a real simulation
behind a token; raw sockets play the clients. The request deadline is 1 s here (10 s served),
so that waiting for it stays short; every wait is on an event (a closed socket, an answer)
with a bound."""

import contextlib
import re
import socket
import threading
import time

import httpx
import pytest

from conftest import make_sim
from corobot_drake.serving.http_limits import MAX_BODY_BYTES, MAX_HEAD_BYTES, http_config
from corobot_drake.serving.security import Access

TOKEN = "s3cret"
DEADLINE = 1.0
"""s: the request deadline the test server has."""
WAIT = 20.0
"""s: the most any socket waits for the server (far beyond the deadline)."""
ROBOT = "/robots/corobot"


@contextlib.contextmanager
def serving(**limits):
    """(host, port) of the served app, with the token TOKEN; `limits` go to `http_config`."""
    import uvicorn

    from corobot_drake.serving.runner import SimRunner
    from corobot_drake.serving.webapp import create_app

    runner = SimRunner(make_sim()).start()
    sock = socket.create_server(("127.0.0.1", 0), backlog=2048)
    app = create_app(runner, Access("127.0.0.1", TOKEN))
    uv = uvicorn.Server(http_config(app, request_timeout=DEADLINE, **limits))
    thread = threading.Thread(target=uv.run, kwargs={"sockets": [sock]}, daemon=True)
    thread.start()  # connections queue on the listening socket until it serves
    try:
        yield sock.getsockname()
    finally:
        uv.should_exit = True
        thread.join(WAIT)
        runner.stop()


@pytest.fixture(scope="module")
def server():
    with serving() as address:
        yield address


def _connect(address) -> socket.socket:
    client = socket.create_connection(address, timeout=WAIT)
    return client


def _answer(client: socket.socket) -> bytes:
    """Everything the server sends until it closes the connection."""
    data = b""
    while chunk := client.recv(65536):
        data += chunk
    return data


def _legitimate(address) -> httpx.Response:
    return httpx.get(f"http://{address[0]}:{address[1]}/simulation", timeout=WAIT,
                     headers={"Authorization": f"Bearer {TOKEN}"})


def test_slow_clients_are_cut_off_at_the_deadline_and_others_are_served(server):
    """300 connections that send half a request head, and one that sends its head a byte at
    a time, are all closed by the server once the deadline passes; meanwhile and after, a
    whole request is answered."""
    slow = [_connect(server) for _ in range(300)]
    for client in slow:
        client.sendall(b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\n")
    assert _legitimate(server).status_code == 200  # served while they hang
    drip = _connect(server)
    drip.settimeout(0.05)  # paces the drip: one byte per 50 ms unless the server closes
    head = b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: " + b"a" * 2000
    sent, closed = 0, False
    while sent < len(head) and not closed:
        try:
            drip.sendall(head[sent:sent + 1])
            sent += 1
            closed = drip.recv(1) == b""
        except TimeoutError:
            continue
        except OSError:  # reset: the server closed it
            closed = True
    assert closed and sent < len(head), f"sent {sent} of {len(head)} bytes unhindered"
    for client in slow:
        assert _answer(client) == b""  # closed by the server, nothing answered
        client.close()
    assert _legitimate(server).status_code == 200


def test_an_oversized_head_is_refused_before_the_token_check(server):
    """A head of over MAX_HEAD_BYTES gets 400 as soon as the limit is passed (not read to
    its end, and not 401: no token was sent)."""
    with _connect(server) as client:
        client.sendall(b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: "
                       + b"a" * (4 * MAX_HEAD_BYTES))
        assert _answer(client).startswith(b"HTTP/1.1 400 ")


@pytest.mark.parametrize("headers, status", [
    (f"Content-Length: {10 * 1024 * 1024}", b"413"),
    (f"Content-Length: {MAX_BODY_BYTES + 1}", b"413"),
    ("Transfer-Encoding: chunked", b"411"),
])
def test_an_oversized_or_unsized_body_is_refused_unread(server, headers, status):
    """Answered on the head alone (the body is never sent here), before the token check (no
    token is sent), and the connection closed."""
    with _connect(server) as client:
        client.sendall(f"POST {ROBOT}/drive/set_power HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                       f"Content-Type: application/json\r\n{headers}\r\n\r\n".encode())
        answer = _answer(client)
    assert answer.startswith(b"HTTP/1.1 " + status + b" "), answer[:200]
    assert b'"detail"' in answer


def test_two_host_headers_get_400(server):
    """h11 refuses them on the wire; `RequestLimits` too, for a server that would not."""
    from corobot_drake.serving.http_limits import RequestLimits

    with _connect(server) as client:
        client.sendall(b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\nHost: evil.example\r\n"
                       b"Authorization: Bearer " + TOKEN.encode() + b"\r\n\r\n")
        answer = _answer(client)
    assert answer.startswith(b"HTTP/1.1 400 ")
    limits = RequestLimits(app=None)
    assert limits.refusal([(b"host", b"127.0.0.1"), (b"host", b"evil.example")]) == (
        400, "a request has one Host header (RFC 9112)")
    assert limits.refusal([(b"host", b"127.0.0.1"), (b"content-length", b"12")]) is None


def test_a_request_within_the_limits_is_served(server):
    base = f"http://{server[0]}:{server[1]}"
    auth = {"Authorization": f"Bearer {TOKEN}"}
    r = httpx.post(f"{base}{ROBOT}/drive/set_power", json={"left": 0.0, "right": 0.0},
                   headers=auth, timeout=WAIT)
    assert r.status_code == 200, r.text
    r = httpx.get(f"{base}/services", headers=auth, timeout=WAIT)
    assert r.status_code == 200 and r.json()["services"][0]["state_url"] == f"{ROBOT}/drive"


@pytest.mark.parametrize("name", ["r?x", "a b", "r%20", "..", "ü"])
def test_robot_names_that_are_not_url_path_segments_are_refused_at_load(name):
    from corobot_drake.config.scenario import ScenarioError, load_scenario

    with pytest.raises(ScenarioError, match="a robot name must be letters, digits"):
        load_scenario(data=f'robots: {{"{name}": {{}}}}')
    assert list(load_scenario(data='robots: {"r_1.b-c~": {}}').robots) == ["r_1.b-c~"]


def test_a_refused_client_still_sending_reads_its_answer(server):
    """A client that goes on sending after its request was refused (the rest of an oversized
    head, or the body of a refused upload) still reads the answer: the server keeps reading
    and discarding what comes for a while instead of closing at once, when its kernel would
    reset the connection and the client's kernel drop the answer unread."""
    with _connect(server) as client:
        client.sendall(b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: "
                       + b"a" * (2 * MAX_HEAD_BYTES))
        client.settimeout(WAIT)
        first = client.recv(1, socket.MSG_PEEK)  # answered: the server has refused it
        assert first == b"H"
        client.sendall(b"a" * MAX_HEAD_BYTES)  # still sending after the answer
        threading.Event().wait(0.2)  # the server's kernel answers what it could not deliver
        assert _answer(client).startswith(b"HTTP/1.1 400 ")
    with _connect(server) as client:
        client.sendall(f"POST {ROBOT}/drive/set_power HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                       f"Content-Type: application/json\r\nContent-Length: "
                       f"{2 * MAX_BODY_BYTES}\r\n\r\n".encode())
        assert client.recv(1, socket.MSG_PEEK) == b"H"
        client.sendall(b"{" * (2 * MAX_BODY_BYTES))  # the body, after its refusal
        threading.Event().wait(0.2)
        assert _answer(client).startswith(b"HTTP/1.1 413 ")


def test_a_refused_client_is_let_go_after_the_linger(server, monkeypatch):
    """The lingering is bounded: a refused client that neither stops sending nor closes is
    disconnected `LINGER` s after its answer (shortened here)."""
    from corobot_drake.serving import http_limits

    monkeypatch.setattr(http_limits, "LINGER", 0.3)
    with _connect(server) as client:
        client.sendall(b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Big: "
                       + b"a" * (2 * MAX_HEAD_BYTES))
        assert _answer(client).startswith(b"HTTP/1.1 400 ")  # then the server's end
        threading.Event().wait(1.0)  # past the linger: the server has closed
        with pytest.raises(OSError):  # reset: nobody reads there any more
            for _ in range(100):
                client.sendall(b"a" * 65536)
                threading.Event().wait(0.01)


def test_slow_clients_beyond_the_file_limit_do_not_lock_others_out(tmp_path):
    """Under `ulimit -n 128` the HTTP process holds at most 32 connections, and says so as it
    starts. 150 slow clients, more than it could open files for, do not keep a whole request
    from being answered while they hang (well before their deadline): each new connection
    takes the place of the one that has waited longest for its request."""
    from corobot_drake.serving.http_limits import REQUEST_TIMEOUT
    from corobot_drake.serving.serve import ServerProcess

    stderr = tmp_path / "stderr.log"
    with ServerProcess(["--headless"], stderr_path=str(stderr), file_limit=128) as server:
        assert ("note: the HTTP server holds at most 32 connections at once: this process "
                "may open 128 files (ulimit -n)\n") in stderr.read_text()
        host, port = server.url.removeprefix("http://").rsplit(":", 1)
        address = (host, int(port))
        started = time.monotonic()
        slow = [_connect(address) for _ in range(150)]
        for client in slow:
            client.sendall(b"GET /simulation HTTP/1.1\r\nHost: 127.0.0.1\r\n")
        r = httpx.get(f"{server.url}/simulation", timeout=REQUEST_TIMEOUT)
        answered = time.monotonic() - started
        assert r.status_code == 200 and answered < REQUEST_TIMEOUT - 2, answered
        hanging = 0
        for client in slow:
            client.setblocking(False)
            try:
                hanging += client.recv(1) != b""  # b"": closed by the server
            except BlockingIOError:  # still open, waiting
                hanging += 1
            except OSError:  # reset by the server
                pass
            client.close()
        assert 0 < hanging <= 32, hanging


def test_at_the_connection_cap_a_waiting_client_gives_way_and_a_served_one_does_not():
    """With 4 connections at most: a fifth closes the one that has waited longest for its
    request; requests pipelined on one connection are each answered (the guard follows them
    one by one); with all 4 served (event streams), a new one gets 503."""
    auth = {"Authorization": f"Bearer {TOKEN}"}
    with serving(max_connections=4) as address:
        base = f"http://{address[0]}:{address[1]}"
        waiting = [_connect(address) for _ in range(4)]
        waiting[0].sendall(b"GET /simulation HTTP/1.1\r\n")
        assert _legitimate(address).status_code == 200
        with contextlib.suppress(ConnectionResetError):  # (reset if its bytes were unread)
            assert _answer(waiting[0]) == b""  # closed for it, unanswered
        for client in waiting:
            client.close()
        with _connect(address) as client:
            request = (f"GET /robots HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer "
                       f"{TOKEN}\r\n").encode()
            client.sendall(request + b"\r\n" + request + b"Connection: close\r\n\r\n")
            assert _answer(client).count(b"HTTP/1.1 200 ") == 2
        with contextlib.ExitStack() as streams:
            clients = [streams.enter_context(httpx.Client(base_url=base, headers=auth,
                                                          timeout=WAIT)) for _ in range(4)]
            for client in clients:
                streams.enter_context(client.stream("GET", f"{ROBOT}/gps/subscribe?limit=5"))
            busy = _answer(_connect(address))
            assert busy.startswith(b"HTTP/1.1 503 ") and b'"detail"' in busy, busy


def test_what_the_guard_reads_of_uvicorn_is_still_there():
    """`http_config` takes uvicorn's h11 protocol by its name in `uvicorn.config.HTTP_PROTOCOLS`
    (no documented name) and makes it with the arguments uvicorn's server gives the protocol
    class: an upgrade that changes either fails here by name, not as a server that does not
    start. (No upper bound on uvicorn in pyproject: this checks what is used, any version.)"""
    import asyncio
    import inspect

    import uvicorn
    import uvicorn.server
    from uvicorn.config import HTTP_PROTOCOLS
    from uvicorn.importer import import_from_string

    assert "h11" in HTTP_PROTOCOLS, f"uvicorn {uvicorn.__version__}: no 'h11' in HTTP_PROTOCOLS"
    inner = import_from_string(HTTP_PROTOCOLS["h11"])
    assert issubclass(inner, asyncio.Protocol), f"uvicorn {uvicorn.__version__}: {inner}"
    for method in ("connection_made", "data_received", "eof_received", "connection_lost",
                   "pause_writing", "resume_writing"):  # what GuardedProtocol forwards
        assert callable(getattr(inner, method, None)), f"{inner.__name__}.{method} is gone"
    # The keywords uvicorn's server makes the protocol class with, as its source says them.
    source = inspect.getsource(uvicorn.server.Server)
    call = source[source.index("config.http_protocol_class("):]
    given = set(re.findall(r"(\w+)=", call[:call.index(")")]))
    assert given == {"config", "server_state", "app_state", "_loop"}, \
        f"uvicorn {uvicorn.__version__} makes its protocol with {sorted(given)}"
    accepted = inspect.signature(inner.__init__).parameters
    assert given <= set(accepted), \
        f"uvicorn {uvicorn.__version__}: {inner.__name__}({', '.join(accepted)})"
    config = http_config(lambda scope, receive, send: None)
    assert config.http.inner_class is inner and issubclass(config.http, asyncio.Protocol)
