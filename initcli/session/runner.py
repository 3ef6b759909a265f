"""The online decision making of §3.3.4 as a state machine, then rectification and fine tuning.

States: ``explore`` (random exploration by wall following) -> with >= 3 confirmed features,
match (Algorithm 1) after each new one -> ``unique``: coarse initialisation done ->
``rectify`` (Eq. 17) -> ``fine`` (particle filter, Eq. 18, while following the wall) -> done.
With ``exploration.active`` (off by default: in the site as built wall following initialised
more sessions) and several but fewer than m_thre hypotheses: ``active`` exploration toward the
nearest feature of the highest-priority category (fewest in the BIM) under the most probable
hypothesis, with the modified bug algorithm (Eq. 15-16); no new feature within t_thre ->
``recovery`` (rotate in place to widen the view) -> still nothing -> ``explore``.

Each step lives in its own module: what the robot sees and logs in :mod:`.perception`, the checks
of a claim and its rivals in :mod:`.claims`, loop and shuttle escapes and floor crossings in
:mod:`.escapes`, looks round in :mod:`.looks`, active exploration in :mod:`.exploration`, fine
tuning in :mod:`.fine_tuning`, the outcome in :mod:`.result`; their tuning is the session config's.
The session writes every record it acts on to its detection log, and decides by running the same
pipeline as ``bim-init match`` (:func:`initcli.match.pipeline.match_log`) on the log so far, so the
log replays to the same coarse verdict and pose.
"""

from __future__ import annotations

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
    wall_follow_params,
)
from initcli.config.building import twin_reason
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import ConfirmedFeature
from initcli.core.geometry.se2 import Pose2D
from initcli.core.navigation.wall_following import MovingObstacleWait, ScanView, wall_follow
from initcli.core.verify.checks import TRACK_HYPOTHESES, CameraView
from initcli.drivers.base import RobotDriver, SensorFrame
from initcli.io.detection_log import Meta, State
from initcli.match.landmarks import site_tracker
from initcli.match.pipeline import DECIDED_BY_LIDAR, DECIDED_BY_PAPER, Hypothesis, MatchReport
from initcli.session.claims import ClaimChecks
from initcli.session.escapes import Escapes, path_points
from initcli.session.exploration import ActiveExploration, unseen_features
from initcli.session.fine_tuning import FineLost, FineTuning, FineTuningHooks, matched_pairs
from initcli.session.looks import Looks
from initcli.session.perception import Perception
from initcli.session.result import SHUT_IN, MatchStep, SessionResult, limit_reason
from initcli.verify.registration import DECIDED_BY_REGISTRATION, SubmapRegistration, registered_hypothesis

