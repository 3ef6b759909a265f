"""The online decision making of §3.3.4 as a state machine, then rectification and fine tuning.

States: ``explore`` (random exploration by wall following) -> with >= 3 confirmed features,
match (Algorithm 1) after each new one -> ``unique``: coarse initialisation done ->
``rectify`` (Eq. 17) -> ``fine`` (particle filter, Eq. 18, while following the wall) -> done.
With several but fewer than m_thre hypotheses: ``active`` exploration toward the nearest feature
of the highest-priority category (fewest in the BIM) under the most probable hypothesis, with the
modified bug algorithm (Eq. 15-16); no new feature within t_thre -> ``recovery`` (rotate in place
to widen the view) -> still nothing -> ``explore``.

The session writes every record it acts on to its detection log, and decides by running the
same pipeline as ``bim-init match`` (:func:`initcli.match.pipeline.match_log`) on the log so far, so the
log replays to the same coarse verdict and pose.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bimtools.site.load import Site
from initcli.config import (
    SessionConfig,
    followed_side,
    match_options,
    turn_in_place_speed,
    wall_follow_params,
)
from initcli.core.bug_navigation import BugNavigator, BugParams, RouteNavigator
from initcli.core.classes import ClassMap
from initcli.core.detection_filter import ConfirmedFeature, Sighting, filter_detections, is_truncated
from initcli.core.geometry import Pose2D, wrap_angle
from initcli.core.grid_planner import PlanningGrid
from initcli.core.particle_filter import (
    FilterNoise,
    LaserModel,
    LikelihoodField,
    ParticleFilter,
    scan_fit,
)
from initcli.core.projection import detections_to_odom
from initcli.core.wall_following import MovingObstacleWait, ScanView, wall_follow
from initcli.drivers.base import RobotDriver, SensorFrame
from initcli.io.detection_log import (
    DetectionLog,
    Detections,
    HypothesesRecord,
    Meta,
    Odom,
    Record,
    Scan,
    State,
    Truth,
)
from initcli.match.pipeline import Hypothesis, MatchReport, match_log
from initcli.sim.robot import motion_delta

SCAN_LOG_EVERY = 5  # control steps between logged scans (2 Hz at 10 Hz control)
RECOVERY_TURN = 2 * math.pi  # rad turned in place by the recovery behaviour
PF_UPDATE_D = 0.25  # m (AMCL update_min_d)
PF_UPDATE_A = 0.2  # rad (AMCL update_min_a)
LOST_LIKELIHOOD = 0.12
VIEW_DISTANCE = 1.8  # m in front of a target feature where active exploration goes to look at it
ACTIVE_TOP = 5  # hypotheses (most probable first) whose targets active exploration validates
DISCRIMINATION_RADIUS = 1.5  # m: another hypothesis predicting a same-category feature this close agrees
VISITED_RADIUS = 2.0  # m: an active-exploration target this close to a visited one is skipped
STALL_S = 15.0  # s without getting closer to the route's next waypoint: the route is blocked
TRAVEL_CAP_S = 120.0  # s of travel allowed toward one target on top of t_thre
LANDMARKS = 4  # matched features that weight the particle filter's seed
LANDMARK_SIGMA = 0.3  # m: how far a matched feature may land from its BIM feature
LOOP_WINDOW_S = 45.0  # s of path checked for a loop (circling an island of clutter, a chicane)
LOOP_RADIUS = 2.5  # m: a path that long staying this close to its centre is a loop
LOOP_ESCAPE_S = 25.0  # s driving out of a loop toward open space
SHUTTLE_WINDOW_S = 150.0  # s of path checked for shuttling
SHUTTLE_LENGTH = 45.0  # m driven in that window ...
SHUTTLE_RADIUS = 8.0  # m ... without leaving a circle this size: follow the other wall
MIN_SCAN_FIT = 0.6  # fraction of beams on mapped walls at the final pose (0.76-0.99 when right)
DRIFTED_M, DRIFTED_DEG = 1.0, 20.0  # the filter moved this far from the carried rectified pose ...
KEEP_RECTIFIED_MARGIN = 0.1  # scan fit by which the carried rectified pose must beat the filter
RESEED_SIGMA_XY = 2.0  # m: the spread of a second try when the first settled on the wrong side
MAX_FRUITLESS = 3  # active-exploration targets in a row without a new feature -> random exploration


@dataclass
class MatchStep:
    """One matching step, for the report: time, features so far, hypotheses' current poses."""

    t: float
    features: int
    verdict: str
    poses: list[tuple[float, float, float]]


