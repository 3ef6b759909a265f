"""initcli.session.runner: a Session on a scripted driver that sees nothing, ended by its limits."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from bimtools.site.load import Site
from initcli.config import load_config
from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
from initcli.core.geometry.se2 import Pose2D
from initcli.drivers.base import LaserScan, SensorFrame
from initcli.session.runner import Session
from tests.helpers import SAMPLES


class BlindDriver:
    """Unicycle odometry at 10 Hz, no images, an open-space scan (``scan``), the given ranges (the
    same at every pose: an endless corridor, say) or none; the truth is the odometry shifted by
    (10, 0)."""

    camera = DEFAULT_CAMERA
    mount = DEFAULT_MOUNT
    control_rate = 10.0
    depth_window = 2

    def __init__(self, scan: bool | np.ndarray = False) -> None:
        n = 360
        ranges = scan if isinstance(scan, np.ndarray) else np.full(n, 12.0)
        self.scan = LaserScan(-math.pi, 2 * math.pi / n, 12.0, ranges) if scan is not False else None
        self.t, self.pose, self._distance = 0.0, Pose2D(0.0, 0.0, 0.0), 0.0
        self.commands: list[tuple[float, float]] = []

    def _frame(self) -> SensorFrame:
        return SensorFrame(
            self.t, self.pose, self.scan, truth=Pose2D(self.pose.x + 10.0, self.pose.y, self.pose.yaw)
        )

    def start(self) -> SensorFrame:
        return self._frame()

    def step(self, v: float, w: float) -> SensorFrame:
        self.commands.append((v, w))
        dt = 1.0 / self.control_rate
        self.pose = self.pose * Pose2D(v * dt, 0.0, w * dt)
        self._distance += abs(v) * dt
        self.t = round(self.t + dt, 6)
        return self._frame()

    @property
    def distance(self) -> float:
        return self._distance


@pytest.fixture(scope="module")
def config():
    return load_config(SAMPLES / "block_a.site.yaml")


def _session(
    config, tmp_path: Path | None = None, observer=None, scan: bool | np.ndarray = False, **limits: float
) -> tuple[Session, BlindDriver]:
    config = dataclasses.replace(config, limits=dataclasses.replace(config.limits, **limits))
    driver = BlindDriver(scan)
    log = tmp_path / "session.jsonl" if tmp_path is not None else None
    site = Site(SAMPLES, {})
    return Session(config, site, None, driver, log, np.random.default_rng(0), observer), driver


def test_time_limit_ends_the_session_with_its_reason_and_paths(config, tmp_path: Path) -> None:
    seen: list[dict] = []
    session, driver = _session(config, tmp_path, seen.append, max_time=2.0)
    result = session.run()
    assert not result.success
    assert result.reason == "no unique match within 2 s"
    assert result.duration_s == pytest.approx(2.1)
    assert len(result.odom_path) == len(driver.commands) + 1 == 22
    assert result.true_path[0] == (10.0, 0.0, 0.0)
    assert result.truth_pose == Pose2D(driver.pose.x + 10.0, driver.pose.y, driver.pose.yaw)
    assert result.features_detected == 0 and result.features == []
    assert result.states[-1] == (pytest.approx(2.1), "failed")
    if config.exploration.initial_look:
        assert result.states[0][1] == "look"
        assert all(v == 0.0 and w != 0.0 for v, w in driver.commands[:5])  # turning on the spot
    assert result.wall_seconds > 0.0
    assert len(seen) == 21 and {"t", "state", "distance", "features", "hypotheses"} <= seen[0].keys()
    records = [json.loads(line) for line in (tmp_path / "session.jsonl").read_text().splitlines()]
    assert records[0]["type"] == "meta"
    states = [r for r in records if r["type"] == "state"]
    assert states[-1]["state"] == "failed" and states[-1]["reason"] == result.reason
    assert sum(r["type"] == "odom" for r in records) >= 2


def test_distance_limit_is_measured_on_odometry(config) -> None:
    no_look = dataclasses.replace(
        config, exploration=dataclasses.replace(config.exploration, initial_look=False)
    )
    session, driver = _session(no_look, scan=True, max_distance=1.0, max_time=60.0)
    result = session.run()
    assert result.reason.startswith("moved 1 m without a unique match (0 features, 0 hypotheses)")
    assert session.perception.travel > 1.0
    assert result.distance_total_m == pytest.approx(driver.distance)
    assert result.duration_s < 60.0


def test_a_start_that_cannot_leave_fails_before_moving(config) -> None:
    session, driver = _session(config)
    session.cannot_leave = "cannot leave: closed in"
    result = session.run()
    assert result.reason == "cannot leave: closed in" and driver.commands == []
    assert result.duration_s == 0.0 and result.distance_total_m == 0.0
    assert math.isclose(result.truth_pose.x, 10.0)


def test_an_unresolved_storey_is_named_in_the_reason(config) -> None:
    """storey: auto with hypotheses left on two storeys: the failure says which storeys remain."""
    session, driver = _session(config, max_distance=1.0)
    session.perception.travel = 1.5  # past the limit, with what a match step left behind
    session.hypotheses, session.storeys_left = 2, ["Level 1", "Level 2"]
    assert session._out_of_limits(driver.start())
    assert session.result.reason == (
        "moved 1 m without a unique match (0 features, 2 hypotheses on storeys Level 1, Level 2: "
        "the storey is not resolved)"
    )
    session.storeys_left = ["Level 1"]
    assert session._out_of_limits(driver.start())
    assert session.result.reason == "moved 1 m without a unique match (0 features, 2 hypotheses)"


def test_the_initial_look_turns_all_the_way_round_before_exploring(tmp_path: Path) -> None:
    """block_a, seed 69: two doors are confirmed 2 s into the look, with 8 hypotheses. The look goes
    on (what is behind the robot costs no distance) and the features seen on the rest of the turn
    make the match unique on the spot; ending the look at the first ambiguous match drove 14 m."""
    from initcli.config.building import prepare_site
    from initcli.session.simulated import sim_session

    config = load_config(SAMPLES / "block_a.site.yaml")
    built = sim_session(config, prepare_site(config, tmp_path / "site"), 69)
    result = built.session.run()
    assert result.success, result.reason
    assert [s for _, s in result.states[:2]] == ["look", "coarse"]
    assert result.distance_total_m < 2.0
    assert result.pose is not None and result.pose.distance_to(result.truth_pose) < 0.5


def corridor_ranges(left: float, right: float, n: int = 360, max_range: float = 12.0) -> np.ndarray:
    """A scan between two endless walls along the robot's heading, ``left`` and ``right`` m away."""
    angles = -math.pi + 2 * math.pi / n * np.arange(n)
    sin = np.sin(angles)
    with np.errstate(divide="ignore"):
        to_wall = np.where(sin > 0, left / sin, np.where(sin < 0, right / -sin, np.inf))
    return np.minimum(to_wall, max_range)


