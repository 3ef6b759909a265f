"""The thresholds of the checks of :mod:`initcli.core.verify.checks`, each written once with its unit,
range and default (the ``verification:`` section of site.yaml is this record, with the session's
own rival settings added)."""

from __future__ import annotations

from dataclasses import dataclass

from bimkit.settings import setting

__all__ = ["VerificationParams"]


@dataclass
class VerificationParams:
    """Thresholds of the checks (negative evidence, path in free space, scan fit, the lidar along
    the path) and of a claim's rivals."""

    enabled: bool = setting(
        True, "check a unique match before it is claimed (false: claim what Algorithm 1 leaves unique)"
    )
    predict_range: float = setting(
        4.5, "m: a BIM feature farther than this is not predicted to be seen", minimum=0.5, maximum=50
    )
    predict_view_angle_deg: float = setting(
        70.0,
        "degrees from a BIM feature's normal within which it is predicted to be seen (tighter than the"
        " detector's camera.max_view_angle)",
        above=0,
        maximum=90,
    )
    image_margin: float = setting(
        0.1,
        "share of the image width and height kept clear at the borders when predicting a feature in view",
        minimum=0,
        below=0.5,
    )
    min_frames: int = setting(
        4, "images a feature must be predicted in view before a miss counts", minimum=1, maximum=1000
    )
    match_radius: float = setting(
        1.5, "m: a same-category sighting this close explains a predicted feature", minimum=0.05, maximum=10
    )
    p_right: float = setting(
        0.4, "chance that a predicted feature is missed at the right place", minimum=0.01, maximum=0.99
    )
    p_wrong: float = setting(
        0.9, "chance that a predicted feature is missed at a wrong place", minimum=0.01, maximum=0.99
    )
    log_odds: float = setting(
        2.3,
        "natural log of the likelihood ratio of misses that rejects a match (2.3: about 10:1)",
        minimum=0,
        maximum=50,
    )
    # Lidar landmarks missed (beyond the paper; the module doc of initcli.core.verify.checks): the same
    # binomial rule on the storey's corners and openings the lidar should have confirmed.
    landmark_range: float = setting(
        5.0, "m: a lidar landmark farther than this is not predicted to be seen", minimum=0.5, maximum=50
    )
    landmark_view_angle_deg: float = setting(
        40.0,
        "degrees from a lidar landmark's normal (a corner's bisector) within which both its faces are"
        " predicted in sight",
        above=0,
        maximum=90,
    )
    landmark_min_views: int = setting(
        4,
        "scan poses of the path (one per 0.5 m) a lidar landmark must be predicted in view from before a"
        " miss counts",
        minimum=1,
        maximum=1000,
    )
    landmark_match_radius: float = setting(
        0.75,
        "m: a confirmed lidar landmark of the same category this close explains a predicted one",
        minimum=0.05,
        maximum=10,
    )
    # Measured on the samples extracted with landmarks (108 sessions, camera on and off, ideal and as
    # built): at the true place 19-37 % of the predicted landmarks were missed (furniture and stacks
    # hide corners, several at once); at wrong places that passed every other check most were twins
    # whose corners fit as well. At these rates no true-place check failed (at 0.5 / 0.9, 4 of 368);
    # the rule holds back a claim only, never rules out a rival (that would let a claim through).
    landmark_p_right: float = setting(
        0.6, "chance that a predicted lidar landmark is missed at the right place", minimum=0.01, maximum=0.99
    )
    landmark_p_wrong: float = setting(
        0.95, "chance that a predicted lidar landmark is missed at a wrong place", minimum=0.01, maximum=0.99
    )
    landmark_log_odds: float = setting(
        2.3,
        "natural log of the likelihood ratio of lidar landmark misses that rejects a match (the camera's"
        " log_odds apart: a blind camera's misses say nothing, the lidar's still do)",
        minimum=0,
        maximum=50,
    )
    min_scan_fit: float = setting(
        0.65, "share of lidar beams on mapped walls below which the place is wrong", minimum=0, maximum=1
    )
    min_fine_scan_fit: float = setting(
        0.6,
        "min_scan_fit for the fine-tuned pose; the fine-tuning filter's own rule too (a filter that"
        " settles on a fit below it tries once more, wider, then is lost)",
        minimum=0,
        maximum=1,
    )
    scan_tolerance: float = setting(
        0.25, "m: a beam end point this close to a mapped wall fits", minimum=0.01, maximum=2
    )
    scan_search_xy: float = setting(
        0.3, "m: the scan fit is the best over shifts of the pose up to this ...", minimum=0, maximum=5
    )
    # a coarse pose is decimetres and, from doors built off their place, up to 15 degrees off (the
    # fit at a wrong place gains little from turning)
    scan_search_yaw_deg: float = setting(
        12.0, "degrees: ... and turns up to this, in 3-degree steps", minimum=0, maximum=90
    )
    min_path_free: float = setting(
        0.85,
        "share of the last 30 m of the odometry path that must lie on (or within path_margin of) free"
        " BIM cells under the hypothesis",
        minimum=0,
        maximum=1,
    )
    path_margin: float = setting(
        0.3, "m: a path point this close to a free cell counts as free", minimum=0, maximum=5
    )
    min_claim_inliers: int = setting(
        4,
        "matched BIM features a unique match needs before it is claimed (a feature matched again by a"
        " revisit counts once)",
        minimum=2,
        maximum=100,
    )
    rival_outliers: int = setting(
        1,
        "the claim must stay the only pose (no rival rival_distance or rival_turn_deg away with"
        " min_inliers matches that passes the checks and is not outranked) when this many more outliers"
        " are allowed, even a claim that explains every detection (0: only claims that needed outliers"
        " get a rival search; a real Revit model as built was claimed 3 m off with 0 outliers, the true"
        " place one outlier behind)",
        minimum=0,
        maximum=5,
    )
    rival_distance: float = setting(
        2.0, "m: a rival of a claim lies at least this far from it ...", minimum=0, maximum=50
    )
    rival_turn_deg: float = setting(30.0, "degrees: ... or turned at least this much", minimum=0, maximum=180)
    # A rival that passes the checks is still no reason to doubt a claim that it trails by at least
    # this many outliers and this much scan fit (both; 0.0 fit margin and 0 outliers would let any
    # equal rival through, a fit margin of 1 turns it off): see ``outranks``.
    outrank_outliers: int = setting(
        1,
        "a rival that passes the checks does not keep a claim out when it has at least this many more"
        " outliers and a scan fit outrank_scan_fit lower",
        minimum=1,
        maximum=10,
    )
    outrank_scan_fit: float = setting(
        0.05,
        "share of lidar beams on mapped walls a rival that passes the checks must trail the claim by"
        " (with outrank_outliers more outliers) to be no reason to doubt it; 1: every such rival keeps"
        " the claim out",
        minimum=0,
        maximum=1,
    )
    # The lidar along the path (``tracked_scan_fit``): the scans of the last ``track_m`` of travel
    # in windows of ``track_window_m``, each aligned by a small move (up to ``track_search_xy`` m and
    # ``track_search_yaw_deg``) from the alignment of the window after it, so odometry drift is
    # followed back along the path while a place one corridor bay off is not.
    track_m: float = setting(
        80.0,
        "m of the latest path whose lidar scans are fitted to the BIM window by window (each aligned"
        " from the next within track_search_xy and track_search_yaw_deg: odometry drift is followed, a"
        " place a corridor bay away is not); 0: the lidar along the path is not used",
        minimum=0,
        maximum=1000,
    )
    track_window_m: float = setting(
        5.0, "m of path in each window of the lidar along the path", above=0, maximum=100
    )
    track_search_xy: float = setting(
        0.3,
        "m: each window is aligned from the alignment of the next within this shift ...",
        minimum=0,
        maximum=5,
    )
    track_search_yaw_deg: float = setting(6.0, "degrees: ... and this turn", minimum=0, maximum=90)
    # One hypothesis outranks another by the path's scans (``track_outranks``) when it fits some
    # window at least ``track_lead`` better, no window more than ``track_slack`` worse, and none of
    # its own windows below ``min_track_fit``.
    track_lead: float = setting(
        0.2,
        "a hypothesis outranks another (a claim's rival, or one of several hypotheses) when it fits some"
        " window of the path at least this share of beams better ...",
        minimum=0,
        maximum=1,
    )
    track_slack: float = setting(0.05, "... no window more than this share worse ...", minimum=0, maximum=1)
    min_track_fit: float = setting(
        0.65,
        "... and none of its own windows below this share of beams on mapped walls",
        minimum=0,
        maximum=1,
    )
    # ... a lead of track_lead_trailing is enough over a place that needs outrank_outliers more
    # outliers (two weaker pieces of evidence, the doors and the lidar, that agree); and no
    # comparison on fewer than min_track_windows windows (the path of the first few metres is no
    # path: a wrong place outranked the right one on a single window at the initial look).
    track_lead_trailing: float = setting(
        0.1,
        "the lead (instead of track_lead) that outranks a hypothesis needing outrank_outliers more"
        " outliers: the doors and the lidar agree",
        minimum=0,
        maximum=1,
    )
    min_track_windows: int = setting(
        3,
        "windows of the path two hypotheses must share before the lidar along the path compares them"
        " (the first metres are no path yet)",
        minimum=1,
        maximum=200,
    )
    # The place to be outranked may be the true one found imprecisely (doors built off their place):
    # before it is, its newest window is searched this far (about rival_distance / rival_turn_deg) and
    # its path fitted from there; it is outranked only if it still trails.
    track_rival_xy: float = setting(
        2.0,
        "m: a place about to be outranked has its newest window searched this far first (it may be the"
        " true place found imprecisely) ...",
        minimum=0,
        maximum=20,
    )
    track_rival_yaw_deg: float = setting(30.0, "degrees: ... and turned this far", minimum=0, maximum=180)
