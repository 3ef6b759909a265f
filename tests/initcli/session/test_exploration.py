"""initcli.session.exploration: targets that tell hypotheses apart, routes, and giving up."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from bimtools.site.load import Site, StoreyModel
from bimtools.site.records import FREE, OCCUPIED, Feature, OccupancyGrid
from initcli.config import load_config
from initcli.config.exploration import TargetSettings
from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.wall_following import WallFollowParams
from initcli.drivers.base import SensorFrame
from initcli.match.pipeline import Hypothesis
from initcli.session.exploration import ActiveExploration
from tests.helpers import SAMPLES

TARGETS = TargetSettings()  # exploration.targets' defaults
VIEW_DISTANCE, STALL_S, LOOK_S, MAX_FRUITLESS = (
    TARGETS.view_distance,
    TARGETS.stall,
    TARGETS.look,
    TARGETS.max_fruitless,
)


def _site() -> Site:
    """An empty 8 m x 5 m room: two doors on the bottom wall, one lift on the top wall."""
    cells = np.full((52, 82), FREE, dtype=np.uint8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    features = [
        Feature("d1", "Door", 1.0, 0.0, 0.0, 1.0, 1.0, 2.1),
        Feature("d2", "Door", 2.5, 0.0, 0.0, 1.0, 1.0, 2.1),
        Feature("l1", "Lift", 6.0, 5.0, 0.0, -1.0, 1.2, 2.2),
    ]
    storey = StoreyModel("L0", 0.0, features, grid=OccupancyGrid(cells, 0.1, (-0.1, -0.1, 0.0)))
    return Site(SAMPLES, {"L0": storey})


def _hypothesis(rank: int, transform: Pose2D, matches: list[str | None]) -> Hypothesis:
    return Hypothesis(rank, "L0", (), matches, 0, 0.1, transform, None, transform, 0.5, 1)


@pytest.fixture(scope="module")
def config():
    return load_config(SAMPLES / "block_a.site.yaml")


def _explorer(config) -> ActiveExploration:
    return ActiveExploration(config, _site(), WallFollowParams())


def test_targets_face_the_rarest_unmatched_category_nearest_first(config) -> None:
    active = _explorer(config)
    a = _hypothesis(1, Pose2D(0, 0, 0), ["d1"])
    b = _hypothesis(2, Pose2D(3.0, 0.0, 0.0), ["d1"])  # puts the lift 3 m off: seeing it decides
    active.validate([a, b])
    frame = SensorFrame(10.0, Pose2D(2.0, 2.0, 0.0))
    first = active.next_target(frame)
    # both go for the lift (1 in the BIM, 2 doors); b's viewpoint is nearer along the corridors
    assert first is not None and first.hypothesis is b
    assert first.viewpoint == pytest.approx([6.0 - 3.0, 5.0 - VIEW_DISTANCE], abs=0.11)
    assert first.route_m == pytest.approx(math.hypot(1.0, 1.2), abs=0.5)
    assert active.plan == [a] and len(active.visited) == 1
    assert active.target_started == 10.0 and active.target_budget > active.t_thre
    second = active.next_target(frame)
    assert second is not None and second.hypothesis is a
    assert second.viewpoint == pytest.approx([6.0, 5.0 - VIEW_DISTANCE], abs=0.11)
    assert second.route_m > first.route_m
    assert active.next_target(frame) is None and active.plan == []


def test_features_every_hypothesis_predicts_are_no_targets(config) -> None:
    active = _explorer(config)
    a = _hypothesis(1, Pose2D(0, 0, 0), ["d1"])
    b = _hypothesis(2, Pose2D(0.5, 0.0, 0.0), ["d1"])  # 0.5 m apart: both would see what the other sees
    active.validate([a, b])
    assert active.next_target(SensorFrame(0.0, Pose2D(2.0, 2.0, 0.0))) is None
    assert active.plan == [] and active.visited == []
    alone = _explorer(config)
    alone.validate([a])  # nothing to rule out: any unmatched feature will do
    target = alone.next_target(SensorFrame(0.0, Pose2D(2.0, 2.0, 0.0)))
    assert target is not None and target.viewpoint == pytest.approx([6.0, 5.0 - VIEW_DISTANCE], abs=0.11)


def test_validate_keeps_the_top_five(config) -> None:
    active = _explorer(config)
    hs = [_hypothesis(k, Pose2D(k, 0, 0), []) for k in range(1, 8)]
    active.validate(hs)
    assert [h.rank for h in active.plan] == [1, 2, 3, 4, 5] and len(active.plan_all) == 7


def test_give_up_reasons_and_exhaustion(config) -> None:
    active = _explorer(config)
    active.navigator = SimpleNamespace(waypoints=[np.array([5.0, 0.0])])
    active.target_started, active.target_budget = 0.0, 100.0
    active.progress = (0.0, math.inf)
    here = Pose2D(0.0, 0.0, 0.0)
    assert active.give_up(SensorFrame(1.0, here), 0.0) is None  # first progress measured
    assert active.give_up(SensorFrame(1.0 + STALL_S + 0.1, here), 0.0) == "no progress toward the target"
    active.progress = (20.0, math.inf)
    active.target_reached_t = 20.0
    assert active.give_up(SensorFrame(20.0 + LOOK_S / 2, here), 0.0) is None
    assert active.give_up(SensorFrame(20.0 + LOOK_S + 0.1, here), 0.0) == "target reached, nothing new"
    assert active.exhausted == (MAX_FRUITLESS <= 2)
    active.target_reached_t = None
    active.progress = (200.0, math.inf)
    assert active.give_up(SensorFrame(201.0, here), 0.0) == "time budget passed"
    assert active.fruitless == 3 and active.exhausted == (MAX_FRUITLESS <= 3)


def test_targets_beyond_max_route_give_way_to_nearer_categories(config) -> None:
    near = dataclasses.replace(config, exploration=dataclasses.replace(config.exploration, max_route=2.0))
    active = ActiveExploration(near, _site(), WallFollowParams())
    active.validate([_hypothesis(1, Pose2D(0, 0, 0), ["d1"])])
    target = active.next_target(SensorFrame(0.0, Pose2D(2.0, 2.0, 0.0)))
    # the lift (rarest) is about 4 m away along the room: the unmatched door d2 is looked at instead
    assert target is not None and target.viewpoint == pytest.approx([2.5, VIEW_DISTANCE], abs=0.11)
    assert target.route_m <= 2.0
    tight = dataclasses.replace(config, exploration=dataclasses.replace(config.exploration, max_route=0.1))
    none = ActiveExploration(tight, _site(), WallFollowParams())
    none.validate([_hypothesis(1, Pose2D(0, 0, 0), ["d1"])])
    assert none.next_target(SensorFrame(0.0, Pose2D(2.0, 2.0, 0.0))) is None
    # 0: no limit, the lift as before
    anywhere = _explorer(config)
    anywhere.validate([_hypothesis(1, Pose2D(0, 0, 0), ["d1"])])
    far = anywhere.next_target(SensorFrame(0.0, Pose2D(2.0, 2.0, 0.0)))
    assert far is not None and far.viewpoint == pytest.approx([6.0, 5.0 - VIEW_DISTANCE], abs=0.11)
