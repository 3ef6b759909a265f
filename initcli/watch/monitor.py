"""The watcher: odometry, scans and the localiser's poses in, in time order; events out.

Every ``watch.check_every`` m of travel the scans of the last ``watch.submap`` m are placed by the
localiser's pose (its odom -> map transform at its last pose, carried by odometry, as Nav2 carries
it) and judged (:mod:`initcli.core.watch.pose_check`); Page's CUSUM over travel
(:mod:`initcli.core.watch.lost_test`) turns the checks into "suspect". A suspect pose is lost only
when the lidar registration of the scans since the change (the submap registration of ``run`` and
``match``, :class:`initcli.verify.registration.SubmapRegistration`) finds a place elsewhere that
fits those scans clearly better than the localiser's pose does, or when the evidence grows to
UNCONFIRMED times the threshold though no place does; if its best place is the
localiser's, the suspicion is dropped. Lost, the watcher registers the scans since the change
every ``watch.recover_every`` m; the first unique registration that passes a session's claim checks
(:func:`initcli.verify.evidence.verify_transform`, the camera counted blind) is the recovered
pose, carried by odometry to the scan that decided.

After a recovery the localiser is expected to take the pose (``/initialpose``). While its own
transform stays where it was when lost (a recording, or a localiser that did not listen), the
watcher checks its poses as corrected by the recovery; once the localiser moves on, its own again.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from bimtools.site.load import Site
from initcli.config.building import twin_reason
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration import RegistrationMap
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import ScanSample, best_scan_alignment
from initcli.core.verify.checks import CameraView
from initcli.core.verify.params import VerificationParams
from initcli.core.watch.lost_test import CusumTest, wrongness
from initcli.core.watch.params import WatchParams
from initcli.core.watch.pose_check import pose_evidence
from initcli.io.log_records import NO_CAMERA, NO_MOUNT
from initcli.match.load import site_class_map
from initcli.verify.evidence import PathEvidence, StoreyEvidence, claim_params, verify_transform
from initcli.verify.registration import SubmapRegistration
from initcli.watch.records import EventKind, WatchCheck, WatchEvent, WatchState
from initcli.watch.scans import RecentScans, check_beams

__all__ = ["Watcher"]

ODOM_KEPT_S = 60.0  # s of odometry kept to place a localiser pose stamped a little in the past
STALE_M = 0.5  # m: the localiser's transform this close to where it was when lost has not moved on
STALE_DEG = 10.0  # degrees: ... nor turned this much
UNCONFIRMED = 10.0  # thresholds of evidence that make a pose lost though no place could be claimed
CONFIRM_SEARCH_M = 0.1  # m: the registration's place aligned within this on the scans since the change
CONFIRM_SEARCH_DEG = 2.0
USUAL_PERCENTILE = 10.0  # the usual fit: this percentile of a right pose's recent fits (its worst usual)
USUAL_CHECKS = 8  # checks of a right pose before its usual fit is known ...
USUAL_SPAN_M = 5.0  # ... over this much travel at least


def _far(a: Pose2D, b: Pose2D, metres: float, degrees: float) -> bool:
    return a.distance_to(b) > metres or abs(math.remainder(a.yaw - b.yaw, math.tau)) > math.radians(degrees)


class Watcher:
    """One localiser watched on one storey of ``site`` (module docstring)."""

    def __init__(
        self,
        site: Site,
        storey: str,
        params: WatchParams | None = None,
        registration: RegistrationParams | None = None,
        verification: VerificationParams | None = None,
    ) -> None:
        self.params = params or WatchParams()
        self.verification = verification or VerificationParams()
        reg = replace(registration or RegistrationParams(), enabled=True)
        self.storey = storey
        self.site = site
        self._registration = SubmapRegistration(reg, site, storey, self.verification.scan_tolerance)
        maps = self._registration.maps()
        if not maps:
            raise ValueError(f"storey {storey!r} has no map")
        self.map: RegistrationMap = maps[0]
        self._evidence = StoreyEvidence.of(site.storeys[storey], site_class_map(site))
        self._twins = twin_reason(site, storey)
        self._view = CameraView(NO_CAMERA, NO_MOUNT, 0.0)
        kept = max(reg.window, self.params.submap) + 5.0
        self.scans = RecentScans(kept)
        self.test = CusumTest(self.params)
        self.state = WatchState.WAITING
        self.events: list[WatchEvent] = []
        self.checks: list[WatchCheck] = []
        self.travel = 0.0
        self._odom: list[tuple[float, Pose2D]] = []
        self._transform: Pose2D | None = None  # the localiser's odom -> map, as it last published
        self._stale: Pose2D | None = None  # its transform when it was lost ...
        self._correction: Pose2D | None = None  # ... and the recovery's correction of it
        self._next_check = 0.0
        self._lost_since = 0.0  # travel where the lost pose went wrong
        self._path: PathEvidence | None = None  # the scans since then, while lost
        self._next_attempt = 0.0
        self._next_probe = self.params.probe_every  # travel of the next registration while tracking
        self._why_not = ""
        self._fits: list[tuple[float, float]] = []  # (travel, fit) of the checks of a right pose

    def usual(self) -> float | None:
        """The usual fit: the USUAL_PERCENTILE of the right pose's checks over the last ``usual_m`` m (None
        before USUAL_CHECKS of them over USUAL_SPAN_M)."""
        if len(self._fits) < USUAL_CHECKS or self._fits[-1][0] - self._fits[0][0] < USUAL_SPAN_M:
            return None
        return float(np.percentile([f for _, f in self._fits], USUAL_PERCENTILE))

    # -- inputs ---------------------------------------------------------------------------------

    def odom(self, t: float, pose: Pose2D) -> None:
        if self._odom:
            self.travel += self._odom[-1][1].distance_to(pose)
        self._odom.append((t, pose))
        old = next((i for i, (s, _) in enumerate(self._odom) if t - s <= ODOM_KEPT_S), 0)
        if old:
            del self._odom[:old]

    def localiser(self, t: float, pose: Pose2D) -> None:
        """The localiser's pose (map frame) stamped ``t``: its odom -> map transform then."""
        odom = self._odom_at(t)
        if odom is not None:
            self._transform = pose * odom.inverse()

    def scan(self, t: float, angles: np.ndarray, ranges: np.ndarray, range_max: float) -> list[WatchEvent]:
        """A scan in the base frame at the latest odometry pose; the events it decided."""
        if not self._odom:
            return []
        sample = ScanSample(
            self._odom[-1][1], np.asarray(angles, float), np.asarray(ranges, float), range_max
        )
        if self.scans.add(t, sample, self.travel) and self._path is not None:
            self._path.add_scan(sample.odom, self.travel, sample.angles, sample.ranges, range_max)
        if self._transform is None or self.travel < self._next_check:
            return []
        self._next_check = self.travel + self.params.check_every
        before = len(self.events)
        self._check(t)
        return self.events[before:]

    # -- the localiser's pose --------------------------------------------------------------------

    def _odom_at(self, t: float) -> Pose2D | None:
        if not self._odom or t < self._odom[0][0] - 0.5:
            return None
        for (t0, p0), (t1, p1) in zip(self._odom[:-1], self._odom[1:], strict=True):
            if t0 <= t <= t1:
                s = 0.0 if t1 <= t0 else (t - t0) / (t1 - t0)
                step = p0.inverse() * p1
                return p0 * Pose2D(s * step.x, s * step.y, s * step.yaw)
        return self._odom[0][1] if t < self._odom[0][0] else self._odom[-1][1]

    def watched(self) -> Pose2D | None:
        """The localiser's odom -> map transform as watched: corrected by a recovery while the
        localiser has not moved on from where it was lost (module docstring)."""
        raw = self._transform
        if raw is None or self._stale is None or self._correction is None:
            return raw
        here = self._odom[-1][1]
        if _far(raw * here, self._stale * here, STALE_M, STALE_DEG):
            self._stale = self._correction = None  # it took the pose (or another): its own again
            return raw
        return self._correction * raw

    # -- the checks ------------------------------------------------------------------------------

    def _check(self, t: float) -> None:
        transform = self.watched()
        ends = self.scans.check_ends(self.params.submap)
        if transform is None or ends is None:
            return
        p = self.params
        ev = pose_evidence(
            ends,
            transform,
            self.map.fit,
            self.map.through,
            self.verification.scan_tolerance,
            p.search_m,
            p.search_deg,
        )
        usual = self.usual()
        w = wrongness(ev.fit, ev.through, ev.off_free, p, usual)
        alarm = self.test.update(self.travel, w)
        if self.test.statistic == 0.0 and self.state is not WatchState.LOST:
            if usual is None or ev.fit >= p.usual_share * usual:  # a right pose's fit: learnt
                self._fits.append((self.travel, ev.fit))
                old = next((i for i, (d, _) in enumerate(self._fits) if self.travel - d <= p.usual_m), 0)
                del self._fits[:old]
        if self.state is WatchState.WAITING:
            self.state = WatchState.TRACKING
        if self.state is WatchState.TRACKING and alarm:
            self._suspect(t, transform)
        elif self.state is WatchState.TRACKING and p.probe_every > 0 and self.travel >= self._next_probe:
            self._probe(t, transform)
        elif self.state is WatchState.LOST and self.travel >= self._next_attempt:
            self._recover(t)
        self.checks.append(
            WatchCheck(
                t,
                self.travel,
                transform * ends.last,
                ev.fit,
                ev.through,
                ev.off_free,
                w,
                self.test.statistic,
                self.state,
            )
        )

    def _since_path(self, since: float) -> PathEvidence:
        path = PathEvidence()
        for _, s, d in self.scans.since(since):
            path.add_scan(s.odom, d, s.angles, s.ranges, s.range_max)
        return path

    def _suspect(self, t: float, transform: Pose2D) -> None:
        """The evidence passed the threshold: is there a place that explains the scans since the
        change better than the localiser's pose?"""
        since = self.test.since
        if self.travel - since < self.params.min_scans_m:
            return  # too few scans since the change to register: wait
        path = self._since_path(since)
        found, last = self._registration.attempt(path, self.travel)
        kept = [s for _, s, _ in self.scans.since(since)]
        best = found.best
        statistic = self.test.statistic
        if best is None or last is None or not kept:
            if statistic > UNCONFIRMED * self.params.threshold:
                self._lose(t, since, path, f"evidence {statistic:.2f} and no place fits ({found.why})")
            return
        p = self.params
        fit_mine, fit_best = self._fits_of(kept, transform, best.pose * last.inverse())
        here = kept[-1].odom
        far = _far(transform * here, best.pose * last.inverse() * here, p.confirm_m, p.confirm_deg)
        travelled = self.travel - since
        if far and fit_best >= fit_mine + p.confirm_margin:
            ours, theirs_pose = transform * here, best.pose * last.inverse() * here
            turned = abs(math.degrees(math.remainder(theirs_pose.yaw - ours.yaw, math.tau)))
            self._lose(
                t,
                since,
                path,
                f"over the last {travelled:.1f} m the scans fit the localiser's pose {fit_mine:.2f} (evidence"
                f" {statistic:.2f}), a place {ours.distance_to(theirs_pose):.1f} m and {turned:.0f} degrees"
                f" away {fit_best:.2f}",
            )
            self._recover(t)
        elif not far:
            self.events.append(
                WatchEvent(
                    t,
                    EventKind.SUSPECT,
                    self.travel,
                    f"evidence {statistic:.2f} over {travelled:.1f} m, but the lidar's best place is the"
                    f" localiser's (fit {fit_best:.2f}): kept",
                )
            )
            self.test.reset(self.travel)
            # what a right pose fits here: the checks since the change, the usual fit from now on
            self._fits = [(c.travel, c.fit) for c in self.checks if c.travel >= since]
        elif statistic > UNCONFIRMED * self.params.threshold:
            self._lose(
                t,
                since,
                path,
                f"evidence {statistic:.2f} over {travelled:.1f} m; the scans fit it {fit_mine:.2f}",
            )

    def _probe(self, t: float, transform: Pose2D) -> None:
        """While tracking, every ``watch.probe_every`` m: register the scans of the last
        ``watch.probe_window`` m. A unique place that passes a session's claim checks, far from the
        localiser's pose and fitting those scans clearly better, makes the pose lost (and found)
        though the evidence never piled up: a wrong pose in a place alike."""
        p = self.params
        self._next_probe = self.travel + p.probe_every
        since = max(self.travel - p.probe_window, 0.0)
        if self._twins is not None or self.travel - since < p.min_scans_m:
            return
        path = self._since_path(since)
        found, last = self._registration.attempt(path, self.travel)
        best = found.best
        kept = [s for _, s, _ in self.scans.since(since)]
        if not found.unique or best is None or last is None or not kept:
            return
        theirs = best.pose * last.inverse()
        here = kept[-1].odom
        if not _far(transform * here, theirs * here, p.confirm_m, p.confirm_deg):
            return
        check = verify_transform(
            theirs,
            self._evidence,
            path,
            [],
            self._view,
            claim_params(self.verification, True),
            None,
            found.lines,
        )
        if not check.passed and self.verification.enabled:
            return
        fit_mine, fit_best = self._fits_of(kept, transform, theirs)  # every beam, both alike
        if fit_best < fit_mine + p.confirm_margin:
            return
        self._lose(
            t,
            since,
            path,
            f"the lidar registration of the last {self.travel - since:.1f} m places the robot"
            f" {(transform * here).distance_to(theirs * here):.1f} m from the localiser (the scans fit"
            f" it {fit_best:.2f}, the localiser's pose {fit_mine:.2f}; {found.why})",
        )
        self._recover(t)

    def _fits_of(self, kept: list[ScanSample], mine: Pose2D, theirs: Pose2D) -> tuple[float, float]:
        """The share of every beam end of ``kept`` on the map's walls placed by the localiser's
        transform ``mine`` (aligned within its own error) and by a registration's ``theirs``."""
        ends = check_beams(kept)
        tol, p = self.verification.scan_tolerance, self.params
        a = best_scan_alignment(mine, ends, self.map.fit, tol, p.search_m, math.radians(p.search_deg))
        b = best_scan_alignment(
            theirs, ends, self.map.fit, tol, CONFIRM_SEARCH_M, math.radians(CONFIRM_SEARCH_DEG)
        )
        return (a[0] if a else 0.0), (b[0] if b else 0.0)

    def _lose(self, t: float, since: float, path: PathEvidence, why: str) -> None:
        self.state = WatchState.LOST
        self._lost_since, self._path, self._next_attempt = since, path, self.travel
        self.events.append(WatchEvent(t, EventKind.LOST, self.travel, why))

    def _recover(self, t: float) -> None:
        """Register the scans since the pose went wrong; claim a unique place that passes the checks."""
        assert self._path is not None
        self._next_attempt = self.travel + self.params.recover_every
        if self._twins is not None:
            self._why_not = self._twins
            return
        found, last = self._registration.attempt(self._path, self.travel)
        best = found.best
        if not found.unique or best is None or last is None:
            self._why_not = found.why
            return
        transform = best.pose * last.inverse()
        params = claim_params(self.verification, True)  # no camera counted: it confirmed nothing here
        check = verify_transform(
            transform, self._evidence, self._path, [], self._view, params, None, found.lines
        )
        if not check.passed and self.verification.enabled:
            self._why_not = f"{found.why}, but it fails the checks ({'; '.join(check.reasons)})"
            return
        here = self._odom[-1][1]
        pose = transform * here
        raw = self._transform
        assert raw is not None
        self._stale, self._correction = raw, transform * raw.inverse()
        self.state = WatchState.TRACKING
        self.test.reset(self.travel)
        self._path = None
        self.events.append(
            WatchEvent(
                t,
                EventKind.RECOVERED,
                self.travel,
                f"lidar registration of the {self.travel - self._lost_since:.1f} m since the pose went wrong:"
                f" {found.why}",
                pose,
                self.storey,
            )
        )

    @property
    def why_not_recovered(self) -> str:
        return self._why_not
