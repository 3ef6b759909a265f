"""The lidar submap registration (beyond the paper; ``registration:`` settings), for the session
and for ``bim-init match``.

The session: with no camera claim, every ``registration.every`` m of travel from
``registration.min_travel`` on, the scans of the last ``registration.window`` m are registered over
every storey's map (:func:`initcli.core.lidar.registration.register`); a unique registration becomes a
hypothesis that the claim checks judge as they judge a camera claim
(:meth:`initcli.session.claims.ClaimChecks.registered`) before the session fine-tunes it.

``bim-init match`` (:func:`check_and_register`): when the features leave no unique verdict, the log
is replayed as a session gathered it and its submap registered where a session registers it (every
``registration.every`` m from ``registration.min_travel``); the first unique registration that
passes the same checks is the verdict, ``decided_by`` ``lidar registration``
(:func:`replay_registration`).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path

import numpy as np

from bimtools.site.load import Site, StoreyModel, load_site
from bimtools.site.records import Feature
from initcli.config.building import twin_reason
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import DetectionFilter
from initcli.core.filters.particle_filter import likelihood_field
from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.ranking import Verdict
from initcli.core.lidar.registration import (
    GRID,
    Candidate,
    Registration,
    RegistrationMap,
    open_doorways,
    register,
    shut_doorways,
)
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import BeamEnds, ScanSample
from initcli.core.lidar.wall_beams import wall_beams
from initcli.core.verify.checks import CameraView, Verification
from initcli.core.verify.params import VerificationParams
from initcli.io.detection_log import DetectionLog, Scan, read_log
from initcli.match.load import site_class_map
from initcli.match.report import DECIDED_BY_REGISTRATION, Hypothesis, MatchReport, RegistrationRecord
from initcli.match.sightings import sightings_from_log
from initcli.verify.evidence import (
    SCAN_BEAM_STEP,
    TRACK_BEAM_STEP,
    PathEvidence,
    StoreyEvidence,
    camera_blind,
    check_loaded,
    claim_params,
    verify_transform,
)

__all__ = [
    "DECIDED_BY_REGISTRATION",
    "SubmapRegistration",
    "check_and_register",
    "door_openings",
    "registered_hypothesis",
    "registration_record",
    "replay_registration",
    "storey_registration_map",
]


class SubmapRegistration:
    """When to register, and the storeys' maps prepared for it (once, on the first attempt)."""

    def __init__(self, params: RegistrationParams, site: Site, storey: str | None, tolerance: float) -> None:
        self.params = params
        self.site = site
        self.storey = storey  # None: every storey
        self.tolerance = tolerance  # verification.scan_tolerance
        self.next_at = params.min_travel  # m of travel of the next attempt
        self.attempts = 0
        self._maps: list[RegistrationMap] | None = None

    def due(self, travel: float) -> bool:
        return self.params.enabled and travel >= self.next_at

    def maps(self) -> list[RegistrationMap]:
        if self._maps is None:
            names = [self.storey] if self.storey is not None else list(self.site.storeys)
            cmap = site_class_map(self.site)
            found = (storey_registration_map(name, self.site.storeys[name], cmap) for name in names)
            self._maps = [m for m in found if m is not None]
        return self._maps

    def _submap_scans(self, path: PathEvidence, lines: float) -> list[ScanSample]:
        """The scans of the last ``window`` m and the newest one, every sixth beam; with ``lines``
        m, only the beams on straight lines that long (found on every beam) of each."""
        scans, _ = path.along(self.params.window, raw=lines > 0)
        newest = path.latest_raw if lines > 0 else (path.scans[-1] if path.scans else None)
        if newest is not None and (not scans or newest.odom != scans[-1].odom):
            # the newest scan too (a turn on the spot adds no travel, so no scan along the path)
            scans = [*scans, newest if lines > 0 else newest.thinned(TRACK_BEAM_STEP)]
        if lines <= 0:
            return scans
        return [wall_beams(s, lines).thinned(SCAN_BEAM_STEP * TRACK_BEAM_STEP) for s in scans]

    def attempt(self, path: PathEvidence, travel: float) -> tuple[Registration, Pose2D | None]:
        """Register the submap of the recent path: the outcome, and the odom pose of the submap's last
        scan (a candidate's transform, odom -> BIM, is its pose times that pose's inverse; None
        without scans). Where every beam fits the map too poorly for a claim (below ``min_fit``:
        the scans see what the map lacks, furniture, people, stacks), the submap is registered again
        on its wall beams alone (``wall_lines``), as a building model draws walls."""
        self.next_at = travel + self.params.every
        self.attempts += 1
        found, last = self._register(path, 0.0)
        best = found.best
        if self.params.wall_lines > 0 and best is not None and best.fit < self.params.min_fit:
            walls, at = self._register(path, self.params.wall_lines)
            if walls.best is not None:
                return replace(walls, why=f"on its wall beams: {walls.why}", lines=self.params.wall_lines), at
        return found, last

    def _register(self, path: PathEvidence, lines: float) -> tuple[Registration, Pose2D | None]:
        scans = self._submap_scans(path, lines)
        if not scans or not self.maps():
            return Registration((), False, "no scans" if not scans else "no map", 0), None
        ends = BeamEnds.of(scans)
        return register(ends, self.maps(), self.params, self.tolerance), ends.last