@dataclass
class SessionResult:
    success: bool
    reason: str
    storey: str | None
    pose: Pose2D | None = None
    covariance: np.ndarray | None = None
    coarse_pose: Pose2D | None = None
    rectified_pose: Pose2D | None = None
    features_detected: int = 0
    distance_coarse_m: float | None = None
    distance_total_m: float = 0.0
    duration_s: float = 0.0
    truth_pose: Pose2D | None = None
    truth_at_coarse: Pose2D | None = None
    matched_ids: list[str | None] = field(default_factory=list)
    transform: Pose2D | None = None  # odom -> BIM of the final estimate
    true_path: list[tuple[float, float, float]] = field(default_factory=list)
    odom_path: list[tuple[float, float, float]] = field(default_factory=list)
    features: list[ConfirmedFeature] = field(default_factory=list)
    match_steps: list[MatchStep] = field(default_factory=list)
    states: list[tuple[float, str]] = field(default_factory=list)
    active_explorations: int = 0
    loop_escapes: int = 0
    fine_converged: bool | None = None
    recoveries: int = 0
    wall_seconds: float = 0.0
    wall_seconds_coarse: float | None = None  # wall-clock seconds until the unique match

    def errors(self) -> tuple[dict[str, float | None], dict[str, float | None]]:
        """Translational (m) and rotational (deg) errors of the coarse, rectified and fine poses."""
        trans: dict[str, float | None] = {"coarse": None, "rectified": None, "fine": None}
        rot: dict[str, float | None] = {"coarse": None, "rectified": None, "fine": None}
        for key, pose, truth in (
            ("coarse", self.coarse_pose, self.truth_at_coarse),
            ("rectified", self.rectified_pose, self.truth_at_coarse),
            ("fine", self.pose if self.covariance is not None else None, self.truth_pose),
        ):
            if pose is not None and truth is not None:
                trans[key] = round(math.hypot(pose.x - truth.x, pose.y - truth.y), 4)
                rot[key] = round(math.degrees(abs(float(wrap_angle(pose.yaw - truth.yaw)))), 3)
        return trans, rot


Observer = Callable[[dict], None]


