"""``crowd`` given a scheduler that is not one, a crowd file nested too deeply, an ``--out`` that
is a file (docs/failures.md): each is one line naming what was wrong, exit 2, within a bounded
time, and nothing written.  The scheduler's peers are real sockets on the loopback: a closed
port, an HTTP server, a server that accepts and never answers, one that answers with garbage."""
import json
import socket
import threading
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from blender_turning.crowd.runner import SCHEDULER_TIMEOUT
from cli_helpers import one_line_error, run

CROWD = {"duration": 2, "figures": [{"name": "a", "preset": "skier",
                                     "turns": {"period": 2, "lean_deg": 20}}]}
# Every step of reaching a scheduler has SCHEDULER_TIMEOUT (docs/failures.md: at most about
# twice that in all); the rest is the interpreter starting (a few seconds on a busy machine).
# A command still running after it fails the test (run's timeout), it does not hang.
BOUND = 2 * SCHEDULER_TIMEOUT + 30


def crowd_file(tmp_path, doc=CROWD):
    p = tmp_path / "crowd.json"
    p.write_text(json.dumps(doc) if not isinstance(doc, str) else doc)
    return p


def closed_port() -> int:
    """A loopback port nobody listens on (bound, then released)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def server(answer):
    """A loopback TCP server; ``answer(conn)`` handles each connection on its own thread."""
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(16)
    conns, stop = [], threading.Event()

    def serve():
        s.settimeout(0.2)
        while not stop.is_set():
            try:
                conn, _ = s.accept()
            except OSError:
                continue
            conns.append(conn)
            threading.Thread(target=answer, args=(conn,), daemon=True).start()

    t = threading.Thread(target=serve, daemon=True)
    t.start()
    try:
        yield s.getsockname()[1]
    finally:
        stop.set()
        t.join()
        for c in conns:
            c.close()
        s.close()


def silent(conn):
    pass                                      # accepted, read nothing, never answers


def http_reply(conn):
    try:                                      # a proxy's reply, read as a Dask frame's length
        conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 8)
    except OSError:
        pass


def garbage(conn):
    try:
        conn.sendall(bytes(range(256)) * 64)
    except OSError:
        pass


@contextmanager
def http_server():
    class Handler(BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.end_headers()
            self.wfile.write(b"<html>a proxy</html>")

        def log_message(self, *a):
            pass

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    t = threading.Thread(target=httpd.serve_forever, daemon=True)
    t.start()
    try:
        yield httpd.server_address[1]
    finally:
        httpd.shutdown()
        httpd.server_close()


def crowd_on(tmp_path, address):
    out = tmp_path / "out"
    r = run("crowd", crowd_file(tmp_path), "--out", out, "--scheduler", address, timeout=BOUND)
    return r, out


@pytest.mark.parametrize("address, says", [("", "empty"),
                                           ("not a scheduler", "not a scheduler address"),
                                           ("tcp://127.0.0.1:99999", "port 1-65535")])
def test_an_empty_or_garbled_address_is_refused_before_anything(tmp_path, address, says):
    r, out = crowd_on(tmp_path, address)
    assert says in one_line_error(r, "--scheduler")
    assert not out.exists()


def _needs_dask():
    pytest.importorskip("distributed", reason="--scheduler past its address needs dask.distributed")


def test_a_closed_port_is_said_at_once(tmp_path):
    _needs_dask()
    port = closed_port()
    r, out = crowd_on(tmp_path, f"tcp://127.0.0.1:{port}")
    line = one_line_error(r, "--scheduler", f"127.0.0.1:{port}")
    assert "Connection refused" in line
    assert not out.exists()


@pytest.mark.parametrize("peer, says", [(silent, "no Dask scheduler answered"),
                                        (garbage, "answers, but not as a Dask scheduler"),
                                        (http_reply, "answers, but not as a Dask scheduler")])
def test_a_peer_that_is_not_a_scheduler_is_given_up_in_time(tmp_path, peer, says):
    _needs_dask()
    with server(peer) as port:
        r, out = crowd_on(tmp_path, f"tcp://127.0.0.1:{port}")
    line = one_line_error(r, "--scheduler", f"127.0.0.1:{port}")
    assert says in line
    assert not out.exists()


def test_an_http_server_is_not_a_scheduler(tmp_path):
    """A web server waits for a request line that Dask's frames never end, so it is silent."""
    _needs_dask()
    with http_server() as port:
        r, out = crowd_on(tmp_path, f"127.0.0.1:{port}")
    line = one_line_error(r, "--scheduler", f"tcp://127.0.0.1:{port}")
    assert "no Dask scheduler answered" in line or "not as a Dask scheduler" in line
    assert not out.exists()


def test_a_crowd_file_nested_too_deeply_is_one_line(tmp_path):
    r = run("crowd", crowd_file(tmp_path, "[" * 100_000), "--out", tmp_path / "out")
    one_line_error(r, "crowd.json", "nested too deeply")
    assert not (tmp_path / "out").exists()


def test_out_naming_an_existing_file_is_refused(tmp_path):
    out = tmp_path / "taken"
    out.write_text("keep")
    one_line_error(run("crowd", crowd_file(tmp_path), "--out", out), "--out", "is a file")
    assert out.read_text() == "keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["crowd.json", "taken"]