def storey_registration_map(name: str, storey: StoreyModel, cmap: ClassMap) -> RegistrationMap | None:
    """A storey's map prepared for the registration (None: it has no map): placed and scored on
    with its doors shut, the wall-crossing test on the map as drawn and with its doors open."""
    if storey.grid is None:
        return None
    doors = door_openings(storey.features, cmap)
    field_ = likelihood_field(storey.grid)
    through = fit = field_  # no doors: the map as drawn, doors open or shut
    if len(doors):
        opened = open_doorways(storey.grid, doors, GRID.door_slack, GRID.door_depth, GRID.door_front)
        through = likelihood_field(opened)
        shut = shut_doorways(storey.grid, doors, GRID.door_slack, GRID.door_depth, GRID.door_front)
        fit = likelihood_field(shut)
    return RegistrationMap(name, storey.grid, field_, through=through, fit=fit)


def door_openings(features: Iterable[Feature], cmap: ClassMap) -> np.ndarray:
    """(N, 5) rows of x, y, normal x, y and width of the storey's doors (IfcDoor or a subclass, or
    features of class door or lift: a lift's landing door), for
    :func:`initcli.core.lidar.registration.open_doorways`."""
    rows = [
        (f.x, f.y, f.norm_x, f.norm_y, f.width)
        for f in features
        if f.ifc_class.startswith("IfcDoor") or cmap.canonical(f.category) in ("door", "lift")
    ]
    return np.array(rows, dtype=float).reshape(-1, 5)


def registered_hypothesis(storey: str, transform: Pose2D, odom: Pose2D) -> Hypothesis:
    """A unique registration as the hypothesis a claim is made of (no feature matched)."""
    pose = transform * odom
    return Hypothesis(
        rank=1,
        storey=storey,
        assignment=(),
        matches=[],
        n_outliers=0,
        cost=0.0,
        pose=pose,
        rectified_pose=None,
        transform=transform,
        confidence=1.0,
        support=1,
    )


def registration_record(claim: Candidate, found: Registration, blind: bool) -> RegistrationRecord:
    """What a registration claim adds to its coarse verification (summary.json, its ``as_dict``)
    and to ``bim-init match``'s report: its fit, its best distinct rival's fit, whether negative
    evidence counted (not when the camera is ``blind``) and, when places alike were ruled out by
    their beams through walls, the shares of such beams (the claim's, then theirs)."""
    rival = next((c for c in found.candidates if c is not claim), None)
    ruled_out = bool(found.contested and found.through)  # places alike, by their beams through walls
    return RegistrationRecord(
        fit=claim.fit,
        rival_fit=None if rival is None else rival.fit,
        negative_evidence=not blind,
        through=found.through if ruled_out else None,
        doors_open=found.doors_open if ruled_out else None,
    )


def check_and_register(
    log_path: Path,
    site_path: Path,
    report: MatchReport,
    skip_bad: bool,
    shown: int,
    params: RegistrationParams,
) -> list[Verification | None]:
    """:func:`initcli.verify.evidence.check_hypotheses`, then, when the verdict is not unique,
    :func:`replay_registration` (``params.enabled``)."""
    log, site = read_log(log_path, skip_bad=skip_bad), load_site(site_path)
    checks = check_loaded(log, site, report, shown)
    return replay_registration(log, site, report, checks, params, shown)


