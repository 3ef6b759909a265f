"""A small rosbridge-v2-protocol server for tests: JSON over websocket on 127.0.0.1 (stdlib only).

It records every operation a client sends (advertise, publish, subscribe, ...), answers a service
call as rosbridge answers one for a service nobody offers (``result: false``), and can publish
messages to the clients subscribed to a topic. ``PlainWebsocketServer``: a websocket server that
speaks no rosbridge (it records and never answers). Bounded in time: each wait takes a timeout.
"""

from __future__ import annotations

import base64
import hashlib
import json
import socket
import struct
import threading
import time
from typing import Any

from tests.helpers import wait_until

_GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"


class RosbridgeServer:
    """``rosapi``: answers ``/rosapi/publishers`` (a topic advertised by a client has rosbridge's
    node as publisher, one in :attr:`robot_topics` the robot's); ``amcl``: an AMCL stand-in that
    answers each ``/initialpose`` after ``amcl_delay`` s with the same pose on ``/amcl_pose`` (the
    first ``amcl_ignores`` are ignored); ``set_initial_pose``: offers AMCL's ``/set_initial_pose``
    service; ``hooks``: the test's callbacks for a client's operations (``("publish", "/cmd_vel")``)."""

    def __init__(
        self,
        rosapi: bool = False,
        amcl: bool = False,
        amcl_delay: float = 0.1,
        amcl_ignores: int = 0,
        set_initial_pose: bool = False,
    ) -> None:
        self.rosapi, self.amcl, self.amcl_delay = rosapi, amcl, amcl_delay
        self.amcl_ignores, self.set_initial_pose = amcl_ignores, set_initial_pose
        self.hooks: dict[tuple[str, str], Any] = {}  # (op, topic) -> called with each such op
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(4)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.ops: list[dict[str, Any]] = []
        self.robot_topics: set[str] = set()  # topics the robot publishes (rosapi lists them)
        self.subscriptions: dict[str, list[socket.socket]] = {}
        self.clients: list[socket.socket] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, daemon=True)

    def __enter__(self) -> RosbridgeServer:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(timeout=2)
        for c in list(self.clients):
            try:
                c.close()
            except OSError:
                pass
        self.sock.close()

    # -- websocket ------------------------------------------------------------------------------------

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self.sock.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            threading.Thread(target=self._client, args=(conn,), daemon=True).start()

    def _client(self, conn: socket.socket) -> None:
        conn.settimeout(0.2)
        try:
            _handshake(conn)
            with self._lock:
                self.clients.append(conn)
            self._receive(conn)
        except (OSError, StopIteration):
            pass
        finally:
            with self._lock:
                if conn in self.clients:
                    self.clients.remove(conn)
                for subs in self.subscriptions.values():
                    if conn in subs:
                        subs.remove(conn)
            conn.close()

    def _receive(self, conn: socket.socket) -> None:
        """Frames until the client closes: pings answered, text and binary frames handled."""
        buffer = b""
        while not self._stop.is_set():
            try:
                chunk = conn.recv(65536)
            except TimeoutError:
                continue
            if not chunk:
                break
            buffer += chunk
            while True:
                frame, buffer = _parse_frame(buffer)
                if frame is None:
                    break
                opcode, payload = frame
                if opcode == 8:  # close
                    return
                if opcode == 9:  # ping -> pong
                    conn.sendall(_frame(payload, 10))
                elif opcode in (1, 2):
                    self._handle(conn, json.loads(payload.decode()))

    def _handle(self, conn: socket.socket, op: dict[str, Any]) -> None:
        with self._lock:
            self.ops.append(op)
            if op.get("op") == "call_service":
                conn.sendall(_frame(json.dumps(self._answer(op)).encode(), 1))
            elif op.get("op") == "publish" and op.get("topic") == "/initialpose" and self.amcl:
                if self.amcl_ignores > 0:
                    self.amcl_ignores -= 1
                else:
                    timer = threading.Timer(self.amcl_delay, self.send, ("/amcl_pose", op["msg"]))
                    timer.daemon = True
                    timer.start()
            elif op.get("op") == "subscribe":
                self.subscriptions.setdefault(op["topic"], []).append(conn)
            elif op.get("op") == "unsubscribe":
                subs = self.subscriptions.get(op["topic"], [])
                if conn in subs:
                    subs.remove(conn)
            hook = self.hooks.get((str(op.get("op")), str(op.get("topic"))))
        if hook is not None:  # outside the lock: a hook may send
            hook(op)

    def _answer(self, op: dict[str, Any]) -> dict[str, Any]:
        """rosapi's publishers and AMCL's service where offered; else what rosbridge answers for a
        service nobody offers."""
        answer: dict[str, Any] = {"op": "service_response", "id": op.get("id"), "service": op.get("service")}
        service = op.get("service")
        if service == "/rosapi/publishers" and self.rosapi:
            topic = (op.get("args") or {}).get("topic")
            up = any(o.get("op") == "advertise" and o.get("topic") == topic for o in self.ops)
            publishers = ["/rosbridge_websocket"] if up else []
            publishers += ["/robot"] if topic in self.robot_topics else []
            return answer | {"values": {"publishers": publishers}, "result": True}
        if service == "/set_initial_pose" and self.set_initial_pose:
            return answer | {"values": {}, "result": True}
        return answer | {"values": f"Service {service} does not exist", "result": False}

    # -- the test's side ------------------------------------------------------------------------------

    def send(self, topic: str, msg: dict[str, Any]) -> int:
        """Publish ``msg`` to every client subscribed to ``topic``; returns how many got it (a client
        that closed its link meanwhile, as an interrupted run does, does not)."""
        data = _frame(json.dumps({"op": "publish", "topic": topic, "msg": msg}).encode(), 1)
        with self._lock:
            targets = list(self.subscriptions.get(topic, []))
        sent = 0
        for c in targets:
            try:
                c.sendall(data)
            except OSError:
                continue
            sent += 1
        return sent

    def published(self, topic: str) -> list[dict[str, Any]]:
        with self._lock:
            return [o["msg"] for o in self.ops if o.get("op") == "publish" and o.get("topic") == topic]

    def of(self, kind: str) -> list[dict[str, Any]]:
        with self._lock:
            return [o for o in self.ops if o.get("op") == kind]

    def wait_for(self, predicate: Any, timeout: float = 5.0) -> bool:
        return wait_until(predicate, timeout)

    def drop_clients(self) -> None:
        """Close every client connection (the robot's bridge went away)."""
        with self._lock:
            clients = list(self.clients)
        for c in clients:
            try:
                c.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass


class PlainWebsocketServer(RosbridgeServer):
    """A websocket server that is no rosbridge: it records what it gets and answers nothing, or with
    ``echo`` sends every frame back as it came."""

    def __init__(self, echo: bool = False) -> None:
        super().__init__()
        self.echo = echo

    def _handle(self, conn: socket.socket, op: dict[str, Any]) -> None:
        with self._lock:
            self.ops.append(op)
        if self.echo:
            conn.sendall(_frame(json.dumps(op).encode(), 1))


def _frame(payload: bytes, opcode: int) -> bytes:
    head = bytes([0x80 | opcode])
    n = len(payload)
    if n < 126:
        head += bytes([n])
    elif n < 65536:
        head += bytes([126]) + struct.pack(">H", n)
    else:
        head += bytes([127]) + struct.pack(">Q", n)
    return head + payload


def _handshake(conn: socket.socket) -> None:
    """The websocket upgrade: read the request (5 s at most), answer with the accept key
    (StopIteration when the request has no key)."""
    request = b""
    deadline = time.monotonic() + 5
    while b"\r\n\r\n" not in request and time.monotonic() < deadline:
        try:
            request += conn.recv(4096)
        except TimeoutError:
            continue
    key = next(
        line.split(":", 1)[1].strip()
        for line in request.decode("latin-1").split("\r\n")
        if line.lower().startswith("sec-websocket-key:")
    )
    accept = base64.b64encode(hashlib.sha1((key + _GUID).encode()).digest()).decode()
    conn.sendall(
        (
            "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            f"Sec-WebSocket-Accept: {accept}\r\n\r\n"
        ).encode()
    )


def _parse_frame(buf: bytes) -> tuple[tuple[int, bytes] | None, bytes]:
    if len(buf) < 2:
        return None, buf
    opcode = buf[0] & 0x0F
    masked = buf[1] & 0x80
    n = buf[1] & 0x7F
    i = 2
    if n == 126:
        if len(buf) < 4:
            return None, buf
        n = struct.unpack(">H", buf[2:4])[0]
        i = 4
    elif n == 127:
        if len(buf) < 10:
            return None, buf
        n = struct.unpack(">Q", buf[2:10])[0]
        i = 10
    mask = b""
    if masked:
        if len(buf) < i + 4:
            return None, buf
        mask = buf[i : i + 4]
        i += 4
    if len(buf) < i + n:
        return None, buf
    payload = buf[i : i + n]
    if masked:
        payload = bytes(b ^ mask[k % 4] for k, b in enumerate(payload))
    return (opcode, payload), buf[i + n :]
