"""``bim-init match``: a detection log and a site model in, ranked pose hypotheses and a verdict out.

Pipeline (paper §3.3.1-3.3.3, §3.3.5), each step a pure function of :mod:`initcli.core`:

1. Eq. 1-2 -- every detected box (centre + depth) to a point in the odom frame;
2. the detection filter -- sightings to confirmed features S_object (Eq. 3);
3. Algorithm 1 (Eq. 4-9) with outlier tolerance, on every storey searched;
4. sub-matches dropped, ranking by (outliers, cost J of Eq. 14), pose-distinct counting;
5. the pose of each shown hypothesis at the log's last odom record (Eq. 10-13 or rigid);
6. BIM rectification (Eq. 17) with the storey's walls;
7. the verdict: ``unique match``, ``N hypotheses`` or ``no consistent match``
   (:class:`~initcli.core.hypotheses.ranking.Verdict`; the command's exit code for each is
   ``initcli.cli.exit_codes``'s).

This module composes the steps: :mod:`initcli.match.load` reads and checks the inputs,
:mod:`initcli.match.features` makes steps 1-2, :mod:`initcli.match.search` steps 3-7 into the
:class:`~initcli.match.report.MatchReport` of :mod:`initcli.match.report`. The names this module
exported before the split are exported still.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from bimtools.site.load import Site
from initcli.config.matching import MatchOptions
from initcli.core.features.classes import ClassMap
from initcli.core.features.detection_filter import ConfirmedFeature, Sighting
from initcli.core.hypotheses.ranking import Verdict, verdict_text
from initcli.io.detection_log import DetectionLog
from initcli.match.features import confirmed_features
from initcli.match.load import check_classes, current_odom, read_inputs, site_class_map, storeys_searched
from initcli.match.report import DECIDED_BY_LIDAR, DECIDED_BY_PAPER, Hypothesis, MatchReport
from initcli.match.search import ESCALATED_PARTIALS, search, transform_poses_batch

__all__ = [
    "DECIDED_BY_LIDAR",
    "DECIDED_BY_PAPER",
    "ESCALATED_PARTIALS",
    "Hypothesis",
    "MatchOptions",
    "MatchReport",
    "check_classes",
    "current_odom",
    "match_log",
    "run_match",
    "site_class_map",
    "transform_poses_batch",
]


def run_match(
    log_path: Path | str,
    site_path: Path | str,
    options: MatchOptions | None = None,
    source: Path | str | None = None,
) -> MatchReport:
    """The whole ``bim-init match`` pipeline; raises :class:`InputError` on bad input.

    The class mapping is the site folder's (:func:`site_class_map`). ``source``: the file the user
    named, when ``log_path`` was converted from it (a bag), for the messages.
    """
    opts = options or MatchOptions()
    opts.validate()
    log, site = read_inputs(log_path, site_path, opts, source)
    return match_log(log, site, opts, site_class_map(site))


def match_log(
    log: DetectionLog,
    site: Site,
    opts: MatchOptions,
    cmap: ClassMap,
    sightings: Sequence[Sighting] | None = None,
) -> MatchReport:
    """The pipeline on an already-read log and site.

    ``sightings``: the log's sightings (Eq. 1-2) when the caller already holds them, as the online
    session does (it converts each image as it arrives with the same code and ``edge_margin``).

    ``cmap`` maps the log's class names to the site's feature categories: the site folder's mapping
    for ``bim-init match`` (:func:`site_class_map`), the session config's ``detector.classes`` for
    ``bim-init run``. Nothing is read from disk here.
    """
    check_classes(log, cmap, site)
    warnings = list(log.warnings)
    notes: list[str] = []
    features, landmarks, odom_pose, odom_path = confirmed_features(
        log, site, opts, cmap, sightings, warnings, notes
    )
    if not log.detections and not log.features:
        notes.append("the log has no detections records")
    report = MatchReport(
        log=log.path,
        site=Path(site.root),
        verdict=verdict_text(0),
        outcome=Verdict.NONE,
        storey=None,
        storeys=storeys_searched(site, opts),
        features=features,
        hypotheses=[],
        n_hypotheses=0,
        odom_pose=odom_pose,
        odom_path=odom_path,
        options=opts,
        warnings=warnings,
        notes=notes,
        truth=log.truth[-1].pose if log.truth else None,
        site_model=site,
        landmarks=landmarks,
    )
    if len(features) < opts.min_inliers:
        notes.append(
            f"{len(features)} confirmed feature(s); a hypothesis needs at least {opts.min_inliers} "
            f"(a feature is confirmed after {opts.min_sightings} sightings)"
        )
        return report

    # Step 3-4: Algorithm 1 on every storey, then rule 1 (sub-matches) per storey; with no match,
    # one more outlier at a time up to the outlier_share budget. With lidar landmarks: the mixed
    # sequence first (the camera's max_outliers; with two camera features or more every landmark
    # may be an outlier and joins a candidate once it holds two: MatchOptions.landmark_matching);
    # when it has no match, the camera's features alone as without landmarks (landmarks of
    # geometry the BIM lacks never cost a camera match).
    params = opts.match_params()
    camera = [f for f in features if not params.is_landmark(f.cls)]
    if len(camera) < len(features):
        if search(report, site, cmap, features, log, opts, escalate=False):
            if len(camera) < 2 and (report.n_hypotheses == 1 or report.one_place()):
                # Landmarks matched alone to one place within landmark_outlier_share: that verdict
                # stands only as the one with every landmark allowed to be an outlier (at most
                # ESCALATED_PARTIALS partial matches). The budget can rule out the true place and
                # leave a chance or mirror fit (ntu_hallway, camera off, seed 16: a claim 71 m off,
                # turned half round, its true place ruled out in the rival search too).
                budgeted = report.verdict
                every = replace(opts, landmark_outlier_share=1.0)
                search(report, site, cmap, features, log, every, False, ESCALATED_PARTIALS)
                if report.outcome is not Verdict.UNIQUE:
                    notes.append(
                        f"{budgeted} within the lidar landmarks' outlier budget; {report.verdict} with"
                        " every landmark allowed to be geometry the BIM lacks"
                    )
            return report
        if report.overflow and not camera:
            return report  # the landmarks' search overflowed, the camera saw nothing: far too ambiguous
        if report.overflow:  # the landmarks' search overflowed: the camera's alone decide
            report.overflow, report.n_hypotheses = False, 0
            report.decide(0)
        if len(camera) < opts.min_inliers:
            return report
        notes.append(
            f"no match with the {len(features) - len(camera)} lidar landmark(s); matched the camera's "
            f"{len(camera)} feature(s) alone"
        )
        report.features = features = _renumbered(camera)
    search(report, site, cmap, features, log, opts, escalate=True)
    return report


def _renumbered(features: Sequence[ConfirmedFeature]) -> list[ConfirmedFeature]:
    return [replace(f, index=i) for i, f in enumerate(features)]
