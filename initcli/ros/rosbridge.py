"""The live link to a ROS robot over rosbridge (protocol v2, JSON over websocket) with roslibpy.

:class:`RosbridgeLink` advertises, publishes, subscribes and calls services; it can ask rosapi
whether a topic is up and wait until rosbridge has read what was sent (:meth:`RosbridgeLink.flush`).
roslibpy is in the ``[ros]`` extra: ``pip install 'bim-init[ros]'``.
"""

from __future__ import annotations

import base64
import os
import socket
import threading
from collections.abc import Callable
from typing import Any

from bimkit.errors import InputError

__all__ = [
    "CONNECT_TIMEOUT_S",
    "DEFAULT_PORT",
    "RosbridgeLink",
    "probe_websocket",
    "ros_type",
]

DEFAULT_PORT = 9090
CONNECT_TIMEOUT_S = 5.0
HANDSHAKE_SERVICE = "/bim_init/handshake"  # no robot offers it: rosbridge answers with a failure
ROSAPI_PUBLISHERS = "/rosapi/publishers"  # rosapi (launched with rosbridge): a topic's publishers


def _quiet_autobahn() -> None:
    """autobahn logs each dropped connection (and roslibpy reconnects three times) on stderr: our
    errors say what failed in one line, so its log keeps to the critical."""
    import txaio

    txaio.use_twisted()
    txaio.set_global_log_level("critical")  # type: ignore[attr-defined]  # set by use_twisted


def ros_type(msgtype: str) -> str:
    """rosbridge's spelling (``geometry_msgs/Twist``), which ROS 1 and ROS 2 bridges both accept."""
    return msgtype.replace("/msg/", "/")


def probe_websocket(host: str, port: int, timeout: float) -> None:
    """Ask ``host:port`` for a websocket (RFC 6455's upgrade) before roslibpy does: a server that
    refuses, closes or answers something else (an HTTP server, garbage) is one line saying which,
    where roslibpy would retry three times, log each drop and say "Failed to connect"."""
    where = f"ws://{host}:{port}"
    key = base64.b64encode(os.urandom(16)).decode()
    request = (
        f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
        f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
    )
    try:
        conn = socket.create_connection((host, port), timeout=timeout)
    except TimeoutError:
        raise InputError(f"cannot reach rosbridge at {where} (no connection in {timeout:g} s)") from None
    except OSError as exc:
        raise InputError(f"cannot reach rosbridge at {where} ({exc.strerror or exc})") from None
    answer = b""
    with conn:
        try:
            conn.sendall(request.encode())
            while b"\r\n" not in answer and len(answer) < 1024:
                chunk = conn.recv(1024)
                if not chunk:
                    break
                answer += chunk
        except TimeoutError:
            silent = f"{where} does not answer a websocket request (no reply in {timeout:g} s)"
            raise InputError(silent) from None
        except (ConnectionResetError, BrokenPipeError):
            pass  # closed on us: said below
    line = answer.split(b"\r\n", 1)[0].decode("latin-1").strip()
    if not line:
        raise InputError(f"{where} closed the connection without answering a websocket request")
    parts = line.split()
    if len(parts) < 2 or not parts[0].startswith("HTTP/") or parts[1] != "101":
        shown = line if len(line) <= 80 else line[:77] + "..."
        raise InputError(f"{where} is not a rosbridge server: it answered {shown!r} to a websocket request")


