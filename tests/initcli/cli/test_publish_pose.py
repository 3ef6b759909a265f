"""initcli.cli.publish_pose called directly with --dry-run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from initcli.cli.publish_pose import publish_pose


def test_publish_pose_dry_run_prints_the_message(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    summary = tmp_path / "summary.json"
    doc = {"success": True, "pose": {"x": 2.0, "y": 3.0, "yaw_deg": 180.0}, "duration_s": 7.5}
    doc["covariance"] = [[0.1, 0, 0], [0, 0.2, 0], [0, 0, 0.3]]
    summary.write_text(json.dumps(doc))
    publish_pose(summary, dry_run=True)
    out = capsys.readouterr().out
    msg = json.loads(out[: out.rindex("}") + 1])
    assert msg["header"]["stamp"] == {"sec": 7, "nanosec": 500_000_000}
    assert msg["pose"]["pose"]["position"] == {"x": 2.0, "y": 3.0, "z": 0.0}
    assert msg["pose"]["pose"]["orientation"]["w"] == pytest.approx(0.0, abs=1e-12)
    cov = msg["pose"]["covariance"]
    assert (cov[0], cov[7], cov[35]) == (0.1, 0.2, 0.3)


def test_publish_pose_failed_session_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import typer

    summary = tmp_path / "summary.json"
    summary.write_text(json.dumps({"success": False, "reason": "distance limit"}))
    with pytest.raises(typer.Exit) as exc:
        publish_pose(summary, dry_run=True)
    assert exc.value.exit_code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "distance limit" in err


def _publish(summary: Path, port: int, confirm: str):
    from typer.testing import CliRunner

    from initcli.cli.main import app

    args = ["publish-pose", str(summary), "--host", "127.0.0.1", "--port", str(port), "--confirm", confirm]
    return CliRunner().invoke(app, args)


def _live_summary(tmp_path: Path, stamps: str) -> Path:
    summary = tmp_path / "summary.json"
    doc = {"success": True, "pose": {"x": 2.0, "y": 3.0, "yaw_deg": 180.0}, "duration_s": 7.5}
    doc["published"] = {"stamp": 1_700_000_020.25, "x": 2.5, "y": 3.5, "yaw_deg": 170.0}
    doc["clock"] = {"origin_stamp": 1_700_000_000.0, "stamps": stamps}
    summary.write_text(json.dumps(doc))
    return summary


@pytest.mark.parametrize("stamps", ["ros1 (secs, nsecs)", "ros2 (sec, nanosec)"])
def test_publish_pose_sends_what_the_live_run_published_in_its_robots_stamps(
    tmp_path: Path, stamps: str
) -> None:
    pytest.importorskip("roslibpy")
    from tests.initcli.ros.rosbridge_server import RosbridgeServer

    summary = _live_summary(tmp_path, stamps)
    with RosbridgeServer(rosapi=True, amcl=True) as server:
        result = _publish(summary, server.port, "3")
        assert result.exit_code == 0, result.output
        assert "confirmed by AMCL" in result.output
        (msg,) = server.published("/initialpose")
        advertised = [
            i for i, o in enumerate(server.ops) if o.get("op") == "advertise" and o["topic"] == "/initialpose"
        ]
        first_publish = next(i for i, o in enumerate(server.ops) if o.get("op") == "publish")
        assert advertised and advertised[0] < first_publish
    ros1 = stamps.startswith("ros1")
    assert msg["header"]["stamp"] == (
        {"secs": 1_700_000_020, "nsecs": 250_000_000}
        if ros1
        else {"sec": 1_700_000_020, "nanosec": 250_000_000}
    )
    assert msg["pose"]["pose"]["position"] == {"x": 2.5, "y": 3.5, "z": 0.0}


def test_publish_pose_unconfirmed_exits_1(tmp_path: Path) -> None:
    pytest.importorskip("roslibpy")
    from tests.initcli.ros.rosbridge_server import RosbridgeServer

    summary = _live_summary(tmp_path, "ros2 (sec, nanosec)")
    with RosbridgeServer(rosapi=True) as server:  # no AMCL
        result = _publish(summary, server.port, "0.5")
    assert result.exit_code == 1 and "not confirmed by AMCL" in result.output


def test_publish_pose_to_a_server_that_goes_mute_is_not_sent(tmp_path: Path, monkeypatch) -> None:
    """A server that answers the handshake, then nothing: no "sent", one line, exit 2."""
    pytest.importorskip("roslibpy")
    from initcli.ros import delivery
    from tests.initcli.ros.rosbridge_server import RosbridgeServer

    monkeypatch.setattr(delivery, "SERVICE_TIMEOUT_S", 0.5)  # its unanswered calls: sooner

    class MuteAfterHandshake(RosbridgeServer):
        answered = 0

        def _handle(self, conn, op):  # type: ignore[no-untyped-def]
            if op.get("op") == "call_service":
                self.answered += 1
                if self.answered > 1:
                    with self._lock:
                        self.ops.append(op)
                    return  # mute
            super()._handle(conn, op)

    summary = _live_summary(tmp_path, "ros2 (sec, nanosec)")
    with MuteAfterHandshake() as server:
        result = _publish(summary, server.port, "0")
    assert result.exit_code == 2, result.output
    assert "sent /initialpose" not in result.output
    assert "not known to be sent" in result.output and "Traceback" not in result.output