def replay_registration(
    log: DetectionLog,
    site: Site,
    report: MatchReport,
    checks: list[Verification | None],
    params: RegistrationParams,
    shown: int,
    verification: VerificationParams | None = None,
) -> list[Verification | None]:
    """A ``bim-init match`` verdict that is not unique (no features, several places, or a unique
    match the checks refused), made unique by the lidar as a session claims it: the log replayed
    as a session gathered it, its submap registered where a session registers it (every
    ``params.every`` m of travel from ``params.min_travel``), the first unique registration that
    passes the checks of a session's registration claim (:func:`initcli.verify.evidence.claim_params`:
    no negative evidence from a camera that saw nothing so far) is claimed. Its place, carried by
    odometry to the log's last odom pose, goes first in ``report`` (Algorithm 1's hypotheses below
    it, at most ``shown`` in all), ``decided_by`` ``lidar registration``, ``paper_verdict``
    Algorithm 1's. Returns the checks in the report's new order (unchanged when nothing is
    claimed)."""
    if (
        not params.enabled
        or report.outcome is Verdict.UNIQUE
        or report.odom_pose is None
        or not log.of_type(Scan)
    ):
        return checks
    verification = verification or VerificationParams()
    storey = None if report.options.storey in (None, "auto") else report.options.storey
    twins = twin_reason(site, storey)
    if twins is not None:  # as a session, which fails at 0 m there: a registration is a coin toss
        report.notes.append(f"lidar registration: not replayed, {twins}")
        return checks
    registration = SubmapRegistration(params, site, storey, verification.scan_tolerance)
    cmap = site_class_map(site)
    seen = sightings_from_log(log, cmap, report.options.edge_margin)
    view = CameraView(log.meta.camera, log.meta.camera_pose, report.options.min_depth)
    # the camera's features confirmed so far (Eq. 3), fed the sightings in log order as a session's
    confirming = DetectionFilter(report.options.filter_params())
    fed = 0
    why = f"{params.min_travel:g} m of travel (registration.min_travel) not reached"
    for path, travel, t in PathEvidence.growing(log):
        if not registration.due(travel):
            continue
        found, last = registration.attempt(path, travel)
        best, why = found.best, found.why
        if not found.unique or best is None or last is None:
            continue
        sightings = [s for s in seen if s.t <= t]
        for s in seen[fed : len(sightings)]:
            confirming.add(s)
        fed = len(sightings)
        # as the session's ClaimChecks.blind: a false box now and then confirms nothing
        blind = camera_blind(len(path.image_poses), len(confirming.result().features))
        transform = best.pose * last.inverse()
        evidence = StoreyEvidence.of(site.storeys[best.storey], cmap)
        confirmed = None if report.landmarks is None else [f for f in report.landmarks if f.t <= t]
        check = verify_transform(
            transform,
            evidence,
            path,
            sightings,
            view,
            claim_params(verification, blind),
            confirmed,
            found.lines,
        )
        if check.passed or not verification.enabled:
            claimed = registered_hypothesis(best.storey, transform, report.odom_pose)
            record = replace(registration_record(best, found, blind), travel=travel, t=t)
            _claim(report, claimed, record, travel, shown)
            return [check, *checks][:shown]
        why = f"{why}, but it fails the checks ({'; '.join(check.reasons)})"
    report.notes.append(
        f"lidar registration: no claim in {registration.attempts} registration(s) along the log,"
        f" the last: {why}"
    )
    return checks


def _claim(
    report: MatchReport, claimed: Hypothesis, record: RegistrationRecord, travel: float, shown: int
) -> None:
    """``report`` made a unique match on the registration's place ``claimed`` (at ``travel`` m)."""
    below = " (its hypotheses listed below)" if report.hypotheses else ""
    report.hypotheses = [claimed, *(replace(h, rank=h.rank + 1) for h in report.hypotheses)][:shown]
    report.paper_verdict = report.paper_verdict or report.verdict
    report.decide(1)
    report.decided_by, report.storey = DECIDED_BY_REGISTRATION, claimed.storey
    report.n_hypotheses += 1
    report.registration = record
    written = record.as_dict()
    report.notes.append(
        f"unique by lidar registration at {travel:.1f} m of travel, as a session claims it (fit"
        f" {written['registration_fit']}, the best distinct place {written['registration_rival_fit']});"
        f" Algorithm 1 left {report.paper_verdict}{below}"
    )
