"""The rosbridge link against a rosbridge-v2-protocol server on loopback."""

from __future__ import annotations

import math

import pytest

from bimkit.errors import InputError
from initcli.ros.records import InitialPose
from tests.initcli.ros.rosbridge_server import PlainWebsocketServer, RosbridgeServer

pytest.importorskip("roslibpy")

from initcli.ros.delivery import publish_initial_pose  # noqa: E402
from initcli.ros.rosbridge import RosbridgeLink  # noqa: E402


def test_initial_pose_fields():
    cov = tuple(float(i) for i in range(36))
    pose = InitialPose(12.25, 3.0, -4.5, math.radians(100.0), cov)
    with RosbridgeServer() as server:
        publish_initial_pose(pose, "127.0.0.1", server.port)
        assert server.wait_for(lambda: server.published("/initialpose"), 5)
        adverts = {o["topic"]: o["type"] for o in server.of("advertise")}
        assert adverts["/initialpose"] == "geometry_msgs/PoseWithCovarianceStamped"
        assert adverts["/bim_init/state"] == "std_msgs/String"
        (msg,) = server.published("/initialpose")
        assert server.wait_for(lambda: server.published("/bim_init/state"), 5)
        assert server.published("/bim_init/state") == [{"data": "initialised"}]
    assert msg["header"] == {"stamp": {"sec": 12, "nanosec": 250_000_000}, "frame_id": "map"}
    p, q = msg["pose"]["pose"]["position"], msg["pose"]["pose"]["orientation"]
    assert (p["x"], p["y"], p["z"]) == (3.0, -4.5, 0.0)
    assert math.degrees(2 * math.atan2(q["z"], q["w"])) == pytest.approx(100.0)
    assert q["x"] == q["y"] == 0.0
    assert msg["pose"]["covariance"] == list(cov)


def test_no_server_is_one_input_error():
    with RosbridgeServer() as server:
        port = server.port
    with pytest.raises(InputError, match=f"cannot reach rosbridge at ws://127.0.0.1:{port}"):
        RosbridgeLink("127.0.0.1", port, timeout=1.0)


def test_subscribe_receives_what_the_robot_publishes():
    got: list[dict] = []
    with RosbridgeServer() as server, RosbridgeLink("127.0.0.1", server.port) as link:
        link.subscribe("/odom", "nav_msgs/msg/Odometry", got.append)
        assert server.wait_for(lambda: server.of("subscribe"), 5)
        assert server.of("subscribe")[0]["type"] == "nav_msgs/Odometry"
        server.send("/odom", {"pose": {"pose": {"position": {"x": 1.5}}}})
        assert server.wait_for(lambda: got, 5)
    assert got[0]["pose"]["pose"]["position"]["x"] == 1.5


@pytest.mark.parametrize("echo", [False, True])
def test_a_websocket_server_that_is_no_rosbridge_is_an_error_and_nothing_is_published(echo):
    pose = InitialPose(1.0, 2.0, 3.0, 0.0, tuple([0.0] * 36))
    with PlainWebsocketServer(echo=echo) as server:
        with pytest.raises(InputError, match=r"is a websocket server but does not speak rosbridge"):
            publish_initial_pose(pose, "127.0.0.1", server.port, timeout=1.0)
        assert [o["op"] for o in server.ops] == ["call_service"]  # the handshake, and nothing after


class _RawServer:
    """A TCP server on loopback that answers each connection with ``reply`` (None: closes at once;
    b"": reads and stays silent), in a thread."""

    def __init__(self, reply: bytes | None) -> None:
        import socket
        import threading

        self.reply = reply
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen()
        self.port = self.sock.getsockname()[1]
        self.held: list[object] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            if self.reply is None:
                conn.close()
                continue
            conn.recv(4096)
            if self.reply:
                conn.sendall(self.reply)
                conn.close()
            else:
                self.held.append(conn)  # mute: keeps the connection open, says nothing

    def close(self) -> None:
        self.sock.close()


@pytest.mark.parametrize(
    ("reply", "said"),
    [
        (b"HTTP/1.0 200 OK\r\n\r\n", r"not a rosbridge server: it answered .HTTP/1.0 200 OK."),
        (b"garbage\r\n\r\n", r"is not a rosbridge server: it answered 'garbage'"),
        (None, r"closed the connection without answering a websocket request"),
        (b"", r"does not answer a websocket request \(no reply in 1 s\)"),
    ],
    ids=["http", "garbage", "closes", "mute"],
)
def test_a_server_that_is_no_websocket_is_one_line_saying_what_it_did(capfd, reply, said):
    """An HTTP server, garbage, a closed or a silent port: one line, no library log on stderr."""
    server = _RawServer(reply)
    try:
        with pytest.raises(InputError, match=said) as info:
            RosbridgeLink("127.0.0.1", server.port, timeout=1.0)
    finally:
        server.close()
    assert "\n" not in str(info.value)
    assert capfd.readouterr().err == ""