__all__ = ["Observer", "Session"]

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
        meta = Meta(driver.camera, driver.mount, depth_window=driver.depth_window, source=meta_source)
        cmap, m = ClassMap(config.detector.classes), config.matching
        tracker = site_tracker(site) if self.options.landmarks else None
        self.perception = Perception(
            meta, log_path, cmap, self.options, m.drift_window, config.lidar.log_every, tracker
        )
        self.side = followed_side(config)
        self.follow = wall_follow_params(config)
        self.waiting = MovingObstacleWait()
        self.state = "explore"
        self.result = SessionResult(False, "", storey)
        self.exploration = ActiveExploration(config, site, self.follow)
        x = config.exploration
        self.escapes = Escapes(x.loops, x.shuttles, x.frontier, self.follow, self.result, x.laps)
        self.escapes.to_long_walls = x.long_walls
        self.finished = False  # the session ended while choosing a command (shut in)
        self.looks = Looks(x)
        self.last_feature_t = 0.0  # s: when the last new feature was confirmed
        self.hypotheses = 0  # of the last match step
        # its hypotheses when no more than exploration.targets.hypotheses (exploration.feature_walls)
        self.last_hypotheses: list[Hypothesis] = []
        self.decided_at = 0.0  # m of travel at the last match step
        self.storeys_left: list[str] = []  # storeys the last match step's hypotheses lie on
        self.checks = config.verification
        view = CameraView(driver.camera, driver.mount, self.options.min_depth)
        self.claims = ClaimChecks(self.checks, site, self.perception, view, self.result, self._note)
        self.registration = SubmapRegistration(config.registration, site, storey, self.checks.scan_tolerance)
        self.cannot_leave: str | None = None  # set when the start is known to be closed in
        # every storey matched maps onto itself turned: no reading tells a pose from its twin
        self.twins = twin_reason(site, storey)
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
        self.escapes.see(frame, step)
        if frame.truth is not None:
            self.result.true_path.append(frame.truth.as_tuple())
        self.result.odom_path.append(frame.odom.as_tuple())

    def _emit(self, frame: SensorFrame, extra: dict | None = None) -> None:
        if self.observer is not None:
            where = {"t": frame.t, "state": self.state, "distance": self.driver.distance}
            seen = {"features": len(self.perception.confirmed), "hypotheses": self.hypotheses}
            self.observer({**where, **seen, **(extra or {})})

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
            self.looks.count += 1
        else:
            self._set_state(frame.t, "explore")
        self.hypotheses, self.storeys_left = 0, []
        self.last_feature_t = frame.t
        self.looks.begin()
        if self.cannot_leave is not None:
            self._fail(frame, self.cannot_leave)
            return
        if self.twins is not None:
            self._fail(frame, self.twins)
            return
        while True:
            v, w = self._command(frame)
            if self.finished:
                return
            previous = frame.odom
            frame = self.driver.step(v, w)
            step += 1
            self.looks.moved(previous, frame.odom)
            self._record_frame(frame, step)
            if self._perceive(frame):
                return
            if self.resume_from is not None:  # a fine stage drove on and failed: go on from there
                frame, self.resume_from = self.resume_from, None
            elif self.registration.due(self.perception.travel) and self._register(frame):
                return
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
        elif self.escapes.under_way(frame):
            v, w = self.escapes.step(frame, scan)
        elif self._held(frame, scan):
            v, w = 0.0, 0.0
        elif self._look_again(frame, scan):
            return 0.0, 0.0
        else:
            v, w = wall_follow(scan, self.side, self.follow)
        if self.escapes.looping(frame):
            # Circling (between obstacles, in an open hall with no wall in reach, round a room): drive
            # to the nearest unexplored opening the lidar has seen, else out along the most open
            # direction; then resume.
            self.escapes.out_of_loop(frame, scan)
            self._note(frame.t, "loop escape")
        self._watch_laps(frame)
        return v, w

    def _watch_laps(self, frame: SensorFrame) -> None:
        """Once round the room, hall or corridor section without a new feature: on to an opening the
        robot can pass, or, with none left, the session stops shut in (``exploration.laps``)."""
        lap = self.escapes.lap(frame, self.perception.travel, len(self.perception.confirmed))
        if isinstance(lap, str):
            self._note(frame.t, lap)
        elif lap is not None:
            self.result.shut_in = lap
            self._set_state(
                frame.t, "failed", reason=SHUT_IN, message=lap.message, explored_m2=lap.explored_m2
            )
            self.result.failed(SHUT_IN, frame.truth, frame.t, self.driver.distance, self.perception.confirmed)
            self.finished = True

    def _look_again(self, frame: SensorFrame, scan: ScanView) -> bool:
        """Turn once on the spot again (:meth:`Looks.again`: open space beside, no new feature for
        ``exploration.look_every`` m)? Costs time, no distance."""
        if not self.looks.again(self.perception.travel, scan, self.side):
            return False
        every = self.config.exploration.look_every
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
            self.looks.begin()
        elif self.exploration.exhausted or not self._next_target(frame):
            self._set_state(frame.t, "explore", why=why)
        return 0.0, 0.0

    def _turn(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """The initial look, a look on an open floor or the recovery rotation: turn in place, then
        carry on (across the floor after a look on an open floor)."""
        if self.looks.done:
            if self.state == "look":
                why = "look done" if self.looks.open_floor else "initial look done"
                self._set_state(frame.t, "explore", why=why)
                if self.looks.open_floor and scan is not None:
                    predicted = unseen_features(self.site, self.last_hypotheses, frame.odom)
                    crossing = self.looks.cross(
                        frame,
                        scan,
                        self.side,
                        self.escapes,
                        self.perception.travel,
                        predicted,
                        path_points(self.result),
                    )
                    if crossing is not None:
                        self._note(frame.t, f"crossing the open floor ({crossing.reach:.1f} m)")
            elif self.exploration.exhausted:
                # Targets keep failing (blocked routes, a symmetric layout): wall following
                # covers new ground until a new feature changes the hypotheses (§3.3.4).
                why = f"{self.exploration.fruitless} targets in a row brought nothing new"
                self._set_state(frame.t, "explore", why=why)
            elif not self._next_target(frame):
                self._set_state(frame.t, "explore", why="nothing detected after recovery")
        return 0.0, turn_in_place_speed(self.config)

    def _perceive(self, frame: SensorFrame) -> bool:
        """Confirm new features and match after each (and again every ``matching.redecide`` m of
        travel while a match step left hypotheses undecided); True once the session is over."""
        if frame.detections is None:
            return False
        if not self.perception.new_features():
            # No new feature, but the path goes on: its scans may now tell the hypotheses left apart
            # (the robot came round a corridor end since the last feature; with the lidar along the
            # path on).
            undecided = 1 <= self.hypotheses <= TRACK_HYPOTHESES and self.checks.track_m > 0
            if undecided and self.perception.travel - self.decided_at >= self.config.matching.redecide:
                return self._decide(frame)
            return False
        features = self.perception.n_features
        self.last_feature_t = frame.t
        self.looks.new_feature(self.perception.travel)
        self.exploration.fruitless = 0
        self.result.features_detected = features
        if features < self.options.min_inliers:
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
        few = len(report.hypotheses) <= self.config.exploration.targets.hypotheses
        self.last_hypotheses = report.hypotheses if few else []  # of many, the top few vote at random
        self.storeys_left = sorted({h.storey for h in report.hypotheses})
        unique = report.n_hypotheses == 1 or report.one_place()
        claim = report if unique else self.claims.lidar_unique(frame, report)
        if claim is not None:
            verified, aligned, rivals = self.claims.verified(frame, claim, picked=not unique)
            if verified:
                by = DECIDED_BY_PAPER if unique else DECIDED_BY_LIDAR
                return self._coarse_done(
                    frame, claim.hypotheses[0], claim.features, claim.verdict, by, aligned
                )
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

    def _register(self, frame: SensorFrame) -> bool:
        """Register the lidar submap of the recent path over the BIM map (no camera claim so far);
        claim a unique registration that passes the checks. True once the session is over."""
        found, last = self.registration.attempt(self.perception.path, self.perception.travel)
        self._note(frame.t, f"lidar registration: {found.why}")
        best = found.best
        if best is None or last is None:
            return False
        if not found.unique:
            # Places that fit the submap alike are not told apart by the lidar along the path here:
            # it picked a place 40-60 m off in the test halls (CHANGELOG, lidar registration).
            return False
        transform = best.pose * last.inverse()
        verified, aligned = self.claims.registered(frame, best, transform, found)
        if not verified:
            return False
        hypothesis = registered_hypothesis(best.storey, transform, frame.odom)
        verdict = f"unique pose by lidar registration ({found.why})"
        return self._coarse_done(frame, hypothesis, [], verdict, DECIDED_BY_REGISTRATION, aligned)

    def _active_below(self, hypotheses: int) -> bool:
        """Go and look where ``hypotheses`` disagree (§3.3.4: fewer than m_thre of them)?"""
        return self.config.exploration.active and hypotheses < self.config.matching.m_thre

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
        self._set_state(frame.t, "active", **target.record())
        return True

    def _watch_shuttling(self, frame: SensorFrame) -> None:
        """Shuttling over the same ground for minutes: follow the other wall (exploring: heading for
        an unexplored opening first, :meth:`Escapes.after_shuttling`)."""
        if not self.escapes.shuttling(frame):
            return
        self.side = -self.side
        self.exploration.navigator = None
        why = self.escapes.after_shuttling(frame, self.side, self.state == "explore")
        self._set_state(frame.t, "explore", why=why)

    def _out_of_limits(self, frame: SensorFrame) -> bool:
        """Fail once the session drove or took longer than its limits allow."""
        p, earlier = self.perception, self.fine_failed_why if self.fine_failures else ""
        why = limit_reason(
            self.config.limits, p.travel, frame.t, p.n_features, self.hypotheses, self.storeys_left, earlier
        )
        if why is not None:
            self._fail(frame, why)
        return why is not None

    # -- the end -------------------------------------------------------------------------------------

    def _fail(self, frame: SensorFrame, reason: str) -> None:
        self._set_state(frame.t, "failed", reason=reason)
        self.result.failed(reason, frame.truth, frame.t, self.driver.distance, self.perception.confirmed)

    def _coarse_done(
        self,
        frame: SensorFrame,
        best: Hypothesis,
        features: list[ConfirmedFeature],
        verdict: str,
        decided_by: str,
        aligned: Pose2D | None = None,
    ) -> bool:
        """The unique match ``best`` (of ``features``; ``decided_by`` what made it unique): record the
        coarse and rectified poses (Eq. 17), fine-tune (Eq. 18); True once the session is over (False:
        the fine stage failed and exploration goes on)."""
        cfg = self.config
        r = self.result
        elapsed = time.perf_counter() - self._started
        r.claimed(best, frame.truth, self.driver.distance, elapsed, features)
        r.decided_by = decided_by
        # Fine tuning starts where the recent scans fit the BIM best near the coarse pose (``aligned``,
        # the verification's search: decimetres, degrees): a coarse pose from doors built off their
        # place can be 15 degrees off, which a filter seeded 10 degrees wide may not recover.
        transform = aligned if aligned is not None else best.reported_pose * frame.odom.inverse()
        r.transform = transform
        # The log's detections end here, so that it replays to this verdict (they go on after a
        # failed fine stage, up to the next claim).
        self.perception.detecting = False
        self._set_state(
            frame.t,
            "coarse",
            verdict=verdict,
            decided_by=decided_by,
            pose=[round(v, 4) for v in best.pose.as_tuple()],
            rectified_pose=[round(v, 4) for v in best.reported_pose.as_tuple()],
            matches=best.matches,
        )
        model = self.site.storeys[best.storey]
        cov: np.ndarray | None = None
        if cfg.fine_tuning.enabled and model.grid is not None:
            self._set_state(frame.t, "fine")
            fit = self.checks.min_fine_scan_fit
            tuning = FineTuning(cfg.fine_tuning, fit, model.grid, self.rng, self.side, self.follow)
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
        failed = self.claims.final(frame, best.storey, pose, transform * frame.odom)
        if failed is not None:
            return self._fine_failed(frame, failed)
        r.initialised(pose, cov, frame.odom, frame.truth, frame.t, self.driver.distance)
        self._set_state(frame.t, "done", pose=[round(v, 4) for v in pose.as_tuple()])
        return True

    def _fine_failed(self, frame: SensorFrame, reason: str) -> bool:
        """The fine stage failed (the filter lost the robot, or its pose failed verification; with
        fine tuning off, the carried coarse pose failed it): the session fails with ``reason`` after
        ``fine_tuning.tries`` such failures; before that the claim is not reported, detection and exploration
        go on, and the match steps on (a new feature, or ``matching.redecide`` m) may claim the same
        place again, fine-tuned from where the robot is then (hoardings and stacks that hide the
        walls here may not be there). True once the session is over."""
        self.fine_failures += 1
        self.fine_failed_why = reason
        if self.fine_failures >= self.config.fine_tuning.tries:
            self._fail(frame, reason)
            return True
        self.resume_from = frame  # the main loop goes on from where the fine stage ended
        self.perception.detecting = True
        self.decided_at = self.perception.travel
        self.escapes.cancel()  # a loop escape or crossing under way at the claim led from elsewhere
        self.result.transform, self.result.fine_converged = None, None
        self._set_state(frame.t, "explore", why=f"{reason}: exploring on")
        return False