class RosbridgeLink:
    """One connection to a rosbridge server."""

    def __init__(self, host: str = "localhost", port: int = DEFAULT_PORT, timeout: float = CONNECT_TIMEOUT_S):
        try:
            import roslibpy
        except ImportError:
            raise InputError("the rosbridge link needs roslibpy: pip install 'bim-init[ros]'") from None
        self._roslibpy = roslibpy
        self.host, self.port = host, port
        probe_websocket(host, port, timeout)
        _quiet_autobahn()
        self.ros = roslibpy.Ros(host=host, port=port)
        try:
            self.ros.run(timeout=timeout)
        except Exception as exc:  # noqa: BLE001 - roslibpy raises its own and twisted's errors
            raise InputError(
                f"cannot reach rosbridge at ws://{host}:{port} ({exc or type(exc).__name__})"
            ) from None
        self._publishers: dict[str, Any] = {}
        self._subscribers: list[Any] = []
        self._lock = threading.Lock()
        try:
            self._handshake(timeout)
        except BaseException:
            self.close()
            raise

    def _handshake(self, timeout: float) -> None:
        """A websocket server is not yet a rosbridge: call a service no robot has and wait for the
        ``service_response`` every rosbridge (ROS 1 and 2) sends back, a failure naming the service.
        A plain websocket server (or one that echoes) never sends one: an error, not "sent"."""
        if self.call_service(HANDSHAKE_SERVICE, "std_srvs/Trigger", {}, timeout) is None:
            raise InputError(
                f"ws://{self.host}:{self.port} is a websocket server but does not speak rosbridge (no answer "
                f"to a rosbridge service call in {timeout:g} s)"
            )

    def call_service(
        self, name: str, srvtype: str, request: dict[str, Any], timeout: float
    ) -> tuple[bool, Any] | None:
        """Call a service through rosbridge: (True, the response) when it answered, (False, the
        error text) when rosbridge refused (no such service, a failure), None: no answer in time."""
        answered = threading.Event()
        answer: list[tuple[bool, Any]] = []

        def done(ok: bool, value: Any) -> None:
            answer.append((ok, value))
            answered.set()

        service = self._roslibpy.Service(self.ros, name, ros_type(srvtype))
        service.call(
            self._roslibpy.ServiceRequest(request), lambda v: done(True, dict(v)), lambda e: done(False, e)
        )
        return answer[0] if answered.wait(timeout) else None

    def publisher_up(self, topic: str, timeout: float) -> bool | None:
        """Whether rosbridge reports a publisher on ``topic`` (rosapi's ``publishers``); None: the
        server offers no rosapi, so nobody can tell."""
        answer = self.call_service(ROSAPI_PUBLISHERS, "rosapi/Publishers", {"topic": topic}, timeout)
        if answer is None or not answer[0]:
            return None
        return bool(answer[1].get("publishers"))

    def flush(self, timeout: float = CONNECT_TIMEOUT_S) -> bool:
        """Wait until rosbridge has read everything sent so far: it handles one connection's frames
        in order, so the answer to a service call sent last comes after all of them."""
        return self.call_service(HANDSHAKE_SERVICE, "std_srvs/Trigger", {}, timeout) is not None

    @property
    def connected(self) -> bool:
        return bool(self.ros.is_connected)

    def advertise(self, topic: str, msgtype: str) -> Any:
        with self._lock:
            pub = self._publishers.get(topic)
            if pub is None:
                pub = self._roslibpy.Topic(self.ros, topic, ros_type(msgtype))
                pub.advertise()
                self._publishers[topic] = pub
            return pub

    def publish(self, topic: str, msgtype: str, message: dict[str, Any]) -> None:
        if not self.connected:
            raise InputError(f"rosbridge at ws://{self.host}:{self.port}: connection lost")
        self.advertise(topic, msgtype).publish(self._roslibpy.Message(message))

    def subscribe(self, topic: str, msgtype: str, callback: Callable[[dict[str, Any]], None]) -> None:
        sub = self._roslibpy.Topic(self.ros, topic, ros_type(msgtype))
        sub.subscribe(callback)
        self._subscribers.append(sub)

    def close(self) -> None:
        for sub in self._subscribers:
            try:
                sub.unsubscribe()
            except Exception:  # noqa: BLE001 - closing anyway
                pass
        for pub in self._publishers.values():
            try:
                pub.unadvertise()
            except Exception:  # noqa: BLE001
                pass
        try:
            self.ros.close()
        except Exception:  # noqa: BLE001
            pass

    def __enter__(self) -> RosbridgeLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
