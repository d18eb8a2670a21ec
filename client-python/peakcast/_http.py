"""HTTP for the client: one kept-alive connection per thread, retries that honour Retry-After."""
import http.client
import json
import select
import threading
import time
import urllib.parse

_CHUNK = 1 << 20
# Refusals worth waiting out: the server said when to come back (Retry-After).
_RETRYABLE = {(503, "queue_full"), (503, "uploads_busy"), (429, "rate_limited")}


class ServerError(Exception):
    """The server refused or failed a request: `status` (HTTP), `code` (proto/'s error codes), the
    server's message and, for 429 and 503, `retry_after` (seconds, or None)."""

    def __init__(self, status, code, message, retry_after=None):
        super().__init__(f"{status} {code}: {message}")
        self.status, self.code, self.message, self.retry_after = status, code, message, retry_after


class Transport:
    """Requests to one server. Thread-safe: each thread has its own connection, kept alive across
    calls. `retries` refusals of 503 queue_full / uploads_busy and 429 rate_limited are waited out
    (Retry-After, at most `max_retry_wait` seconds each); 0 turns that off."""

    def __init__(self, url, token, timeout, retries, max_retry_wait):
        u = urllib.parse.urlsplit(url)
        if u.scheme not in ("http", "https") or not u.hostname:
            raise ValueError(f"not an http(s) URL: {url!r}")
        if not isinstance(retries, int) or retries < 0:
            raise ValueError(f"retries must be a whole number >= 0 (0: no retries), not {retries!r}")
        self._https = u.scheme == "https"
        self._host, self._port = u.hostname, u.port or (443 if self._https else 80)
        self.base = u.path.rstrip("/")
        self.token, self.timeout, self.retries, self.max_retry_wait = token, timeout, retries, max_retry_wait
        self._local = threading.local()
        self._open, self._lock = set(), threading.Lock()

    def new_connection(self):
        cls = http.client.HTTPSConnection if self._https else http.client.HTTPConnection
        return cls(self._host, self._port, timeout=self.timeout)

    def headers(self, extra=None):
        h = dict(extra or {})
        if self.token:
            h["Authorization"] = "Bearer " + self.token
        return h

    def close(self):
        """Closes every thread's connection (a later call opens a new one)."""
        with self._lock:
            conns, self._open = self._open, set()
        for c in conns:
            c.close()

    def _kept(self):
        c = getattr(self._local, "conn", None)
        if c is None:
            c = self._local.conn = self.new_connection()
            with self._lock:
                self._open.add(c)
        return c

    def _drop(self):
        c = getattr(self._local, "conn", None)
        if c is not None:
            c.close()
            with self._lock:
                self._open.discard(c)
            self._local.conn = None

    def request(self, method, path, body=None, headers=None):
        """(status, headers: {lower-cased name: [values]}, body); ServerError for a refusal."""
        return self.retrying(lambda: self._once(method, path, body, headers))

    def retrying(self, attempt):
        for n in range(self.retries + 1):
            try:
                return attempt()
            except ServerError as e:
                if n == self.retries or (e.status, e.code) not in _RETRYABLE:
                    raise
                time.sleep(min(self.max_retry_wait, e.retry_after if e.retry_after is not None else 1.0))

    def _once(self, method, path, body, headers):
        for fresh in (False, True):  # a kept connection the server has since closed: once more on a new one
            conn = self._kept()
            reused = conn.sock is not None
            try:
                conn.request(method, self.base + path, body=body, headers=self.headers(headers))
                r = conn.getresponse()
                data = r.read()
            except (http.client.RemoteDisconnected, ConnectionResetError, BrokenPipeError):
                self._drop()
                if reused and not fresh:
                    continue
                raise
            except BaseException:
                self._drop()
                raise
            if r.will_close:
                self._drop()
            return checked(r.status, header_lists(r.getheaders()), data)

    def stream(self, method, path, body=None, headers=None):
        """A response read as it arrives, on a connection of its own: (headers, an iterator of its
        body's pieces). A refusal raises ServerError before any piece; a body the server cut short
        (an error after its header) raises ConnectionError when the iterator reaches the cut."""
        conn = self.new_connection()
        try:
            conn.request(method, self.base + path, body=body, headers=self.headers(headers))
            r = conn.getresponse()
            if r.status != 200:
                checked(r.status, header_lists(r.getheaders()), r.read())
        except BaseException:
            conn.close()
            raise
        return header_lists(r.getheaders()), _pieces(conn, r)

    def upload(self, target, body, length, rewind):
        """POST with Expect: 100-continue on a connection of its own: a refusal (size, budget, rate,
        token) arrives before the body is sent, as with curl. `rewind()` before each retry."""
        def attempt():
            rewind()
            return self._upload_once(target, body, length)
        return json.loads(self.retrying(attempt)[2])

    def _upload_once(self, target, body, length):
        conn = self.new_connection()
        try:
            conn.putrequest("POST", self.base + target)
            for k, v in self.headers({"Content-Type": "application/octet-stream", "Content-Length": str(length),
                                      "Expect": "100-continue"}).items():
                conn.putheader(k, v)
            conn.endheaders()
            if select.select([conn.sock], [], [], 5.0)[0]:  # else a server that ignores Expect: send anyway
                status, headers, answer = _read_interim(conn.sock)
                if status != 100:
                    return checked(status, headers, answer)
            if isinstance(body, memoryview):
                for i in range(0, length, _CHUNK):
                    conn.sock.sendall(body[i:i + _CHUNK])
            else:
                while chunk := body.read(_CHUNK):
                    conn.sock.sendall(chunk)
            r = conn.getresponse()
            return checked(r.status, header_lists(r.getheaders()), r.read())
        finally:
            conn.close()


def _pieces(conn, r):
    got = 0
    try:
        while True:
            try:
                piece = r.read1(_CHUNK)
            except http.client.IncompleteRead as e:
                raise ConnectionError(f"the server ended the response after {got + len(e.partial)} bytes, before its "
                                      "end (its log says why)") from None
            if not piece:
                return
            got += len(piece)
            yield piece
    finally:
        conn.close()


def header_lists(pairs):
    out = {}
    for k, v in pairs:
        out.setdefault(k.lower(), []).append(v)
    return out


def _read_interim(sock):
    """The server's answer to the headers alone: (100, {}, b"") to go on, or a whole refusal
    (status, headers, body), read off the socket directly (http.client would wait past a 100 for
    the final answer)."""
    data = b""
    while b"\r\n\r\n" not in data:
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("the server closed the connection before answering")
        data += chunk
    head, _, rest = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    if status == 100:
        return 100, {}, b""
    headers = header_lists(tuple(part.strip() for part in line.split(":", 1)) for line in lines[1:] if ":" in line)
    length = int(headers["content-length"][0]) if "content-length" in headers else None
    while length is not None and len(rest) < length:
        chunk = sock.recv(65536)
        if not chunk:
            break
        rest += chunk
    return status, headers, rest if length is None else rest[:length]


def checked(status, headers, body):
    if status >= 400:
        try:
            j = json.loads(body)
            code, message = j.get("error", "error"), j.get("message", "")
        except ValueError:
            code, message = "error", body[:500].decode("utf-8", "replace")
        retry = headers.get("retry-after")
        try:
            retry_after = float(retry[0]) if retry else None
        except ValueError:
            retry_after = None
        raise ServerError(status, code, message, retry_after)
    return status, headers, body
