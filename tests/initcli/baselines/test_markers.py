"""The ArUco marker baseline of §4.3 on the block_a sample: wall following until a tag is decoded."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.load import Site
from initcli.baselines.markers import MarkerParams, deploy_markers, run_markers
from initcli.config import SessionConfig, load_config
from initcli.config.building import choose_storey, prepare_site
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.build import build_sim
from initcli.sim.markers import Marker
from tests.helpers import SAMPLES


@pytest.fixture(scope="module")
def block_a(tmp_path_factory: pytest.TempPathFactory) -> tuple[SessionConfig, Site, str]:
    config = load_config(SAMPLES / "block_a.site.yaml")
    site = prepare_site(config, tmp_path_factory.mktemp("block_a"))
    storey, _ = choose_storey(config, site)
    return config, site, storey


def facing_first_marker(config: SessionConfig, site: Site, storey: str) -> tuple[Pose2D, Marker]:
    """A start 1.3 m in front of tag 0, looking at it and 20 degrees along the corridor."""
    tag = deploy_markers(config, site, storey, MarkerParams())[0]
    n = np.array(tag.normal)
    xy = np.array([tag.x, tag.y]) + 1.3 * n
    return Pose2D(float(xy[0]), float(xy[1]), tag.yaw + math.pi + math.radians(20.0)), tag


def test_localises_from_a_start_facing_a_marker(block_a: tuple[SessionConfig, Site, str]) -> None:
    config, site, storey = block_a
    start, _ = facing_first_marker(config, site, storey)
    setup = build_sim(config, site, storey, 4, start=start)
    outcome = run_markers(config, site, setup, np.random.default_rng(4))
    assert outcome.method == "markers"
    assert outcome.localised and "marker" in outcome.reason
    assert outcome.pose is not None and outcome.truth is not None
    assert outcome.distance_m < 3.0
    assert outcome.features >= 1
    assert outcome.pose.distance_to(outcome.truth) < 0.2
    assert math.degrees(outcome.pose.yaw_error(outcome.truth)) < 3.0
    assert outcome.duration_s >= 0.0 and outcome.wall_seconds > 0.0
    assert outcome.truth.distance_to(start) <= outcome.distance_m + 1e-6


def test_same_seed_same_outcome(block_a: tuple[SessionConfig, Site, str]) -> None:
    config, site, storey = block_a
    runs = [
        run_markers(config, site, build_sim(config, site, storey, 7), np.random.default_rng(7))
        for _ in range(2)
    ]
    assert runs[0].localised == runs[1].localised
    assert runs[0].pose == runs[1].pose and runs[0].distance_m == runs[1].distance_m


def test_gives_up_after_the_distance_limit(block_a: tuple[SessionConfig, Site, str]) -> None:
    config, site, storey = block_a
    config = load_config(SAMPLES / "block_a.site.yaml")
    config.limits.max_distance = 4.0
    setup = build_sim(config, site, storey, 2)
    outcome = run_markers(config, site, setup, np.random.default_rng(2), MarkerParams(count=0))
    assert not outcome.localised
    assert outcome.pose is None and outcome.truth is not None
    assert outcome.features == 0
    assert 4.0 < outcome.distance_m < 4.5
    assert "4 m" in outcome.reason


def test_invisible_markers_are_never_decoded(block_a: tuple[SessionConfig, Site, str]) -> None:
    config, site, storey = block_a
    config = load_config(SAMPLES / "block_a.site.yaml")
    config.limits.max_distance = 3.0
    start, _ = facing_first_marker(config, site, storey)
    setup = build_sim(config, site, storey, 4, start=start)
    outcome = run_markers(config, site, setup, np.random.default_rng(4), MarkerParams(min_side_px=1000.0))
    assert not outcome.localised and outcome.features == 0
