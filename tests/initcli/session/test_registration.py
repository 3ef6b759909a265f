"""The session's lidar submap registration: with the camera off (every feature missed) a block_b
session initialises from the lidar alone, and says so; without the registration it cannot; with
the camera on, a registration claim weighs the doors the camera missed."""

from __future__ import annotations

import dataclasses

import pytest

from bimtools.site.load import Site
from initcli.config import SessionConfig, load_config
from initcli.session.registration import DECIDED_BY_REGISTRATION
from initcli.session.simulated import sim_session
from initcli.site import prepare_site
from tests.helpers import SAMPLES


@pytest.fixture(scope="module")
def camera_off(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site]:
    config = load_config(SAMPLES / "block_b.site.yaml")
    sim = dataclasses.replace(config.sim, miss_rate=1.0, false_positives_per_minute=0.0)
    limits = dataclasses.replace(config.limits, max_distance=60.0)
    config = dataclasses.replace(config, sim=sim, limits=limits)
    return config, prepare_site(config, tmp_path_factory.mktemp("block_b"))


def _run(config: SessionConfig, site: Site, enabled: bool):
    registration = dataclasses.replace(config.registration, enabled=enabled)
    built = sim_session(dataclasses.replace(config, registration=registration), site, 1)
    return built.session.run()


def test_with_the_camera_off_the_lidar_registration_initialises(camera_off) -> None:
    config, site = camera_off
    result = _run(config, site, True)
    assert result.success, result.reason
    assert result.features_detected == 0
    assert result.decided_by == DECIDED_BY_REGISTRATION
    assert result.pose is not None and result.truth_pose is not None
    assert result.pose.distance_to(result.truth_pose) < 0.3
    coarse = result.verifications[0]
    assert coarse["decided_by"] == DECIDED_BY_REGISTRATION and coarse["passed"]
    # the camera saw nothing, so the doors it missed are no evidence against the place
    assert coarse["negative_evidence"] is False and coarse["missed_predictions"] > 0


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