@pytest.mark.parametrize(
    ("right", "look_every", "looks"),
    [(None, 10.0, 2), (1.3, 10.0, 0), (None, 0.0, 0)],  # open beside the wall, a corridor, off
)
def test_looks_again_along_a_wall_with_open_space_beside_it(config, right, look_every, looks) -> None:
    """Following the left wall with nothing within 3 m on the right (a hall, a car park) and no
    feature: every ``exploration.look_every`` m of travel the robot turns once on the spot, then
    follows the wall on; in a corridor, or with looks off, it drives on."""
    exploration = dataclasses.replace(
        config.exploration, initial_look=False, look_every=look_every, cross_after=0
    )
    ranges = corridor_ranges(0.7, 50.0 if right is None else right)
    session, driver = _session(
        dataclasses.replace(config, exploration=exploration), scan=ranges, max_distance=25.0, max_time=600.0
    )
    result = session.run()
    assert result.reason.startswith("moved 25 m without a unique match")
    assert [s for _, s in result.states].count("look") == looks
    turned_on_the_spot = sum(abs(w) * 0.1 for v, w in driver.commands if v == 0.0)
    assert turned_on_the_spot == pytest.approx(looks * 2 * math.pi, abs=0.2)


@pytest.mark.parametrize(
    ("right", "cross", "crossings", "looks"), [(11.0, True, 1, 1), (11.0, False, 0, 2), (1.3, True, 0, 0)]
)
def test_crosses_the_open_floor_after_a_look_there(config, right, cross, crossings, looks) -> None:
    """After the look on an open floor (the far side 11 m to the right of the followed wall) the
    robot turns square across and drives over (the scan is the same in the robot's frame
    everywhere, so it follows the wall on in that direction). Off, it drives on along the wall and
    looks again 10 m on; in a corridor it neither looks nor crosses."""
    exploration = dataclasses.replace(
        config.exploration, initial_look=False, look_every=10.0, cross_after=1 if cross else 0
    )
    session, driver = _session(
        dataclasses.replace(config, exploration=exploration),
        scan=corridor_ranges(0.7, right),
        max_distance=21.0,
        max_time=600.0,
    )
    result = session.run()
    assert result.crossings == crossings
    assert [s for _, s in result.states].count("look") == looks  # the next look 10 m after the crossing
    if crossings:
        assert driver.pose.x == pytest.approx(10.0, abs=0.7) and driver.pose.y == pytest.approx(
            -11.0, abs=0.7
        )
    else:
        assert abs(driver.pose.y) < 1.5 and driver.pose.x > 20.0  # along the wall (a look ends a little over)


