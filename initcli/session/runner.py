"""The online decision making of §3.3.4 as a state machine, then rectification and fine tuning.

States: ``explore`` (random exploration by wall following) -> with >= 3 confirmed features,
match (Algorithm 1) after each new one -> ``unique``: coarse initialisation done ->
``rectify`` (Eq. 17) -> ``fine`` (particle filter, Eq. 18, while following the wall) -> done.
With ``exploration.active`` (off by default: in the site as built wall following initialised
more sessions) and several but fewer than m_thre hypotheses: ``active`` exploration toward the
nearest feature of the highest-priority category (fewest in the BIM) under the most probable
hypothesis, with the modified bug algorithm (Eq. 15-16); no new feature within t_thre ->
``recovery`` (rotate in place to widen the view) -> still nothing -> ``explore``.

Each step lives in its own module: what the robot sees and logs in :mod:`.perception`, active
exploration in :mod:`.exploration`, fine tuning in :mod:`.fine_tuning`, the outcome in
:mod:`.result`. The session writes every record it acts on to its detection log, and decides by
running the same pipeline as ``bim-init match`` (:func:`initcli.match.pipeline.match_log`) on the
log so far, so the log replays to the same coarse verdict and pose.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bimtools.site.load import Site
from initcli.config import (
    SessionConfig,
    followed_side,
    match_options,
    turn_in_place_speed,
    verification_params,
    wall_follow_params,
)
from initcli.core.bug_navigation import BugNavigator, BugParams, RouteNavigator, cross_floor
from initcli.core.classes import ClassMap
from initcli.core.confinement import ConfinementWatch
from initcli.core.frontier import LocalMap
from initcli.core.geometry import Pose2D, wrap_angle
from initcli.core.verification import (
    TRACK_HYPOTHESES,
    CameraView,
    Verification,
    outranks,
    rival_search,
    track_favoured,
    track_outranks,
    trails,
)
from initcli.core.wall_following import MovingObstacleWait, ScanView, open_beside, wall_follow
from initcli.drivers.base import RobotDriver, SensorFrame
from initcli.io.detection_log import Meta, State
from initcli.match.pipeline import Hypothesis, MatchReport
from initcli.match.verify import StoreyEvidence, track_transform, verify_transform
from initcli.session.exploration import ActiveExploration
from initcli.session.fine_tuning import FineLost, FineTuning, FineTuningHooks, matched_pairs
from initcli.session.perception import Perception
from initcli.session.result import CoarseClaim, MatchStep, SessionResult

__all__ = ["Observer", "Session"]

RECOVERY_TURN = 2 * math.pi  # rad turned in place by the initial look and the recovery behaviour
LOOP_WINDOW_S = 45.0  # s of path checked for a loop (circling an island of clutter, a chicane)
LOOP_RADIUS = 2.5  # m: a path that long staying this close to its centre is a loop
LOOP_LENGTH = 8.0  # m driven in the window (a robot arcing at 0.3 m/s on a 0.7 m radius drives 12 m)
LOOP_ESCAPE_S = 25.0  # s driving out of a loop toward open space
OPEN_REACH = 8.0  # m along the longest free beam to the point a loop escape heads for ...
OPEN_SHORT = 1.0  # m ... or this much short of the obstacle that beam hit
BLIND_REACH = 2.0  # m straight ahead when there is no scan to pick a free beam from
SHUTTLE_WINDOW_S = 150.0  # s of path checked for shuttling
SHUTTLE_LENGTH = 30.0  # m driven in that window (0.2 m/s on average) ...
SHUTTLE_RADIUS = 8.0  # m ... without leaving a circle this size: follow the other wall
FRONTIER_SCAN_EVERY = 10  # control steps between scans written into the local frontier map (1 Hz) ...
FRONTIER_BEAM_STEP = 2  # ... every second beam of them
# Doors built off their place can push the true place past Eq. 8's distance tolerance while a
# turned place of a nearly symmetric lobby fits within it: a claim must stay unique with alpha this
# many times wider too (ntu_hallway, doors shifted sigma 0.6 m: a 177-degree-off claim on 5 features).
RIVAL_ALPHA_FACTOR = 1.5
RIVAL_ALPHA_MAX_INLIERS = 6  # ... for a claim on this many matched features or fewer (more: alpha as is)
DOUBT_WINDOW_M = 10.0  # m after a claim held back by credible rivals in which claims get the wide search
RIVAL_SEARCH_FACTOR = 2.0  # a rival's scan fit may shift it this many times farther than a claim's
RIVALS_CHECKED = 8  # rivals of a claim verified one by one; more count as credible without a check ...
RIVALS_COMPARED = 64  # ... unless the claim outranks them all, compared one by one up to this many
REDECIDE_M = 10.0  # m of travel after which hypotheses left undecided are matched and judged again
FINE_TRIES = 2  # final-pose checks a session may fail: after a failed one it explores on and claims again
AGREE_M = 2.0  # m: a fine pose farther than this from the odometry-carried coarse pose disagrees ...
AGREE_DEG = 30.0  # ... or turned more than this

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
        self.options = match_options(config, storey)
        meta = Meta(
            camera=driver.camera,
            camera_pose=driver.mount,
            depth_window=driver.depth_window,
            source=meta_source,
        )
        self.perception = Perception(
            meta, log_path, ClassMap(config.detector.classes), self.options, config.matching.drift_window
        )
        self.side = followed_side(config)
        self.follow = wall_follow_params(config)
        self.waiting = MovingObstacleWait()
        self.state = "explore"
        self.result = SessionResult(False, "", storey)
        self.exploration = ActiveExploration(config, site, self.follow)
        self.loops = ConfinementWatch(LOOP_WINDOW_S, LOOP_LENGTH, LOOP_RADIUS)
        # Back and forth over the same few metres for minutes (a dead end behind a material stack
        # the followed wall leads around, targets that keep failing): a longer, wider loop.
        self.shuttles = ConfinementWatch(SHUTTLE_WINDOW_S, SHUTTLE_LENGTH, SHUTTLE_RADIUS)
        self.escape: BugNavigator | RouteNavigator | None = None  # driving out of a loop
        self.local_map = LocalMap()  # what the lidar has seen, for frontier-guided loop escapes
        self.loop_escape_until = -1.0  # s
        self.last_feature_t = 0.0  # s: when the last new feature was confirmed
        self.turned = 0.0  # rad turned since the look or recovery rotation began
        self.look_from = 0.0  # m of odometry travel at the last look or new feature
        self.looks = 0  # looks begun (the initial one included)
        self.open_floor_look = False  # the look under way is one on an open floor, not the initial one
        self.fruitless_looks = 0  # looks on an open floor ended since the last new feature or crossing
        self.hypotheses = 0  # of the last match step
        self.decided_at = 0.0  # m of travel at the last match step
        self.storeys_left: list[str] = []  # storeys the last match step's hypotheses lie on
        self.checks = verification_params(config)
        # m of travel when a claim was last held back by rivals that pass the checks: claims soon
        # after get the wide rival search, however many features they have
        self.doubted_at: float | None = None
        self.view = CameraView(driver.camera, driver.mount, self.options.min_depth)
        self._evidence: dict[str, StoreyEvidence] = {}
        self.cannot_leave: str | None = None  # set when the start is known to be closed in
        self.fine_failures = 0  # fine stages that failed
        self.fine_failed_why = ""  # why the last one failed
        self.resume_from: SensorFrame | None = None  # the last frame of a fine stage that failed
        self._started = time.perf_counter()

    # -- records -------------------------------------------------------------------------------------

    def close(self) -> None:
        self.perception.close()

    def _set_state(self, t: float, state: str, **data: object) -> None:
        self.state = state
        self.result.states.append((t, state))
        self.perception.write(State(round(t, 3), {"state": state, **data}))

    def _note(self, t: float, why: str) -> None:
        """Log why the session stays in its state."""
        self.perception.write(State(round(t, 3), {"state": self.state, "why": why}))

    def _record_frame(self, frame: SensorFrame, step: int) -> None:
        self.perception.record_frame(frame, step)
        if frame.scan is not None and step % FRONTIER_SCAN_EVERY == 0:
            s = frame.scan
            k = FRONTIER_BEAM_STEP
            self.local_map.integrate(frame.odom, s.angles[::k], s.ranges[::k], s.range_max)
        if frame.truth is not None:
            self.result.true_path.append(frame.truth.as_tuple())
        self.result.odom_path.append(frame.odom.as_tuple())

    def _emit(self, frame: SensorFrame, extra: dict | None = None) -> None:
        if self.observer is None:
            return
        self.observer(
            {
                "t": frame.t,
                "state": self.state,
                "distance": self.driver.distance,
                "features": len(self.perception.confirmed),
                "hypotheses": self.hypotheses,
                **(extra or {}),
            }
        )

    # -- the loop ------------------------------------------------------------------------------------

    def run(self) -> SessionResult:
        self._started = time.perf_counter()
        try:
            self._run()
        finally:
            self.result.wall_seconds = time.perf_counter() - self._started
            self.close()
        return self.result

    def _run(self) -> None:
        frame = self.driver.start()
        step = 0
        self._record_frame(frame, step)
        if self.config.exploration.initial_look:
            # Turn once on the spot first: features behind the robot cost no distance (§3.3.4's
            # recovery rotation, done before the first metre).
            self._set_state(frame.t, "look")
            self.looks += 1
        else:
            self._set_state(frame.t, "explore")
        self.hypotheses, self.storeys_left = 0, []
        self.last_feature_t = frame.t
        self.turned = 0.0
        if self.cannot_leave is not None:
            self._fail(frame, self.cannot_leave)
            return
        while True:
            v, w = self._command(frame)
            previous = frame.odom
            frame = self.driver.step(v, w)
            step += 1
            self.turned += abs(float(wrap_angle(frame.odom.yaw - previous.yaw)))
            self._record_frame(frame, step)
            if self._perceive(frame):
                return
            if self.resume_from is not None:  # a fine stage drove on and failed: go on from there
                frame, self.resume_from = self.resume_from, None
            self._emit(frame)
            self._watch_shuttling(frame)
            if self._out_of_limits(frame):
                return

    def _command(self, frame: SensorFrame) -> tuple[float, float]:
        """The velocity command (v m/s, w rad/s) for this period, by state (which it may change)."""
        scan = ScanView.of(frame.scan.angles, frame.scan.ranges, frame.scan.range_max) if frame.scan else None
        if self.state == "explore":
            return self._explore(frame, scan)
        if self.state == "active":
            return self._active(frame, scan)
        if self.state in ("look", "recovery"):
            return self._turn(frame, scan)
        raise RuntimeError(f"unexpected state {self.state}")

    def _held(self, frame: SensorFrame, scan: ScanView) -> bool:
        """Stand and wait for a worker in the way to move on?"""
        return self.waiting.hold(frame.t, scan.front(), self.follow.front_stop)

    def _explore(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """Random exploration: follow the wall, look round on open floors, drive out of loops."""
        if scan is None:
            v, w = 0.0, 0.0  # no scan this period: nothing to steer by
        elif self.escape is not None and frame.t < self.loop_escape_until:
            v, w, arrived = self.escape.step(frame.odom, scan)
            if arrived:
                self.escape = None
        elif self._held(frame, scan):
            v, w = 0.0, 0.0
        elif self._look_again(frame, scan):
            return 0.0, 0.0
        else:
            v, w = wall_follow(scan, self.side, self.follow)
        if self._looping(frame):
            # Circling (between obstacles, in an open hall with no wall in reach, round a room): drive
            # to the nearest unexplored opening the lidar has seen (a frontier), else out along the
            # most open direction; then resume.
            if not self._head_for_frontier(frame):
                toward = self._open_point(frame, scan)
                self._escape(frame, BugNavigator(toward, BugParams(follow=self.follow)))
            self._note(frame.t, "loop escape")
        return v, w

    def _look_again(self, frame: SensorFrame, scan: ScanView) -> bool:
        """Turn once on the spot again (beyond the paper)? After ``exploration.look_every`` m
        without a new feature along a wall with open space on the other side: the camera looks
        along the followed wall, and in a hall or a car park the features stand on the walls across
        the open floor, out of its view. Costs time, no distance. In a corridor (see
        :func:`open_beside`) the camera already sees both walls ahead, and the robot drives on."""
        every = self.config.exploration.look_every
        if every <= 0 or self.perception.travel - self.look_from < every:
            return False
        if not open_beside(scan, self.side):
            return False
        self.look_from = self.perception.travel
        self.turned = 0.0
        self.looks += 1
        self.open_floor_look = True
        self._set_state(frame.t, "look", why=f"{every:g} m without a new feature, open space beside")
        return True

    def _active(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """Active exploration toward the current target; give it up when it brings nothing."""
        held = scan is None or self._held(frame, scan)
        v, w = self.exploration.drive(frame, None if held else scan)
        why = self.exploration.give_up(frame, self.last_feature_t)
        if why is None:
            return v, w
        if self.config.exploration.recovery:
            self._set_state(frame.t, "recovery", why=why)
            self.result.recoveries += 1
            self.turned = 0.0
        elif self.exploration.exhausted or not self._next_target(frame):
            self._set_state(frame.t, "explore", why=why)
        return 0.0, 0.0

    def _turn(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """The initial look, a look on an open floor or the recovery rotation: turn in place, then
        carry on (across the floor after a look on an open floor)."""
        if self.turned >= RECOVERY_TURN:
            if self.state == "look":
                why = "look done" if self.open_floor_look else "initial look done"
                self._set_state(frame.t, "explore", why=why)
                if self.open_floor_look and scan is not None:
                    self._cross_floor(frame, scan)
            elif self.exploration.exhausted:
                # Targets keep failing (blocked routes, a symmetric layout): wall following
                # covers new ground until a new feature changes the hypotheses (§3.3.4).
                self._set_state(
                    frame.t,
                    "explore",
                    why=f"{self.exploration.fruitless} targets in a row brought nothing new",
                )
            elif not self._next_target(frame):
                self._set_state(frame.t, "explore", why="nothing detected after recovery")
        return 0.0, turn_in_place_speed(self.config)

    def _perceive(self, frame: SensorFrame) -> bool:
        """Confirm new features and match after each (and again every REDECIDE_M of travel while a
        match step left hypotheses undecided); True once the session is over."""
        if frame.detections is None:
            return False
        if not self.perception.new_features():
            # No new feature, but the path goes on: its scans may now tell the hypotheses left apart
            # (the robot came round a corridor end since the last feature; with the lidar along the
            # path on).
            undecided = 1 <= self.hypotheses <= TRACK_HYPOTHESES and self.checks.track_m > 0
            if undecided and self.perception.travel - self.decided_at >= REDECIDE_M:
                return self._decide(frame)
            return False
        confirmed = self.perception.confirmed
        self.last_feature_t = frame.t
        self.look_from = self.perception.travel
        self.fruitless_looks = 0
        self.exploration.fruitless = 0
        self.result.features_detected = len(confirmed)
        if len(confirmed) < self.options.min_inliers:
            if self.state == "recovery":
                self._set_state(frame.t, "explore", why="new feature")
            return False
        return self._decide(frame)

    def _decide(self, frame: SensorFrame) -> bool:
        """Match the features so far (Algorithm 1) and act on the hypotheses: claim a unique match
        that passes verification, or explore on; True once the session is over."""
        self.decided_at = self.perception.travel
        report = self._match(frame.t)
        self.hypotheses = report.n_hypotheses
        self.storeys_left = sorted({h.storey for h in report.hypotheses})
        unique = report.n_hypotheses == 1 or report.one_place()
        claim = report if unique else self._lidar_unique(frame, report)
        if claim is not None:
            verified, aligned, rivals = self._verified(frame, claim, picked=not unique)
            if verified:
                return self._coarse_done(frame, claim, aligned)
            if self.state == "look":
                return False  # the look turns all the way round first: what is behind costs no distance
            if rivals and self._active_below(len(rivals)):
                # Rivals with a few more outliers: go and look where the claim and they disagree,
                # as with several hypotheses (§3.3.4), the claim first.
                self.exploration.validate([claim.hypotheses[0], *rivals])
                if self._next_target(frame):
                    return False
            if self.state != "explore":
                self._set_state(frame.t, "explore", why="the unique match failed verification")
            return False
        if self.state == "look":
            return False
        if 1 < report.n_hypotheses and self._active_below(report.n_hypotheses):
            self.exploration.validate(report.hypotheses)
            if not self._next_target(frame) and self.state != "explore":
                self._set_state(frame.t, "explore", why="no target left to validate")
        elif self.state != "explore":
            self._set_state(frame.t, "explore", why=report.verdict)
        return False

    def _lidar_unique(self, frame: SensorFrame, report: MatchReport) -> MatchReport | None:
        """Several hypotheses, one of which the lidar along the path plainly favours (beyond the
        paper; ``track_favoured`` over one hypothesis per place, each verified: the favoured one
        passes the checks a claim must pass and outranks every other, passing or not): that one, to
        be checked as a unique match (its rival search included). A periodic corridor seen from its
        middle leaves several places alike in the recent scans, but the path's turns into a lobby or
        a corridor end fit only the right one. None when no hypothesis stands out so, when there are
        more than TRACK_HYPOTHESES or the lidar along the path is off."""
        hs = report.hypotheses
        c = self.checks
        if not c.enabled or c.track_m <= 0 or report.n_hypotheses > len(hs) or len(hs) > TRACK_HYPOTHESES:
            return None
        # one per place: the same place cannot outrank itself
        places_checked = [
            (hs[i], self._verify(hs[i].storey, hs[i].reported_pose * frame.odom.inverse(), rival=True))
            for i in report.places()
        ]
        if not any(check.passed for _, check in places_checked):
            return None
        tracks = [self._track(frame, h, check) for h, check in places_checked]
        favoured = track_favoured(
            [check.passed for _, check in places_checked],
            [h.n_outliers for h, _ in places_checked],
            [h.n_inliers for h, _ in places_checked],
            tracks,
            lambda k: self._track(frame, places_checked[k][0], places_checked[k][1], wide=True),
            c,
        )
        if favoured is None:
            return None
        best = places_checked[favoured][0]
        passing = sum(check.passed for _, check in places_checked)
        self._note(
            frame.t,
            f"{report.n_hypotheses} hypotheses, {passing} pass the checks: the lidar along the path"
            f" favours hypothesis {best.rank} (its worst window {float(np.min(tracks[favoured])):.2f})",
        )
        return dataclasses.replace(
            report,
            hypotheses=[best],
            n_hypotheses=1,
            verdict=f"unique match by the lidar along the path ({report.verdict})",
        )

    def _track(
        self, frame: SensorFrame, h: Hypothesis, check: Verification, wide: bool = False
    ) -> np.ndarray:
        """The lidar's fit along the path for hypothesis ``h`` (``check`` its verification now),
        from where its recent scans fit best (``wide``: searched as a place about to be outranked)."""
        start = check.aligned_or(h.reported_pose * frame.odom.inverse())
        return track_transform(start, self._evidence_of(h.storey), self.perception.path, self.checks, wide)

    def _evidence_of(self, storey: str) -> StoreyEvidence:
        if storey not in self._evidence:
            self._evidence[storey] = StoreyEvidence.of(self.site.storeys[storey], self.perception.cmap)
        return self._evidence[storey]

    def _verify(
        self, storey: str, transform: Pose2D, fine: bool = False, rival: bool = False
    ) -> Verification:
        checks = self.checks
        if fine:  # the fine pose: the fine-tuning filter's own scan-fit rule
            checks = dataclasses.replace(checks, min_scan_fit=checks.min_fine_scan_fit)
        if rival:  # found with wider tolerances, so less exact: the scans may move it twice as far
            checks = dataclasses.replace(checks, scan_search_xy=RIVAL_SEARCH_FACTOR * checks.scan_search_xy)
        return verify_transform(
            transform,
            self._evidence_of(storey),
            self.perception.path,
            self.perception.sightings,
            self.view,
            checks,
        )

    def _record_check(
        self, frame: SensorFrame, stage: str, storey: str, pose: Pose2D, check: Verification, **extra: object
    ) -> None:
        """Keep a verification for summary.json and write it to the log."""
        doc = {
            "t": round(frame.t, 3),
            "stage": stage,
            "storey": storey,
            "pose": [round(v, 4) for v in pose.as_tuple()],
        }
        doc.update(check.as_dict(), **extra)
        self.result.verifications.append(doc)
        self._note(
            frame.t, f"verification ({stage}): " + ("passed" if check.passed else "; ".join(check.reasons))
        )

    def _verified(
        self, frame: SensorFrame, report: MatchReport, picked: bool = False
    ) -> tuple[bool, Pose2D | None, list[Hypothesis]]:
        """Check a unique match before claiming it (beyond the paper): enough matched features, no
        credible rival when more outliers are allowed (an as-built site has doors the BIM lacks),
        negative evidence, the path and the lidar (``picked``: the lidar along the path picked it out
        of several hypotheses, so its rivals get the wider search). A failed one is logged and
        exploration goes on. Also returns the transform moved to where the recent scans fit best
        (None: not checked) and the rivals that keep a claim out (credible, or too many to check),
        for active exploration."""
        if not self.checks.enabled:
            return True, None, []
        hypothesis = report.hypotheses[0]
        inliers = hypothesis.n_inliers
        if inliers < self.checks.min_claim_inliers:
            self._note(
                frame.t, f"unique match on {inliers} features: waiting for {self.checks.min_claim_inliers}"
            )
            return False, None, []
        c = self.checks
        budget = report.options.outlier_budget(len(report.features))
        extra = rival_search(
            c.rival_outliers,
            hypothesis.n_outliers,
            report.outliers_allowed,
            report.options.max_outliers,
            budget,
        )
        rivals, found = self.perception.rivals(
            self.site,
            report,
            hypothesis,
            extra,
            c.rival_distance,
            math.radians(c.rival_turn_deg),
            # ``picked``: the lidar along the path picked this place out of several, the doors
            # alone did not single it out (point-symmetric ntu_hallway, a fifth of the features
            # never seen: the place turned 179 degrees was favoured, the true one, its doors
            # built off their place, fell outside Eq. 8's tolerance)
            RIVAL_ALPHA_FACTOR if inliers <= RIVAL_ALPHA_MAX_INLIERS or self._doubted() or picked else 1.0,
        )
        pose = hypothesis.reported_pose
        check = self._verify(hypothesis.storey, pose * frame.odom.inverse())
        tracked: list[np.ndarray] = []  # the claim's lidar along the path, once it is needed

        def claim_track() -> np.ndarray:
            if not tracked:
                tracked.append(self._track(frame, hypothesis, check))
            return tracked[0]

        outranked = 0
        if rivals:
            credible, held, outranked = self._credible(frame, check, claim_track, hypothesis, rivals, found)
            fewest = min((h.n_outliers for h in found), default=None)
            why = f"unique match has {rivals} rival(s) with {extra} more outlier(s) allowed" + (
                f" (the claim has {hypothesis.n_outliers} outlier(s), the best rival {fewest})"
                if fewest is not None
                else ""
            )
            if credible:
                self.doubted_at = self.perception.travel
                self._note(frame.t, f"{why}: {credible} pass the checks too")
                return False, None, held
            if outranked:
                self._note(
                    frame.t,
                    f"{why}: those that pass the checks trail the claim by {c.outrank_outliers}+ outlier(s)"
                    f" and {c.outrank_scan_fit:.2f}+ in scan fit, or by the lidar along the path",
                )
            else:
                self._note(frame.t, f"{why}: none passes the checks")
        along = {"track_fit": [round(float(f), 4) for f in tracked[0]]} if tracked else {}
        self._record_check(
            frame, "coarse", hypothesis.storey, pose, check, outranked_rivals=outranked, **along
        )
        if check.passed:
            return True, check.aligned, []
        self.result.rejected += 1
        return False, None, []

    def _active_below(self, hypotheses: int) -> bool:
        """Go and look where ``hypotheses`` disagree (§3.3.4: fewer than m_thre of them)?"""
        return self.config.exploration.active and hypotheses < self.config.matching.m_thre

    def _doubted(self) -> bool:
        """Was a claim held back by credible rivals within the last DOUBT_WINDOW_M of travel? One new
        feature (a phantom, a door the BIM lacks) can leave a claim unique, and its many matched
        features would narrow the rival search just when the true place needs the wider one."""
        return self.doubted_at is not None and self.perception.travel - self.doubted_at <= DOUBT_WINDOW_M

    def _credible(
        self,
        frame: SensorFrame,
        check: Verification,
        claim_track: Callable[[], np.ndarray],
        claim: Hypothesis,
        rivals: int,
        found: list[Hypothesis],
    ) -> tuple[int, list[Hypothesis], int]:
        """How many of the rivals of a claim pass the checks a claim must pass (negative evidence,
        lidar fit, path through free space): a rival that fails them is no reason to doubt the claim
        (a mirror-symmetric wing passes them, and keeps the claim out). None counts when the claim
        passes its own checks and outranks every rival (``outranks``: each fails the checks or
        trails the claim by outliers and scan fit; or ``track_outranks``: the scans along the path,
        ``claim_track`` for the claim, plainly favour the claim; up to RIVALS_COMPARED rivals are
        compared, the likeliest first, stopping at the first that holds its own). Otherwise more than
        RIVALS_CHECKED rivals, or a search stopped at its cap, count as that many (``found`` kept as
        it is). Returns that count, the credible rivals and how many rivals pass the checks yet are
        outranked (those two counts are never both non-zero)."""
        checks: dict[int, Verification] = {}
        c = self.checks

        def rival_check(h: Hypothesis) -> Verification:
            if id(h) not in checks:
                checks[id(h)] = self._verify(h.storey, h.reported_pose * frame.odom.inverse(), rival=True)
            return checks[id(h)]

        def beaten(h: Hypothesis) -> bool:
            """Does the claim outrank rival ``h``: by outliers and recent scan fit, or by the lidar
            along the path (the claim's track computed once, the rival's only when needed)?"""
            theirs = rival_check(h)
            if outranks(check, claim.n_outliers, theirs, h.n_outliers, c):
                return True
            if c.track_m <= 0:
                return False
            # h may be the true place found imprecisely (doors built off their place): it is outranked
            # only if it still trails with its newest window searched wide (in the point-symmetric
            # ntu_hallway, doors 0.6 m off, a turned place fitted the path better than the true one
            # 1.8 m off until that search).
            mine = claim_track()
            trailing = trails(claim.n_outliers, h.n_outliers, c)
            return track_outranks(mine, self._track(frame, h, theirs), c, trailing) and track_outranks(
                mine, self._track(frame, h, theirs, wide=True), c, trailing
            )

        complete = len(found) == rivals
        if complete and check.passed and rivals <= RIVALS_COMPARED:
            if all(beaten(h) for h in found):
                return 0, [], sum(rival_check(h).passed for h in found)
        if rivals > RIVALS_CHECKED or not complete:
            return rivals, found, 0
        credible = [h for h in found if rival_check(h).passed]
        return len(credible), credible, 0

    def _match(self, t: float) -> MatchReport:
        report = self.perception.match(t, self.site)
        self.result.match_steps.append(
            MatchStep(t, len(report.features), report.verdict, [h.pose.as_tuple() for h in report.hypotheses])
        )
        return report

    def _next_target(self, frame: SensorFrame) -> bool:
        """Start active exploration toward the next hypothesis' target; False when none is left."""
        target = self.exploration.next_target(frame)
        if target is None:
            return False
        self.result.active_explorations += 1
        self._set_state(
            frame.t,
            "active",
            target=[round(float(c), 3) for c in target.viewpoint],
            hypothesis=target.hypothesis.rank,
            route_m=round(target.route_m, 1),
            matches=target.hypothesis.matches,
        )
        return True

    def _head_for_frontier(self, frame: SensorFrame) -> bool:
        """Drive out of a loop to the nearest unexplored opening of the local grid; False if none."""
        route = self.local_map.plan(frame.odom)
        if route:
            self._escape(frame, RouteNavigator(route, BugParams(follow=self.follow)))
        return bool(route)

    def _escape(self, frame: SensorFrame, navigator: BugNavigator | RouteNavigator) -> None:
        """Follow ``navigator`` for LOOP_ESCAPE_S instead of the wall (a loop or shuttle escape)."""
        self.escape = navigator
        self.loop_escape_until = frame.t + LOOP_ESCAPE_S
        self.result.loop_escapes += 1

    def _cross_floor(self, frame: SensorFrame, scan: ScanView) -> None:
        """After ``exploration.cross_after`` looks on an open floor since the last new feature (a
        look that found one counts as the first), drive across it (:func:`cross_floor`), then
        follow the wall found there: from the façade of an open-plan office the doors of the rooms
        in the middle are out of the camera's reach, and looking again from the same wall finds
        nothing. The next look comes look_every m after the crossing's reach."""
        self.fruitless_looks += 1
        after = self.config.exploration.cross_after
        if after <= 0 or self.fruitless_looks < after:
            return
        crossing = cross_floor(frame.odom, scan, self.side, self.follow)
        if crossing is None:
            return
        self.fruitless_looks = 0
        self.escape = crossing.navigator
        self.loop_escape_until = frame.t + crossing.seconds
        self.result.crossings += 1
        self.look_from = self.perception.travel + crossing.reach
        self._note(frame.t, f"crossing the open floor ({crossing.reach:.1f} m)")

    def _watch_shuttling(self, frame: SensorFrame) -> None:
        """Shuttling over the same ground for minutes: follow the other wall."""
        if not self.shuttles.confined(frame.t, frame.odom):
            return
        self.side = -self.side
        self.exploration.navigator = None
        # Shuttling in a corridor section (a stack or a hoarding narrows the way on): head for the
        # nearest opening the lidar has seen and not yet reached, as out of a loop.
        heading = self.state == "explore" and self._head_for_frontier(frame)
        self._set_state(
            frame.t,
            "explore",
            why="shuttling over the same ground; "
            + ("heading for an unexplored opening, then " if heading else "")
            + "following the "
            + ("left" if self.side > 0 else "right")
            + " wall",
        )

    def _out_of_limits(self, frame: SensorFrame) -> bool:
        """Fail once the session drove or took longer than its limits allow."""
        limits = self.config.limits
        # Measured on what the robot knows (its odometry), as on a real robot: not the true path.
        if self.perception.travel > limits.max_distance:
            self._fail(
                frame,
                f"moved {limits.max_distance:g} m without a unique match "
                f"({len(self.perception.confirmed)} features, {self.hypotheses} hypotheses"
                + (
                    f" on storeys {', '.join(self.storeys_left)}: the storey is not resolved)"
                    if len(self.storeys_left) > 1
                    else ")"
                )
                + (
                    f"; the fine stage of an earlier one failed: {self.fine_failed_why}"
                    if self.fine_failures
                    else ""
                ),
            )
            return True
        if frame.t > limits.max_time:
            self._fail(frame, f"no unique match within {limits.max_time:g} s")
            return True
        return False

    @staticmethod
    def _open_point(frame: SensorFrame, scan: ScanView | None) -> np.ndarray:
        """An odom point OPEN_REACH along the longest free beam (or OPEN_SHORT short of the obstacle)."""
        if scan is None or len(scan.ranges) == 0:
            return frame.odom.apply(np.array([BLIND_REACH, 0.0]))
        i = int(np.argmax(scan.ranges))
        reach = min(OPEN_REACH, float(scan.ranges[i]) - OPEN_SHORT)
        return frame.odom.apply(reach * np.array([math.cos(scan.angles[i]), math.sin(scan.angles[i])]))

    def _looping(self, frame: SensorFrame) -> bool:
        """Has the robot driven a long way in the last LOOP_WINDOW_S while staying in a small area?"""
        return frame.t >= self.loop_escape_until and self.loops.confined(frame.t, frame.odom)

    # -- the end -------------------------------------------------------------------------------------

    def _fail(self, frame: SensorFrame, reason: str) -> None:
        self._set_state(frame.t, "failed", reason=reason)
        r = self.result
        r.success, r.reason = False, reason
        r.distance_total_m = self.driver.distance
        r.duration_s = frame.t
        r.truth_pose = frame.truth
        r.features = list(self.perception.confirmed)

    def _coarse_done(self, frame: SensorFrame, report: MatchReport, aligned: Pose2D | None = None) -> bool:
        """The unique match: record the coarse and rectified poses (Eq. 17), fine-tune (Eq. 18);
        True once the session is over (False: the fine stage failed and exploration goes on)."""
        cfg = self.config
        best = report.hypotheses[0]
        r = self.result
        r.storey = best.storey
        r.coarse_pose = best.pose
        rectified = best.reported_pose
        r.rectified_pose = rectified
        r.truth_at_coarse = frame.truth
        r.distance_coarse_m = round(self.driver.distance, 3)
        r.wall_seconds_coarse = time.perf_counter() - self._started
        if r.first_claim is None:
            r.first_claim = CoarseClaim(rectified, frame.truth, r.distance_coarse_m, r.wall_seconds_coarse)
        r.matched_ids = list(best.matches)
        r.features = list(report.features)  # the ones matched (a drift window may leave old ones out)
        transform = rectified * frame.odom.inverse()
        if aligned is not None:
            # Fine tuning starts where the recent scans fit the BIM best near the coarse pose (the
            # verification's search: decimetres, degrees): a coarse pose from doors built off their
            # place can be 15 degrees off, which a filter seeded 10 degrees wide may not recover.
            transform = aligned
        r.transform = transform
        # The log's detections end here, so that it replays to this verdict (they go on after a
        # failed fine stage, up to the next claim).
        self.perception.detecting = False
        self._set_state(
            frame.t,
            "coarse",
            verdict=report.verdict,
            pose=[round(v, 4) for v in best.pose.as_tuple()],
            rectified_pose=[round(v, 4) for v in rectified.as_tuple()],
            matches=best.matches,
        )
        model = self.site.storeys[best.storey]
        cov: np.ndarray | None = None
        if cfg.fine_tuning.enabled and model.grid is not None:
            self._set_state(frame.t, "fine")
            tuning = FineTuning(cfg.fine_tuning, model.grid, self.rng, self.side, self.follow)
            hooks = FineTuningHooks(self._record_frame, self._note, self._emit)
            landmarks = matched_pairs(r.features, r.matched_ids, model.features)
            outcome = tuning.run(self.driver, frame, transform * frame.odom, transform, landmarks, hooks)
            frame = outcome.frame
            if isinstance(outcome, FineLost):
                return self._fine_failed(frame, outcome.reason)
            r.fine_converged = outcome.converged
            pose, cov = outcome.pose, outcome.covariance
        else:
            pose = transform * frame.odom
        if self.checks.enabled:
            check = self._verify(best.storey, pose * frame.odom.inverse(), fine=True)
            carried = transform * frame.odom
            apart = pose.distance_to(carried) > AGREE_M or pose.yaw_error(carried) > math.radians(AGREE_DEG)
            self._record_check(frame, "fine", best.storey, pose, check, agrees_with_coarse=not apart)
            if not check.passed or apart:
                why = (
                    "; ".join(check.reasons)
                    if not check.passed
                    else (
                        f"fine tuning ended {pose.distance_to(carried):.1f} m / "
                        f"{math.degrees(pose.yaw_error(carried)):.0f} deg from the coarse pose"
                    )
                )
                return self._fine_failed(frame, f"the pose failed verification: {why}")
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
        return True

    def _fine_failed(self, frame: SensorFrame, reason: str) -> bool:
        """The fine stage failed (the filter lost the robot, or its pose failed verification; with
        fine tuning off, the carried coarse pose failed it): the session fails with ``reason`` after
        FINE_TRIES such failures; before that the claim is not reported, detection and exploration
        go on, and the match steps on (a new feature, or REDECIDE_M of travel) may claim the same
        place again, fine-tuned from where the robot is then (hoardings and stacks that hide the
        walls here may not be there). True once the session is over."""
        self.fine_failures += 1
        self.fine_failed_why = reason
        if self.fine_failures >= FINE_TRIES:
            self._fail(frame, reason)
            return True
        self.resume_from = frame  # the main loop goes on from where the fine stage ended
        self.perception.detecting = True
        self.decided_at = self.perception.travel
        self.escape = None  # a loop escape or crossing under way at the claim led from elsewhere
        self.result.transform, self.result.fine_converged = None, None
        self._set_state(frame.t, "explore", why=f"{reason}: exploring on")
        return False
