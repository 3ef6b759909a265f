"""The session's lidar submap registration: with the camera off (every feature missed) a block_b
session initialises from the lidar alone, and says so; without the registration it cannot; with
the camera on, a registration claim weighs the doors the camera missed. ``bim-init match`` replays
such a claim from the session's log (and not with ``--no-registration``, nor from the log cut
before the claim)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from bimtools.site.load import Site
from initcli.cli.main import app
from initcli.config import SessionConfig, load_config
from initcli.config.building import prepare_site
from initcli.session.simulated import sim_session
from initcli.verify.registration import DECIDED_BY_REGISTRATION
from tests.helpers import SAMPLES


@pytest.fixture(scope="module")
def camera_off(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    config = load_config(SAMPLES / "block_b.site.yaml")
    sim = dataclasses.replace(config.sim, miss_rate=1.0, false_positives_per_minute=0.0)
    limits = dataclasses.replace(config.limits, max_distance=60.0)
    config = dataclasses.replace(config, sim=sim, limits=limits)
    return config, prepare_site(config, tmp_path_factory.mktemp("block_b"))


def _run(config: SessionConfig, site: Site, enabled: bool, log: Path | None = None):
    registration = dataclasses.replace(config.registration, enabled=enabled)
    built = sim_session(dataclasses.replace(config, registration=registration), site, 1, log_path=log)
    return built.session.run()


@pytest.fixture(scope="module")
def camera_off_run(camera_off, tmp_path_factory: pytest.TempPathFactory):
    """The camera-off session with its detection log: the result and the log's path."""
    config, site = camera_off
    log = tmp_path_factory.mktemp("camera_off_log") / "session.jsonl"
    return _run(config, site, True, log), log


def test_with_the_camera_off_the_lidar_registration_initialises(camera_off_run) -> None:
    result, _ = camera_off_run
    assert result.success, result.reason
    assert result.features_detected == 0
    assert result.decided_by == DECIDED_BY_REGISTRATION
    assert result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.3
    coarse = result.verifications[0]
    assert coarse["decided_by"] == DECIDED_BY_REGISTRATION and coarse["passed"]
    # the camera saw nothing, so the doors it missed are no evidence against the place
    assert coarse["negative_evidence"] is False and coarse["missed_predictions"] > 0


@pytest.fixture(scope="module")
def phantom_run(camera_off, tmp_path_factory: pytest.TempPathFactory):
    """The camera-off session, but for a false box a minute (sim.false_positives_per_minute 1): the
    result and the log's path."""
    config, site = camera_off
    config = dataclasses.replace(config, sim=dataclasses.replace(config.sim, false_positives_per_minute=1.0))
    log = tmp_path_factory.mktemp("phantom_log") / "session.jsonl"
    return _run(config, site, True, log), log


def _boxes_before_claim(log: Path) -> int:
    """How many boxes the camera fired in the images before the session's coarse claim."""
    docs = [json.loads(line) for line in log.read_text().splitlines()]
    claim_t = next(d["t"] for d in docs if d.get("state") == "coarse")
    return sum(len(d["objects"]) for d in docs if d.get("type") == "detections" and d["t"] <= claim_t)


def test_a_false_box_now_and_then_does_not_hold_back_the_lidar_registration(phantom_run) -> None:
    """A camera that sees nothing but fires a false box now and then is blind all the same: the
    box confirms no feature, so the doors the place predicts in view and the camera missed are no
    evidence against the lidar's place (a phantom stairs 5 s before the first unique registration
    used to refuse the true place: 5 of 5 doors in view never detected)."""
    result, log = phantom_run
    assert result.success, result.reason
    assert result.decided_by == DECIDED_BY_REGISTRATION and result.features_detected == 0
    assert _boxes_before_claim(log) >= 1  # the false box came before the claim
    coarse = result.verifications[0]
    assert coarse["decided_by"] == DECIDED_BY_REGISTRATION and coarse["passed"]
    assert coarse["negative_evidence"] is False and coarse["missed_predictions"] > 0
    assert result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.3


def test_the_log_with_a_false_box_replays_to_the_registration_claim(camera_off, phantom_run) -> None:
    """``bim-init match`` judges the camera of the log as the session did: blind, its false box
    notwithstanding, so the same registration is claimed offline."""
    _, site = camera_off
    result, log = phantom_run
    code, doc = _match(log, site)
    assert code == 0 and doc["decided_by"] == DECIDED_BY_REGISTRATION
    assert doc["registration"]["negative_evidence"] is False
    assert doc["registration"]["registration_fit"] == result.verifications[0]["registration_fit"]


def test_with_the_camera_off_and_no_registration_nothing_is_claimed(camera_off) -> None:
    config, site = camera_off
    result = _run(config, site, False)
    assert not result.success and result.decided_by is None
    assert result.coarse_pose is None