@pytest.mark.parametrize("lost_stages", [1, 2])
def test_a_failed_fine_stage_explores_on_and_fine_tunes_the_next_claim(
    tmp_path: Path, monkeypatch, lost_stages
) -> None:
    """The filter loses the robot in the first fine stage (hoardings hiding the walls, say): the
    claim is dropped, exploration goes on, the match is claimed again and fine-tuned from there.
    When the second stage fails too (FINE_TRIES), the session fails with the filter's reason."""
    from initcli.config.building import prepare_site
    from initcli.config.session import FineTuningSection
    from initcli.session import fine_tuning
    from initcli.session.simulated import sim_session

    FINE_TRIES = FineTuningSection().tries  # fine_tuning.tries' default
    assert FINE_TRIES == 2
    real_run = fine_tuning.FineTuning.run
    stages: list[float] = []

    def failing_first(self, driver, frame, *args, **kwargs):
        stages.append(driver.distance)
        if len(stages) <= lost_stages:
            for _ in range(30):  # the filter follows the wall for 3 s, then loses the robot
                frame = driver.step(0.3, 0.0)
            return fine_tuning.FineLost(frame, "lost during fine tuning (forced by the test)")
        return real_run(self, driver, frame, *args, **kwargs)

    monkeypatch.setattr(fine_tuning.FineTuning, "run", failing_first)
    config = load_config(SAMPLES / "block_a.site.yaml")
    result = sim_session(config, prepare_site(config, tmp_path / "site"), 3).session.run()
    assert len(stages) == 2 and stages[1] > stages[0] + 0.9  # claimed again after driving on from there
    assert [s for _, s in result.states].count("coarse") == 2
    if lost_stages == 1:
        assert result.success, result.reason
        assert result.pose is not None and result.pose.distance_to(result.truth_pose) < 0.5
    else:
        assert not result.success and result.reason == "lost during fine tuning (forced by the test)"


@pytest.mark.parametrize(("feature_walls", "crossings"), [(True, 1), (False, 0)])
def test_crosses_to_the_wall_where_the_hypotheses_put_an_unseen_door(
    config, feature_walls, crossings
) -> None:
    """A hall whose far wall is 11 m to the right of the followed one, one hypothesis (its transform
    turned 2 rad) whose storey holds a door on that wall, facing the robot, not yet seen. After the
    first look on the open floor the robot crosses to it (exploration.feature_walls), long before
    cross_after (6) fruitless looks would send it over; off, it drives on along its wall."""
    from bimtools.site.load import StoreyModel
    from bimtools.site.records import Feature
    from initcli.match.pipeline import Hypothesis

    theta = 2.0
    transform = Pose2D(3.0, -4.0, theta)  # odom -> BIM
    door_xy = transform.apply(np.array([10.0, -11.0]))  # on the far wall, beside the first look
    normal = (-math.sin(theta), math.cos(theta))  # (0, 1) in odom: toward the followed wall
    door = Feature("door", "Door", float(door_xy[0]), float(door_xy[1]), *normal, 0.9, 2.1)
    exploration = dataclasses.replace(
        config.exploration, initial_look=False, look_every=10.0, feature_walls=feature_walls
    )
    session, driver = _session(
        dataclasses.replace(config, exploration=exploration),
        scan=corridor_ranges(0.7, 11.0),
        max_distance=21.0,
        max_time=600.0,
    )
    session.site = Site(SAMPLES, {"hall": StoreyModel("hall", 0.0, [door])})
    pose = Pose2D(0.0, 0.0, 0.0)
    session.last_hypotheses = [Hypothesis(0, "hall", (), [], 0, 0.0, pose, None, transform, 1.0, 1)]
    result = session.run()
    assert exploration.cross_after > 1 and result.crossings == crossings
    if crossings:
        assert driver.pose.y == pytest.approx(-11.0, abs=1.0)  # over at the door's wall
    else:
        assert abs(driver.pose.y) < 1.5 and driver.pose.x > 20.0


@pytest.mark.parametrize("long_walls", [True, False])
def test_long_walls_reaches_the_escapes(config, long_walls) -> None:
    """exploration.long_walls as the config says (true by default): the escapes the session is
    assembled with head out of a circle round a column to the nearest long wall, or not."""
    from initcli.session.assembly import assemble
    from tests.initcli.session.test_escapes import ALL_OVER_THE_HALL, COLUMN, HALL, ROUND_THE_COLUMN, lap_in

    assert config.exploration.long_walls  # the default
    exploration = dataclasses.replace(config.exploration, long_walls=long_walls)
    config = dataclasses.replace(config, exploration=exploration)
    parts = assemble(config, Site(SAMPLES, {}), None, BlindDriver(), None, np.random.default_rng(0), "test")
    why, result = lap_in(parts.escapes, parts.result, HALL + COLUMN, ROUND_THE_COLUMN, ALL_OVER_THE_HALL)
    to_the_wall = why == "a 6 m circle without a new feature: heading for the nearest long wall"
    assert to_the_wall is long_walls and result.crossings == int(long_walls)
