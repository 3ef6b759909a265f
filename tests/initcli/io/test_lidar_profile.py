"""The lidar profile measured on real laser logs (``lidar.profile``): the shipped file is valid and
read, a broken one or one beside the values it replaces is refused, and the simulator takes its
noise, dropout and clutter while the default leaves the simulated scans as they were."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from bimkit.errors import InputError
from initcli.config import load_config, parse_config
from initcli.config.building import choose_storey, prepare_site
from initcli.config.checks import lidar_profile
from initcli.io.lidar_profile import (
    LIDAR_PROFILE_FORMAT,
    LIDAR_PROFILE_NAMES,
    LidarProfile,
    read_lidar_profile,
    resolve_lidar_profile,
)
from initcli.sim.build import build_sim
from tests.helpers import SAMPLES

SHIPPED = LIDAR_PROFILE_NAMES["real-logs"]


def test_the_shipped_profile_is_valid_and_carries_its_measurements_and_provenance() -> None:
    profile = read_lidar_profile(SHIPPED)
    assert resolve_lidar_profile("real-logs") == SHIPPED
    assert 0 < profile.noise < 0.1 and 0 < profile.dropout < 0.2 and profile.clutter > 0
    doc = json.loads(SHIPPED.read_text())
    assert doc["format"] == LIDAR_PROFILE_FORMAT
    logs = doc["measured"]["logs"]
    assert len(logs) >= 2 and doc["provenance"]["logs"] == sorted(logs)
    for measured in [*logs.values(), doc["measured"]["pooled"]]:
        assert 0 < measured["off_wall_share"] < 1
        assert 0 <= measured["no_return_share"] < 1
    assert doc["sim"]["dropout"] == doc["measured"]["pooled"]["no_return_share"]
    assert doc["odometry"]["measured"] is False  # the corrected logs' odometry is their truth
    assert doc["sim_check"], "the simulated off-wall share the clutter was tuned on"


@pytest.mark.parametrize(
    ("doc", "pattern"),
    [
        ({"format": "x", "sim": {}}, "not a lidar profile"),
        ({"format": LIDAR_PROFILE_FORMAT}, "sim: an object"),
        ({"format": LIDAR_PROFILE_FORMAT, "sim": {"noise": 0.02, "dropout": 0.01}}, "sim.clutter: a number"),
        ({"format": LIDAR_PROFILE_FORMAT, "sim": {"noise": 0.02, "dropout": 2, "clutter": 0}}, "sim.dropout"),
    ],
)
def test_a_malformed_profile_is_refused(doc: dict[str, Any], pattern: str) -> None:
    with pytest.raises(InputError, match=pattern):
        LidarProfile.from_dict(doc, "p.json")


def _site_doc(name: str, **lidar: Any) -> dict[str, Any]:
    """The sample's config without the keys a profile replaces (the site's path absolute)."""
    doc = yaml.safe_load((SAMPLES / f"{name}.site.yaml").read_text())
    doc["site"]["path"] = str((SAMPLES / doc["site"]["path"]).resolve())
    for key in ("noise", "dropout"):
        doc.get("lidar", {}).pop(key, None)
    doc["sim"].pop("clutter", None)
    doc["lidar"] = {**doc.get("lidar", {}), **lidar}
    return doc


def test_a_profile_beside_the_values_it_replaces_or_missing_is_refused(tmp_path: Path) -> None:
    doc = _site_doc("block_a", profile="real-logs")
    assert lidar_profile(parse_config(doc, tmp_path / "site.yaml")) == read_lidar_profile(SHIPPED)
    both = {**doc, "lidar": {**doc["lidar"], "noise": 0.05}, "sim": {**doc["sim"], "clutter": 0.1}}
    with pytest.raises(InputError, match="lidar.profile replaces lidar.noise, sim.clutter: set the profile"):
        parse_config(both, tmp_path / "site.yaml")
    with pytest.raises(InputError, match=r"lidar.profile: .*mine.json: no such lidar profile"):
        parse_config(_site_doc("block_a", profile="mine.json"), tmp_path / "site.yaml")
    assert lidar_profile(parse_config(_site_doc("block_a"), tmp_path / "site.yaml")) is None


def _scans(doc: dict[str, Any], tmp_path: Path, name: str) -> tuple[Any, np.ndarray]:
    path = tmp_path / f"{name}.site.yaml"
    path.write_text(yaml.safe_dump(doc))
    config = load_config(path)
    site = prepare_site(config, tmp_path / name)
    storey, _ = choose_storey(config, site)
    setup = build_sim(config, site, storey, 5)
    driver = setup.driver
    scans = [driver.start().scan.ranges]
    for _ in range(5):
        scans.append(driver.step(0.3, 0.2).scan.ranges)
    return setup, np.array(scans)


def test_the_profile_changes_the_simulated_scans_and_the_default_leaves_them(tmp_path: Path) -> None:
    base = yaml.safe_load((SAMPLES / "block_a.site.yaml").read_text())
    base["site"]["path"] = str((SAMPLES / base["site"]["path"]).resolve())
    default, default_scans = _scans(base, tmp_path, "default")
    config = load_config(tmp_path / "default.site.yaml")
    assert default.driver.lidar.noise == config.lidar.noise
    assert default.driver.lidar.dropout == config.lidar.dropout
    # an empty profile is the default: the same world and the same scans, draw for draw
    empty, empty_scans = _scans({**base, "lidar": {**base["lidar"], "profile": ""}}, tmp_path, "empty")
    assert np.array_equal(empty_scans, default_scans, equal_nan=True)
    assert len(empty.world.clutter) == len(default.world.clutter)

    measured = read_lidar_profile(SHIPPED)
    profiled, profiled_scans = _scans(_site_doc("block_a", profile="real-logs"), tmp_path, "profiled")
    assert profiled.driver.lidar.noise == measured.noise != config.lidar.noise
    assert profiled.driver.lidar.dropout == measured.dropout != config.lidar.dropout
    assert len(profiled.world.clutter) > len(default.world.clutter)  # more stacks off the walls
    assert not np.array_equal(profiled_scans, default_scans, equal_nan=True)
    returns = np.isfinite(profiled_scans) & (profiled_scans < profiled.driver.lidar.max_range)
    assert (~returns).mean() >= measured.dropout * 0.5  # dropped beams