class Session:
    """One initialisation session on a driver, against a site model."""

    def __init__(
        self,
        config: SessionConfig,
        site: Site,
        storey: str | None,
        driver: RobotDriver,
        log_path: Path | None,
        rng: np.random.Generator,
        observer: Observer | None = None,
        meta_source: str = "bim-init run",
    ):
        self.config = config
        self.site = site
        self.storey = storey  # None: match against every storey
        self.driver = driver
        self.rng = rng
        self.observer = observer
        self.cmap = ClassMap(config.detector.classes)
        self.options = match_options(config, storey)
        self.meta = Meta(
            camera=driver.camera,
            camera_pose=driver.mount,
            depth_window=driver.depth_window,
            source=meta_source,
        )
        self.log = DetectionLog(path=log_path or Path("session.jsonl"), meta=self.meta, records=[], lines=[])
        self._log_file = open(log_path, "w", encoding="utf-8") if log_path else None  # noqa: SIM115
        self._write(self.meta, keep=False)
        self.side = followed_side(config)
        self.follow = wall_follow_params(config)
        self.loop_escape_until = -1.0
        self.waiting = MovingObstacleWait()
        self.sightings: list[Sighting] = []
        self.frames = 0
        self.confirmed: list[ConfirmedFeature] = []
        self.state = "explore"
        self.result = SessionResult(False, "", storey)
        self.detecting = True
        self.loops = ConfinementWatch(LOOP_WINDOW_S, 3 * LOOP_RADIUS * 2, LOOP_RADIUS)
        # Back and forth over the same few metres for minutes (a dead end behind a material stack
        # the followed wall leads around, targets that keep failing): a longer, wider loop.
        self.shuttles = ConfinementWatch(SHUTTLE_WINDOW_S, SHUTTLE_LENGTH, SHUTTLE_RADIUS)
        self.plan: list[Hypothesis] = []
        self.plan_all: list[Hypothesis] = []
        self.visited: list[np.ndarray] = []
        self.navigator: RouteNavigator | None = None
        self._planners: dict[str, PlanningGrid | None] = {}
        self.target_budget = config.exploration.t_thre
        self.target_started = 0.0
        self.target_reached_t: float | None = None
        self.progress: tuple[float, float] = (0.0, math.inf)
        self._started = time.perf_counter()
        self.fruitless = 0  # active-exploration targets in a row that brought no new feature

    # -- logging -------------------------------------------------------------------------------------

    def _write(self, record: Record, keep: bool = True) -> None:
        if keep:
            self.log.records.append(record)
            self.log.lines.append(len(self.log.records) + 1)
        if self._log_file is not None:
            from initcli.io.detection_log import format_record

            self._log_file.write(format_record(record) + "\n")

    def close(self) -> None:
        if self._log_file is not None:
            self._log_file.close()
            self._log_file = None

    def _set_state(self, t: float, state: str, **data: object) -> None:
        self.state = state
        self.result.states.append((t, state))
        self._write(State(round(t, 3), {"state": state, **data}))

    def _record_frame(self, frame: SensorFrame, step: int) -> None:
        t = round(frame.t, 3)
        self._write(Odom(t, frame.odom.x, frame.odom.y, frame.odom.yaw))
        if frame.truth is not None:
            self._write(Truth(t, frame.truth.x, frame.truth.y, frame.truth.yaw))
            self.result.true_path.append(frame.truth.as_tuple())
        self.result.odom_path.append(frame.odom.as_tuple())
        if frame.scan is not None and step % SCAN_LOG_EVERY == 0:
            s = frame.scan
            self._write(
                Scan(
                    t,
                    s.angle_min,
                    s.angle_increment,
                    s.range_max,
                    tuple(round(float(r), 3) for r in s.ranges),
                ),
                keep=False,
            )
        if frame.detections is not None and self.detecting:
            self._write(Detections(t, frame.odom, tuple(frame.detections)))
            self._add_sightings(t, frame.odom, frame.detections)

    def _add_sightings(self, t: float, odom: Pose2D, objects: list) -> None:
        """Eq. 1-2 for one image, exactly as :func:`initcli.match.pipeline.sightings_from_log` does."""
        frame = self.frames
        self.frames += 1
        objs = [o for o in objects if o.depth is not None and math.isfinite(o.depth)]
        if not objs:
            return
        pts = detections_to_odom(
            np.array([o.bbox for o in objs]),
            np.array([o.depth for o in objs]),
            self.meta.camera,
            self.meta.camera_pose,
            odom,
        )
        for o, p in zip(objs, pts, strict=True):
            self.sightings.append(
                Sighting(
                    t,
                    self.cmap.canonical(o.cls),
                    float(p[0]),
                    float(p[1]),
                    o.score,
                    float(o.depth),
                    frame,
                    truncated=is_truncated(o.bbox, self.meta.camera.width, self.options.edge_margin),
                )
            )

    # -- matching ------------------------------------------------------------------------------------

    def _new_features(self) -> bool:
        confirmed = filter_detections(self.sightings, self.options.filter_params()).features
        grew = len(confirmed) > len(self.confirmed)
        self.confirmed = confirmed
        return grew

    def _match(self, t: float) -> MatchReport:
        report = match_log(self.log, self.site, self.options, self.cmap)
        window = self.config.matching.drift_window
        if report.n_hypotheses == 0 and window > 0 and len(report.features) > self.options.min_inliers:
            # Odometry drift: the oldest features no longer fit; match the recent ones
            # (``bim-init match --drift-window`` replays this).
            recent = match_log(
                self.log, self.site, dataclasses.replace(self.options, drift_window=window), self.cmap
            )
            if recent.n_hypotheses > 0:
                report = recent
        self.result.match_steps.append(
            MatchStep(t, len(report.features), report.verdict, [h.pose.as_tuple() for h in report.hypotheses])
        )
        self._write(
            HypothesesRecord(
                round(t, 3),
                {
                    "verdict": report.verdict,
                    "count": report.n_hypotheses,
                    "features": len(report.features),
                    "storey": report.storey,
                    "hypotheses": [
                        {
                            "matches": h.matches,
                            "cost": round(h.cost, 4),
                            "storey": h.storey,
                            "pose": [round(v, 4) for v in h.pose.as_tuple()],
                        }
                        for h in report.hypotheses[:5]
                    ],
                },
            )
        )
        return report

    def _planner(self, storey: str) -> PlanningGrid | None:
        if storey not in self._planners:
            grid = self.site.storeys[storey].grid
            self._planners[storey] = (
                PlanningGrid.of(grid, self.config.robot.radius + 0.1) if grid is not None else None
            )
        return self._planners[storey]

    def _target(self, hypothesis: Hypothesis, odom: Pose2D) -> tuple[list[np.ndarray], float] | None:
        """A route (odom waypoints) to a viewpoint in front of the BIM feature of the highest-priority
        category (fewest in the BIM) that ``hypothesis`` has not matched yet, nearest along the
        BIM's corridors, not visited before; and its length."""
        features = self.site.storeys[hypothesis.storey].features
        counts: dict[str, int] = {}
        for f in features:
            counts[f.category] = counts.get(f.category, 0) + 1
        matched = {m for m in hypothesis.matches if m is not None}
        here = hypothesis.transform * odom
        planner = self._planner(hypothesis.storey)
        if planner is None:
            return None
        dist, pred, start = planner.distances_from(here.x, here.y)
        for category in sorted(counts, key=lambda c: (counts[c], c)):
            best: tuple[float, int, np.ndarray] | None = None
            for f in features:
                if f.category != category or f.id in matched:
                    continue
                view_bim = np.array([f.x + VIEW_DISTANCE * f.norm_x, f.y + VIEW_DISTANCE * f.norm_y])
                view = hypothesis.transform.apply_inverse(view_bim)
                if any(math.hypot(*(view - v)) <= VISITED_RADIUS for v in self.visited):
                    continue
                if not self._discriminates(hypothesis, f):
                    continue
                node = planner.node_at(*view_bim)
                if node >= 0 and math.isfinite(dist[node]) and (best is None or dist[node] < best[0]):
                    best = (float(dist[node]), node, view)
            if best is not None:
                self.visited.append(best[2])
                route = planner.path(pred, start, best[1])
                return [hypothesis.transform.apply_inverse(p) for p in route], best[0]
        return None

    def _discriminates(self, hypothesis: Hypothesis, feature) -> bool:
        """Would seeing ``feature`` where ``hypothesis`` puts it rule out some other hypothesis?

        Not when every other hypothesis also has a feature of that category there (a symmetric
        layout): the robot would see something either way and learn nothing.
        """
        others = [h for h in self.plan_all if h is not hypothesis]
        if not others:
            return True
        where = hypothesis.transform.apply_inverse(np.array([feature.x, feature.y]))  # odom frame
        for other in others:
            p = other.transform.apply(where)
            same = [
                g
                for g in self.site.storeys[other.storey].features
                if g.category == feature.category
                and math.hypot(g.x - p[0], g.y - p[1]) < DISCRIMINATION_RADIUS
            ]
            if not same:
                return True
        return False

    def _next_target(self, frame: SensorFrame) -> bool:
        """Start active exploration toward the next hypothesis' target; False when none is left.

        Targets of the remaining hypotheses are planned together and the nearest (along the BIM's
        corridors) is validated first: a wrong hypothesis whose target is close is cheap to refute,
        and the true one is confirmed as soon as its target feature is seen.
        """
        cfg = self.config
        options = []
        for hypothesis in self.plan:
            planned = self._target(hypothesis, frame.odom)
            if planned is not None:
                options.append((planned[1], hypothesis.rank, hypothesis, planned[0]))
        del self.visited[len(self.visited) - len(options) :]  # _target marked them; only the chosen one is
        if not options:
            self.plan = []
            return False
        length, rank, hypothesis, route = min(options, key=lambda o: (o[0], o[1]))
        self.plan = [h for h in self.plan if h is not hypothesis]
        self.visited.append(route[-1])
        self.navigator = RouteNavigator(route, BugParams(follow=self.follow))
        # t_thre to find something, plus the time to get there (capped: under a wrong hypothesis the
        # route may run into walls).
        self.target_budget = cfg.exploration.t_thre + min(1.5 * length / cfg.robot.max_linear, TRAVEL_CAP_S)
        self.target_started = frame.t
        self.target_reached_t = None
        self.progress = (frame.t, math.inf)
        self.result.active_explorations += 1
        self._set_state(
            frame.t,
            "active",
            target=[round(float(c), 3) for c in route[-1]],
            hypothesis=rank,
            route_m=round(length, 1),
            matches=hypothesis.matches,
        )
        return True

    def _stalled(self, frame: SensorFrame) -> bool:
        """No progress toward the route's current waypoint for STALL_S seconds."""
        assert self.navigator is not None
        if not self.navigator.waypoints:
            return False
        remaining = math.hypot(*(self.navigator.waypoints[0] - frame.odom.xy)) + 2.0 * len(
            self.navigator.waypoints
        )
        since, best = self.progress
        if remaining < best - 0.5:
            self.progress = (frame.t, remaining)
            return False
        return frame.t - since > STALL_S

    # -- the loop ------------------------------------------------------------------------------------

    def _emit(self, frame: SensorFrame, extra: dict | None = None) -> None:
        if self.observer is None:
            return
        self.observer(
            {
                "t": frame.t,
                "state": self.state,
                "distance": self.driver.distance,
                "features": len(self.confirmed),
                "hypotheses": self._last_count,
                **(extra or {}),
            }
        )

    def run(self) -> SessionResult:
        self._started = time.perf_counter()
        try:
            self._run()
        finally:
            self.result.wall_seconds = time.perf_counter() - self._started
            self.close()
        return self.result

    def _run(self) -> None:
        cfg = self.config
        limits = cfg.limits
        frame = self.driver.start()
        step = 0
        self._record_frame(frame, step)
        if cfg.exploration.initial_look:
            # Turn once on the spot first: features behind the robot cost no distance (§3.3.4's
            # recovery rotation, done before the first metre).
            self._set_state(frame.t, "look")
        else:
            self._set_state(frame.t, "explore")
        self._last_count = 0
        escape: BugNavigator | None = None
        last_feature_t = frame.t
        turned = 0.0
        report: MatchReport | None = None
        while True:
            scan = (
                ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
                if frame.scan
                else None
            )
            # Decide the command for this period.
            if self.state == "explore":
                if escape is not None and frame.t < self.loop_escape_until:
                    v, w, arrived = escape.step(frame.odom, scan)
                    if arrived:
                        escape = None
                elif self.waiting.hold(frame.t, scan.front(), self.follow.front_stop):
                    v, w = 0.0, 0.0
                else:
                    v, w = wall_follow(scan, self.side, self.follow)
                if self._looping(frame):
                    # Circling between obstacles: drive out along the most open direction, then resume.
                    escape = BugNavigator(self._open_point(frame, scan), BugParams(follow=self.follow))
                    self.loop_escape_until = frame.t + LOOP_ESCAPE_S
                    self.result.loop_escapes += 1
                    self._write(State(round(frame.t, 3), {"state": "explore", "why": "loop escape"}))
            elif self.state == "active":
                assert self.navigator is not None
                if self.waiting.hold(frame.t, scan.front(), self.follow.front_stop):
                    v, w, arrived = 0.0, 0.0, False
                else:
                    v, w, arrived = self.navigator.step(frame.odom, scan)
                if arrived and self.target_reached_t is None:
                    self.target_reached_t = frame.t
                since = max(last_feature_t, self.target_started)
                reached_and_looked = (
                    self.target_reached_t is not None and frame.t - self.target_reached_t > 2.0
                )
                stalled = self.target_reached_t is None and self._stalled(frame)
                if reached_and_looked or stalled or frame.t - since > self.target_budget:
                    self.fruitless += 1
                    why = (
                        "target reached, nothing new"
                        if reached_and_looked
                        else "no progress toward the target"
                        if stalled
                        else "time budget passed"
                    )
                    if cfg.exploration.recovery:
                        self._set_state(frame.t, "recovery", why=why)
                        self.result.recoveries += 1
                        turned = 0.0
                    elif self.fruitless >= MAX_FRUITLESS or not self._next_target(frame):
                        self._set_state(frame.t, "explore", why=why)
                    v, w = 0.0, 0.0
            elif self.state == "look":
                v, w = 0.0, turn_in_place_speed(cfg)
                if turned >= RECOVERY_TURN:
                    self._set_state(frame.t, "explore", why="initial look done")
            elif self.state == "recovery":
                v, w = 0.0, turn_in_place_speed(cfg)
                if turned >= RECOVERY_TURN:
                    if self.fruitless >= MAX_FRUITLESS:
                        # Targets keep failing (blocked routes, a symmetric layout): wall following
                        # covers new ground until a new feature changes the hypotheses (§3.3.4).
                        self._set_state(
                            frame.t, "explore", why=f"{self.fruitless} targets in a row brought nothing new"
                        )
                    elif not self._next_target(frame):
                        self._set_state(frame.t, "explore", why="nothing detected after recovery")
            else:
                raise RuntimeError(f"unexpected state {self.state}")

            previous = frame.odom
            frame = self.driver.step(v, w)
            step += 1
            turned += abs(float(wrap_angle(frame.odom.yaw - previous.yaw)))
            self._record_frame(frame, step)

            if frame.detections is not None and self._new_features():
                last_feature_t = frame.t
                self.fruitless = 0
                self.result.features_detected = len(self.confirmed)
                if len(self.confirmed) >= self.options.min_inliers:
                    report = self._match(frame.t)
                    self._last_count = report.n_hypotheses
                    if report.n_hypotheses == 1:
                        self._coarse_done(frame, report)
                        return
                    if 1 < report.n_hypotheses < cfg.matching.m_thre:
                        # Validate the most probable hypothesis first, then the next ones (§3.3.3).
                        self.plan = list(report.hypotheses[:ACTIVE_TOP])
                        self.plan_all = list(report.hypotheses)
                        if not self._next_target(frame) and self.state != "explore":
                            self._set_state(frame.t, "explore", why="no target left to validate")
                    elif self.state != "explore":
                        self._set_state(frame.t, "explore", why=report.verdict)
                elif self.state == "recovery":
                    self._set_state(frame.t, "explore", why="new feature")
            self._emit(frame)
            if self.shuttles.confined(frame):
                self.side = -self.side
                self.navigator = None
                self._set_state(
                    frame.t,
                    "explore",
                    why="shuttling over the same ground; following the "
                    + ("left" if self.side > 0 else "right")
                    + " wall",
                )
            if self.driver.distance > limits.max_distance:
                self._fail(
                    frame,
                    f"moved {limits.max_distance:g} m without a unique match "
                    f"({len(self.confirmed)} features, {self._last_count} hypotheses)",
                )
                return
            if frame.t > limits.max_time:
                self._fail(frame, f"no unique match within {limits.max_time:g} s")
                return

    @staticmethod
    def _open_point(frame: SensorFrame, scan: ScanView) -> np.ndarray:
        """An odom point 8 m (or 1 m short of the obstacle) along the longest free beam."""
        if scan is None or len(scan.ranges) == 0:
            return frame.odom.apply(np.array([2.0, 0.0]))
        i = int(np.argmax(scan.ranges))
        reach = min(8.0, float(scan.ranges[i]) - 1.0)
        return frame.odom.apply(reach * np.array([math.cos(scan.angles[i]), math.sin(scan.angles[i])]))

    def _looping(self, frame: SensorFrame) -> bool:
        """Has the robot driven a long way in the last LOOP_WINDOW_S while staying in a small area?"""
        return frame.t >= self.loop_escape_until and self.loops.confined(frame)

    def _fail(self, frame: SensorFrame, reason: str) -> None:
        self._set_state(frame.t, "failed", reason=reason)
        r = self.result
        r.success, r.reason = False, reason
        r.distance_total_m = self.driver.distance
        r.duration_s = frame.t
        r.truth_pose = frame.truth
        r.features = list(self.confirmed)

    def _coarse_done(self, frame: SensorFrame, report: MatchReport) -> None:
        cfg = self.config
        best = report.hypotheses[0]
        r = self.result
        r.storey = best.storey
        r.coarse_pose = best.pose
        r.rectified_pose = best.rectified_pose or best.pose
        r.truth_at_coarse = frame.truth
        r.distance_coarse_m = round(self.driver.distance, 3)
        r.wall_seconds_coarse = time.perf_counter() - self._started
        r.matched_ids = list(best.matches)
        r.features = list(report.features)  # the ones matched (a drift window may leave old ones out)
        r.transform = r.rectified_pose * frame.odom.inverse()
        self.detecting = False  # the log ends its detections here: it replays to this verdict
        self._set_state(
            frame.t,
            "coarse",
            verdict=report.verdict,
            pose=[round(v, 4) for v in best.pose.as_tuple()],
            rectified_pose=[round(v, 4) for v in r.rectified_pose.as_tuple()],
            matches=best.matches,
        )
        pose, cov = r.rectified_pose, None
        if cfg.fine_tuning.enabled and self.site.storeys[best.storey].grid is not None:
            outcome = self._fine_tune(frame, r.rectified_pose, best.storey)
            if outcome is None:
                return
            frame, pose, cov = outcome
        else:
            pose = r.transform * frame.odom
        r.success = True
        if cov is None:
            r.reason = "initialised (no fine tuning)"
        elif r.fine_converged:
            r.reason = "initialised"
        else:
            r.reason = (
                "initialised (fine tuning stopped at its distance limit above the covariance threshold)"
            )
        r.pose, r.covariance = pose, cov
        r.transform = pose * frame.odom.inverse()
        r.truth_pose = frame.truth
        r.distance_total_m = round(self.driver.distance, 3)
        r.duration_s = round(frame.t, 2)
        self._set_state(frame.t, "done", pose=[round(v, 4) for v in pose.as_tuple()])

    def _matched_pairs(self, storey: str) -> tuple[np.ndarray, np.ndarray]:
        """(odom positions, BIM positions) of the confirmed features the coarse match matched."""
        by_id = {f.id: f for f in self.site.storeys[storey].features}
        pairs = [
            (f.xy, (by_id[m].x, by_id[m].y))
            for f, m in zip(self.result.features, self.result.matched_ids, strict=False)
            if m in by_id
        ]
        if not pairs:
            return np.zeros((0, 2)), np.zeros((0, 2))
        return np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs], dtype=float)

    def _fine_tune(
        self, frame: SensorFrame, seed: Pose2D, storey: str
    ) -> tuple[SensorFrame, Pose2D, np.ndarray] | None:
        """Eq. 18: track with a particle filter seeded at the rectified pose while following the wall."""
        cfg = self.config.fine_tuning
        grid = self.site.storeys[storey].grid
        assert grid is not None
        self._set_state(frame.t, "fine")
        pf = ParticleFilter(LikelihoodField(grid), cfg.particles, FilterNoise(), LaserModel(), self.rng)
        pf.seed(seed, cfg.seed_sigma_xy, math.radians(cfg.seed_sigma_yaw))
        odom_xy, bim_xy = self._matched_pairs(storey)
        pf.weight_by_landmarks(frame.odom, odom_xy[-LANDMARKS:], bim_xy[-LANDMARKS:], LANDMARK_SIGMA)
        start_distance = self.driver.distance
        reseeded = False
        last_update = frame.odom
        lost = 0
        step = 0
        converged_at: float | None = None
        while True:
            scan = (
                ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
                if frame.scan
                else None
            )
            v, w = wall_follow(scan, self.side, self.follow) if scan is not None else (0.0, 0.0)
            frame = self.driver.step(v, w)
            step += 1
            self._record_frame(frame, step)
            moved = motion_delta(last_update, frame.odom)
            if abs(moved[1]) >= PF_UPDATE_D or abs(moved[0] + moved[2]) >= PF_UPDATE_A:
                pf.predict(moved)
                last_update = frame.odom
                pf.update(frame.scan.angles, frame.scan.ranges, frame.scan.range_max)
                lost = lost + 1 if pf.last_likelihood < LOST_LIKELIHOOD else 0
                estimate = pf.estimate()
                cov = estimate.covariance
                self._emit(frame, {"covariance": float(max(cov[0, 0], cov[1, 1]))})
                if lost >= 5:
                    self._fail(frame, "lost during fine tuning (laser scans do not fit the map)")
                    return None
                travelled = self.driver.distance - start_distance
                if (
                    cov[0, 0] < cfg.covariance
                    and cov[1, 1] < cfg.covariance
                    and cov[2, 2] < cfg.yaw_covariance
                    and travelled >= 1.0
                ):
                    converged_at = frame.t
                if converged_at is not None or travelled >= cfg.distance:
                    scan_args = (frame.scan.angles, frame.scan.ranges, frame.scan.range_max, pf.field)
                    fit = scan_fit(estimate.pose, *scan_args)
                    # The rectified pose carried along by odometry is the other candidate: a filter
                    # that drifted off a good coarse result fits the scan worse than it does.
                    assert self.result.transform is not None
                    carried = self.result.transform * frame.odom
                    carried_fit = scan_fit(carried, *scan_args)
                    apart = estimate.pose.distance_to(carried) > DRIFTED_M or abs(
                        float(wrap_angle(estimate.pose.yaw - carried.yaw))
                    ) > math.radians(DRIFTED_DEG)
                    if apart and carried_fit >= max(fit + KEEP_RECTIFIED_MARGIN, MIN_SCAN_FIT):
                        self._write(
                            State(
                                round(frame.t, 3),
                                {
                                    "state": "fine",
                                    "why": f"filter drifted (scan fit {fit:.0%}); rectified pose kept "
                                    f"({carried_fit:.0%})",
                                },
                            )
                        )
                        self.result.fine_converged = False
                        return frame, carried, cov
                    if fit < MIN_SCAN_FIT:
                        if reseeded:
                            self._fail(
                                frame, f"lost during fine tuning (only {fit:.0%} of the scan fits the map)"
                            )
                            return None
                        # The cloud settled where only the beams it kept agree (the far side of a
                        # wall, say): spread it wider around the estimate and track again.
                        reseeded = True
                        self._write(
                            State(
                                round(frame.t, 3), {"state": "fine", "why": f"scan fit {fit:.0%}, reseeded"}
                            )
                        )
                        pf.seed(estimate.pose, RESEED_SIGMA_XY, math.radians(cfg.seed_sigma_yaw))
                        start_distance, converged_at = self.driver.distance, None
                        continue
                    self.result.fine_converged = converged_at is not None
                    return frame, estimate.pose, cov