def test_with_the_camera_on_a_registration_claim_weighs_the_doors_it_missed(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """block_b under construction, seed 7: the camera has seen doors but not yet enough for a unique
    match when the lidar's submap is unique (30 m; the doors alone claimed after 87 m). The camera
    works, so the doors the place predicts in view and the camera missed count against it before
    the claim."""
    config = load_config(SAMPLES / "block_b.site.yaml", reality="construction")
    site = prepare_site(config, tmp_path_factory.mktemp("block_b_construction"))
    result = sim_session(config, site, 7).session.run()
    assert result.success, result.reason
    assert result.decided_by == DECIDED_BY_REGISTRATION
    assert result.features_detected > 0
    coarse = result.verifications[0]
    assert coarse["negative_evidence"] is True and coarse["passed"]
    assert result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.3


def _match(log: Path, site: Site, *extra: str) -> tuple[int, dict]:
    out = CliRunner().invoke(app, ["match", str(log), "--site", str(site.root), "--json", *extra])
    assert out.exit_code in (0, 3, 4), out.output
    return out.exit_code, json.loads(out.stdout)


def test_the_camera_off_session_log_replays_to_the_registration_claim(camera_off, camera_off_run) -> None:
    """``bim-init match`` registers the log's submaps where the session did: the same registration
    (its fit) claimed, at the session's place carried to the log's end; not with --no-registration."""
    _, site = camera_off
    result, log = camera_off_run
    code, doc = _match(log, site)
    assert code == 0 and doc["verdict"] == "unique match"
    assert doc["decided_by"] == DECIDED_BY_REGISTRATION and doc["paper_verdict"] == "no consistent match"
    coarse = result.verifications[0]
    assert doc["registration"]["registration_fit"] == coarse["registration_fit"]
    assert doc["registration"]["negative_evidence"] is False
    best = doc["hypotheses"][0]
    assert best["matches"] == [] and best["verification"]["passed"]
    truth = doc["truth"]
    assert abs(best["pose"]["x"] - truth["x"]) < 0.3 and abs(best["pose"]["y"] - truth["y"]) < 0.3
    code, doc = _match(log, site, "--no-registration")
    assert code == 4 and doc["decided_by"] is None and doc["registration"] is None
    assert not any(h["matches"] == [] for h in doc["hypotheses"])


def test_the_log_cut_before_the_claim_claims_nothing(camera_off, camera_off_run, tmp_path: Path) -> None:
    """The log up to a second before the session's claim: the registrations the session made by
    then were not unique or failed the checks, so none is claimed offline either."""
    _, site = camera_off
    _, log = camera_off_run
    lines = log.read_text().splitlines()
    claim_t = next(json.loads(line)["t"] for line in lines if '"state"' in line and '"coarse"' in line)
    cut = tmp_path / "cut.jsonl"
    cut.write_text("\n".join(line for line in lines if json.loads(line).get("t", 0.0) < claim_t - 1.0) + "\n")
    code, doc = _match(cut, site)
    assert code == 4 and doc["decided_by"] is None
    assert any("no claim in" in note for note in doc["notes"])


def test_as_built_the_open_doors_tell_a_repeating_floor_from_its_half_turn(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """ntu_hallway's corridors are the same turned half round but for where the doors are; its map
    draws the doors shut. As built, with the camera off, the beams through the open doors cross the
    map's walls at the true place as at every place alike, and only with the model's doors open
    (:func:`initcli.core.lidar.registration.open_doorways`) are the places alike ruled out."""
    config = load_config(SAMPLES / "ntu_hallway.site.yaml", reality="construction")
    sim = dataclasses.replace(config.sim, miss_rate=1.0, false_positives_per_minute=0.0)
    config = dataclasses.replace(
        config, sim=sim, limits=dataclasses.replace(config.limits, max_distance=60.0)
    )
    site = prepare_site(config, tmp_path_factory.mktemp("ntu_hallway"))
    result = sim_session(config, site, 1).session.run()
    assert result.success, result.reason
    assert result.decided_by == DECIDED_BY_REGISTRATION and result.features_detected == 0
    assert result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.3
    through = result.verifications[0]["registration_through"]
    assert through[0] <= 0.02 and min(through[1:]) >= through[0] + config.registration.see_through


def test_a_start_unlike_any_other_place_is_registered_before_the_robot_drives(
    tmp_path_factory: pytest.TempPathFactory,
) -> None:
    """block_a, camera off, seed 72: the first registration at 0 m (``registration.min_travel``)
    places the robot from its first scan; at 10 m, as before, not before 10 m."""
    config = load_config(SAMPLES / "block_a.site.yaml")
    sim = dataclasses.replace(config.sim, miss_rate=1.0, false_positives_per_minute=0.0)
    config = dataclasses.replace(
        config, sim=sim, limits=dataclasses.replace(config.limits, max_distance=30.0)
    )
    site = prepare_site(config, tmp_path_factory.mktemp("block_a"))
    assert config.registration.min_travel == 0.0
    result = sim_session(config, site, 72).session.run()
    assert result.success and result.decided_by == DECIDED_BY_REGISTRATION, result.reason
    assert result.distance_coarse_m is not None and result.distance_coarse_m < 2.0
    assert result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.3
    later = dataclasses.replace(config.registration, min_travel=10.0)
    result = sim_session(dataclasses.replace(config, registration=later), site, 72).session.run()
    # (10 m of odometry travel, the distance is the true path's)
    assert result.distance_coarse_m is None or result.distance_coarse_m >= 9.5
