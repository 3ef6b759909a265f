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
tuning in :mod:`.fine_tuning`, the outcome in :mod:`.result`, the states in :mod:`.states`; they are
built from the session config in :mod:`.assembly`.
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
from initcli.config import SessionConfig, turn_in_place_speed
from initcli.core.navigation.wall_following import MovingObstacleWait, ScanView, wall_follow
from initcli.core.verify.checks import TRACK_HYPOTHESES
from initcli.drivers.base import RobotDriver, SensorFrame
from initcli.match.pipeline import Hypothesis, MatchReport
from initcli.session.assembly import assemble
from initcli.session.claims import Claim
from initcli.session.escapes import path_points
from initcli.session.exploration import unseen_features
from initcli.session.fine_tuning import FineLost, FineTuningHooks
from initcli.session.result import SHUT_IN, DecidedBy, MatchStep, SessionResult, limit_reason
from initcli.session.states import SessionState

__all__ = ["Observer", "Session"]

Observer = Callable[[dict], None]

EXPLORE, LOOK, ACTIVE, RECOVERY = (
    SessionState.EXPLORE,
    SessionState.LOOK,
    SessionState.ACTIVE,
    SessionState.RECOVERY,
)


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
        self.config, self.site, self.storey = config, site, storey  # storey None: every storey
        self.driver, self.observer = driver, observer
        parts = assemble(config, site, storey, driver, log_path, rng, meta_source)
        self.options, self.perception, self.result = parts.options, parts.perception, parts.result
        self.states, self.claims, self.registration, self.fine = (
            parts.states,
            parts.claims,
            parts.registration,
            parts.fine,
        )
        self.side, self.follow, self.twins = parts.side, parts.follow, parts.twins
        self.exploration, self.escapes, self.looks = parts.exploration, parts.escapes, parts.looks
        self.hooks = FineTuningHooks(self._record_frame, self.states.note, self._emit)
        self.checks = config.verification
        self.waiting = MovingObstacleWait()
        self.finished = False  # the session ended while choosing a command (shut in)
        self.last_feature_t = 0.0  # s: when the last new feature was confirmed
        self.hypotheses = 0  # of the last match step
        # its hypotheses when no more than exploration.targets.hypotheses (exploration.feature_walls)
        self.last_hypotheses: list[Hypothesis] = []
        self.decided_at = 0.0  # m of travel at the last match step
        self.storeys_left: list[str] = []  # storeys the last match step's hypotheses lie on
        self.cannot_leave: str | None = None  # set when the start is known to be closed in
        self.resume_from: SensorFrame | None = None  # the last frame of a fine stage that failed
        self._started = time.perf_counter()

    @property
    def state(self) -> SessionState:
        """The state the session is in."""
        return self.states.now

    # -- records -------------------------------------------------------------------------------------

    def close(self) -> None:
        self.perception.close()

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
            self.states.enter(frame.t, LOOK)
            self.looks.count += 1
        else:
            self.states.enter(frame.t, EXPLORE)
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
        if self.state is EXPLORE:
            return self._explore(frame, scan)
        if self.state is ACTIVE:
            return self._active(frame, scan)
        if self.state.turning:
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
            self.states.note(frame.t, "loop escape")
        self._watch_laps(frame)
        return v, w

    def _watch_laps(self, frame: SensorFrame) -> None:
        """Once round the room, hall or corridor section without a new feature: on to an opening the
        robot can pass, or, with none left, the session stops shut in (``exploration.laps``)."""
        lap = self.escapes.lap(frame, self.perception.travel, len(self.perception.confirmed))
        if isinstance(lap, str):
            self.states.note(frame.t, lap)
        elif lap is not None:
            self.result.shut_in = lap
            self._fail(frame, SHUT_IN, message=lap.message, explored_m2=lap.explored_m2)
            self.finished = True

    def _look_again(self, frame: SensorFrame, scan: ScanView) -> bool:
        """Turn once on the spot again (:meth:`Looks.again`: open space beside, no new feature for
        ``exploration.look_every`` m)? Costs time, no distance."""
        if not self.looks.again(self.perception.travel, scan, self.side):
            return False
        every = self.config.exploration.look_every
        self.states.enter(frame.t, LOOK, why=f"{every:g} m without a new feature, open space beside")
        return True

    def _active(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """Active exploration toward the current target; give it up when it brings nothing."""
        held = scan is None or self._held(frame, scan)
        v, w = self.exploration.drive(frame, None if held else scan)
        why = self.exploration.give_up(frame, self.last_feature_t)
        if why is None:
            return v, w
        if self.config.exploration.recovery:
            self.states.enter(frame.t, RECOVERY, why=why)
            self.result.recoveries += 1
            self.looks.begin()
        elif self.exploration.exhausted or not self._next_target(frame):
            self.states.enter(frame.t, EXPLORE, why=why)
        return 0.0, 0.0

    def _turn(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """The initial look, a look on an open floor or the recovery rotation: turn in place, then
        carry on (across the floor after a look on an open floor)."""
        if self.looks.done:
            if self.state is LOOK:
                why = "look done" if self.looks.open_floor else "initial look done"
                self.states.enter(frame.t, EXPLORE, why=why)
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
                        self.states.note(frame.t, f"crossing the open floor ({crossing.reach:.1f} m)")
            elif self.exploration.exhausted:
                # Targets keep failing (blocked routes, a symmetric layout): wall following
                # covers new ground until a new feature changes the hypotheses (§3.3.4).
                why = f"{self.exploration.fruitless} targets in a row brought nothing new"
                self.states.enter(frame.t, EXPLORE, why=why)
            elif not self._next_target(frame):
                self.states.enter(frame.t, EXPLORE, why="nothing detected after recovery")
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
            if self.state is RECOVERY:
                self.states.enter(frame.t, EXPLORE, why="new feature")
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
                by = DecidedBy.PAPER if unique else DecidedBy.LIDAR
                return self._coarse_done(
                    frame, Claim(claim.hypotheses[0], claim.features, claim.verdict, by, aligned)
                )
            if self.state is LOOK:
                return False  # the look turns all the way round first: what is behind costs no distance
            if rivals and self._active_below(len(rivals)):
                # Rivals with a few more outliers: go and look where the claim and they disagree,
                # as with several hypotheses (§3.3.4), the claim first.
                self.exploration.validate([claim.hypotheses[0], *rivals])
                if self._next_target(frame):
                    return False
            self.states.explore(frame.t, "the unique match failed verification")
            return False
        if self.state is LOOK:
            return False
        if 1 < report.n_hypotheses and self._active_below(report.n_hypotheses):
            self.exploration.validate(report.hypotheses)
            if not self._next_target(frame):
                self.states.explore(frame.t, "no target left to validate")
        else:
            self.states.explore(frame.t, report.verdict)
        return False

    def _register(self, frame: SensorFrame) -> bool:
        """Claim a unique registration of the lidar submap that passes the checks
        (:meth:`ClaimChecks.by_registration`); True once the session is over."""
        claim = self.claims.by_registration(frame, self.registration)
        return claim is not None and self._coarse_done(frame, claim)

    def _active_below(self, hypotheses: int) -> bool:
        """Go and look where ``hypotheses`` disagree (§3.3.4: fewer than m_thre of them)?"""
        return self.config.exploration.active and hypotheses < self.config.matching.m_thre

    def _match(self, t: float) -> MatchReport:
        report = self.perception.match(t, self.site)
        self.result.match_steps.append(MatchStep.of(t, report))
        return report

    def _next_target(self, frame: SensorFrame) -> bool:
        """Start active exploration toward the next hypothesis' target; False when none is left."""
        target = self.exploration.next_target(frame)
        if target is None:
            return False
        self.result.active_explorations += 1
        self.states.enter(frame.t, ACTIVE, **target.record())
        return True

    def _watch_shuttling(self, frame: SensorFrame) -> None:
        """Shuttling over the same ground for minutes: follow the other wall (exploring: heading for
        an unexplored opening first, :meth:`Escapes.after_shuttling`)."""
        if not self.escapes.shuttling(frame):
            return
        self.side = -self.side
        self.exploration.navigator = None
        why = self.escapes.after_shuttling(frame, self.side, self.state is EXPLORE)
        self.states.enter(frame.t, EXPLORE, why=why)

    def _out_of_limits(self, frame: SensorFrame) -> bool:
        """Fail once the session drove or took longer than its limits allow."""
        p, earlier = self.perception, self.fine.earlier_failure
        why = limit_reason(
            self.config.limits, p.travel, frame.t, p.n_features, self.hypotheses, self.storeys_left, earlier
        )
        if why is not None:
            self._fail(frame, why)
        return why is not None

    # -- the end -------------------------------------------------------------------------------------

    def _fail(self, frame: SensorFrame, reason: str, **data: object) -> None:
        self.states.fail(frame, reason, self.driver.distance, self.perception.confirmed, **data)

    def _coarse_done(self, frame: SensorFrame, claim: Claim) -> bool:
        """Claim the unique match ``claim``: record the coarse and rectified poses (Eq. 17), fine-tune
        (Eq. 18); True once the session is over (False: the fine stage failed and exploration goes on)."""
        r, best = self.result, claim.best
        elapsed = time.perf_counter() - self._started
        r.claimed(best, frame.truth, self.driver.distance, elapsed, claim.features)
        r.decided_by = claim.decided_by
        # Fine tuning starts where the recent scans fit the BIM best near the coarse pose (``aligned``,
        # the verification's search: decimetres, degrees): a coarse pose from doors built off their
        # place can be 15 degrees off, which a filter seeded 10 degrees wide may not recover.
        transform = claim.aligned if claim.aligned is not None else best.reported_pose * frame.odom.inverse()
        r.transform = transform
        # The log's detections end here, so that it replays to this verdict (they go on after a
        # failed fine stage, up to the next claim).
        self.perception.detecting = False
        self.states.enter(frame.t, SessionState.COARSE, **claim.record())
        model = self.site.storeys[best.storey]
        cov: np.ndarray | None = None
        if self.fine.tunes(model):
            self.states.enter(frame.t, SessionState.FINE)
            outcome = self.fine.run(self.driver, frame, model, transform, self.side, r, self.hooks)
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
        self.states.enter(frame.t, SessionState.DONE, pose=[round(v, 4) for v in pose.as_tuple()])
        return True

    def _fine_failed(self, frame: SensorFrame, reason: str) -> bool:
        """The fine stage failed (the filter lost the robot, or its pose failed verification; with
        fine tuning off, the carried coarse pose failed it): the session fails with ``reason`` after
        ``fine_tuning.tries`` such failures; before that the claim is not reported, detection and exploration
        go on, and the match steps on (a new feature, or ``matching.redecide`` m) may claim the same
        place again, fine-tuned from where the robot is then (hoardings and stacks that hide the
        walls here may not be there). True once the session is over."""
        if self.fine.failed(reason):
            self._fail(frame, reason)
            return True
        self.resume_from = frame  # the main loop goes on from where the fine stage ended
        self.perception.detecting = True
        self.decided_at = self.perception.travel
        self.escapes.cancel()  # a loop escape or crossing under way at the claim led from elsewhere
        self.result.transform, self.result.fine_converged = None, None
        self.states.enter(frame.t, EXPLORE, why=f"{reason}: exploring on")
        return False