@dataclass
class ConfinementWatch:
    """:func:`confined` once a second over the robot's recent path (a loop round clutter,
    shuttling in a dead end); the trace starts afresh after each detection."""

    window_s: float
    length: float
    radius: float
    trace: list[tuple[float, float, float]] = field(default_factory=list)
    checked: float = -1.0

    def confined(self, frame: SensorFrame) -> bool:
        if frame.t - self.checked < 1.0:
            return False
        self.checked = frame.t
        if confined(self.trace, frame, self.window_s, self.length, self.radius):
            self.trace.clear()
            return True
        return False


def confined(
    trace: list[tuple[float, float, float]], frame: SensorFrame, window_s: float, length: float, radius: float
) -> bool:
    """Append the frame's odom position to ``trace`` (kept ``window_s`` long) and tell whether the
    path over a full window is longer than ``length`` yet stays within ``radius`` of its centre."""
    trace.append((frame.t, frame.odom.x, frame.odom.y))
    while trace and trace[0][0] < frame.t - window_s:
        trace.pop(0)
    if len(trace) < 2 or trace[-1][0] - trace[0][0] < 0.9 * window_s:
        return False
    xy = np.array([(x, y) for _, x, y in trace])
    travelled = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    spread = float(np.hypot(*(xy - xy.mean(axis=0)).T).max())
    return travelled > length and spread < radius
