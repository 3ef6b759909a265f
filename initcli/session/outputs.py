"""What a session leaves behind: ``summary.json`` and ``report.png``."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from bimtools.fonts import unicode_fonts
from bimtools.site.load import StoreyModel
from initcli.core.geometry.se2 import SESSION_DIGITS, Pose2D, pose_json
from initcli.session.result import SessionResult

__all__ = ["render_report", "report_title", "summary_document", "write_summary"]

PLAN_MARGIN_M = 2.0  # m of the report's plan round the storey's walls and the true path
ZOOM_MIN_M = 3.0  # m: the smallest side of the inset round the final pose
INSET_HEIGHT = 0.48  # of the plan's height: the inset round the final pose
INSET_GAP_PT = 18.0  # points: room for the inset's title under the legend


def _pose(p: Pose2D | None) -> dict | None:
    return None if p is None else pose_json(p, SESSION_DIGITS)


def summary_document(result: SessionResult, simulated: bool, extra: dict | None = None) -> dict:
    trans, rot = result.errors()
    doc = {
        "success": result.success,
        "reason": result.reason,
        "storey": result.storey,
        "pose": _pose(result.pose),
        "covariance": None
        if result.covariance is None
        else [[round(float(v), 6) for v in row] for row in result.covariance],
        "coarse_pose": _pose(result.coarse_pose),
        "rectified_pose": _pose(result.rectified_pose),
        "features_detected": result.features_detected,
        "matched_ids": result.matched_ids,
        "distance_coarse_m": result.distance_coarse_m,
        "distance_total_m": round(result.distance_total_m, 3),
        "duration_s": round(result.duration_s, 2),
        "wall_clock_s": round(result.wall_seconds, 2),
        "active_explorations": result.active_explorations,
        "recoveries": result.recoveries,
        "loop_escapes": result.loop_escapes,
        "crossings": result.crossings,
        # Beyond the paper: each check of a unique match (stage coarse) and of the final pose (fine):
        # missed_predictions, scan_fit, passed (initcli.core.verify.checks).
        "verification": list(result.verifications),
        "rejected_matches": result.rejected,
        "decided_by": result.decided_by,
        "laps": result.laps,
    }
    if result.shut_in is not None:
        # reason "shut in": the robot went round the space it is in and has no way on it can pass
        shut = result.shut_in
        doc["shut_in"] = {
            "explored_m2": shut.explored_m2,
            "features_seen": shut.features,
            "lap_m": shut.lap_m,
            "advice": shut.advice,
            "message": shut.message,
        }
    if simulated:
        doc["truth_pose"] = _pose(result.truth_pose)
        doc["error_translation_m"] = trans
        doc["error_rotation_deg"] = rot
    if extra:
        doc.update(extra)
    return doc


def write_summary(path: Path, document: dict) -> None:
    Path(path).write_text(json.dumps(document, indent=2) + "\n", encoding="utf-8")


def _ellipse(cov: np.ndarray, scale: float = 2.0) -> np.ndarray:
    values, vectors = np.linalg.eigh(cov[:2, :2])
    values = np.sqrt(np.maximum(values, 0.0)) * scale
    t = np.linspace(0, 2 * math.pi, 60)
    return (vectors @ np.vstack([values[0] * np.cos(t), values[1] * np.sin(t)])).T


def report_title(result: SessionResult, site: str) -> str:
    """Two lines: the site and storey, the outcome and why; what decided the pose, after how many
    metres, and, where the truth is known, the final pose's error beside its sigma."""
    storey = f", storey {result.storey}" if result.storey else ""
    outcome = "initialised" if result.success else "not initialised"
    why = f" - {result.reason}" if result.reason and result.reason != outcome else ""
    first = f"{site}{storey}: {outcome}{why}"
    parts = []
    if result.decided_by is not None:
        after = f" after {result.distance_coarse_m:.1f} m" if result.distance_coarse_m is not None else ""
        parts.append(f"decided by {result.decided_by}{after}")
    if result.pose is not None and result.truth_pose is not None:
        off_m = result.pose.distance_to(result.truth_pose)
        off_deg = math.degrees(result.pose.yaw_error(result.truth_pose))
        parts.append(f"final error {off_m:.2f} m, {off_deg:.1f} deg")
    if result.covariance is not None:
        sigma = math.sqrt(max(float(np.linalg.eigvalsh(result.covariance[:2, :2]).max()), 0.0))
        parts.append(f"sigma {sigma:.2f} m")
    return first + ("\n" + "; ".join(parts) if parts else "")


def _plan_limits(
    storey: StoreyModel, result: SessionResult
) -> tuple[tuple[float, float], tuple[float, float]] | None:
    """The x and y limits of the report's plan: the storey's walls and the true path, with a margin
    (a hypothesis far outside the building is not what the picture is about)."""
    xy = [np.array([[w.x1, w.y1], [w.x2, w.y2]]) for w in storey.walls]
    xy += [np.array(result.true_path)[:, :2]] if result.true_path else []
    if not xy:
        return None
    pts = np.vstack(xy)
    lo, hi = pts.min(axis=0) - PLAN_MARGIN_M, pts.max(axis=0) + PLAN_MARGIN_M
    return (float(lo[0]), float(hi[0])), (float(lo[1]), float(hi[1]))


def _zoom(
    ax: Any, result: SessionResult, storey: StoreyModel, world_segments: np.ndarray | None, top: float
) -> None:
    """An inset beside the plan round the final pose: the coarse, rectified and final poses, the
    truth and the covariance ellipse, at a scale where they can be told apart; its top at ``top``
    (axes fraction: under the legend)."""
    from matplotlib.collections import LineCollection

    pose = result.pose
    assert pose is not None
    inset = ax.inset_axes([1.03, top - INSET_HEIGHT, 0.34, INSET_HEIGHT])
    pts = [np.array([[pose.x, pose.y]])]
    for other in (result.coarse_pose, result.rectified_pose, result.truth_pose):
        if other is not None and other.distance_to(pose) < 5.0:
            pts.append(np.array([[other.x, other.y]]))
    ring = None
    if result.covariance is not None:
        ring = _ellipse(result.covariance) + [pose.x, pose.y]
        if np.ptp(ring, axis=0).max() < 10.0:
            pts.append(ring)
    box = np.vstack(pts)
    centre = (box.min(axis=0) + box.max(axis=0)) / 2
    half = max(ZOOM_MIN_M, float(np.ptp(box, axis=0).max()) * 1.4) / 2
    if world_segments is not None and len(world_segments):
        segments = list(world_segments.reshape(-1, 2, 2))
        inset.add_collection(LineCollection(segments, colors="tab:orange", linewidths=1.0, alpha=0.7))
    walls = [((w.x1, w.y1), (w.x2, w.y2)) for w in storey.walls]
    inset.add_collection(LineCollection(walls, colors="0.25", linewidths=0.8))
    if result.true_path:
        true = np.array(result.true_path)
        inset.plot(true[:, 0], true[:, 1], color="tab:green", lw=1.0)
    arrow = 0.35 * half  # m: the poses' arrows
    for other, colour, marker in (
        (result.coarse_pose, "tab:orange", "o"),
        (result.rectified_pose, "tab:purple", "s"),
        (pose, "tab:red", "^"),
    ):
        if other is not None:
            inset.plot([other.x], [other.y], marker=marker, mfc="none", mec=colour, ms=9, ls="none")
            dx, dy = arrow * math.cos(other.yaw), arrow * math.sin(other.yaw)
            inset.annotate(
                "",
                (other.x + dx, other.y + dy),
                (other.x, other.y),
                arrowprops={"color": colour, "width": 1.5, "headwidth": 6},
            )
    if ring is not None:
        inset.plot(ring[:, 0], ring[:, 1], color="tab:red", lw=1.0)
    if result.truth_pose is not None:
        t = result.truth_pose
        inset.plot([t.x], [t.y], marker="*", color="tab:green", ms=12, ls="none", zorder=7)
    inset.set_xlim(centre[0] - half, centre[0] + half)
    inset.set_ylim(centre[1] - half, centre[1] + half)
    inset.set_aspect("equal")
    inset.tick_params(labelsize=7)
    inset.set_title(f"the final pose, {2 * half:.1f} m across", fontsize=8)


def _draw_poses(ax: Any, result: SessionResult) -> None:
    """The coarse, rectified and final poses, the covariance ellipse and the true final pose."""
    for label, pose, pose_colour in (
        ("coarse", result.coarse_pose, "tab:orange"),
        ("rectified (Eq. 17)", result.rectified_pose, "tab:purple"),
        ("final", result.pose, "tab:red"),
    ):
        if pose is not None:
            ax.quiver(
                [pose.x],
                [pose.y],
                [math.cos(pose.yaw)],
                [math.sin(pose.yaw)],
                color=pose_colour,
                scale=18,
                width=0.006,
                label=f"{label} pose",
                zorder=6,
            )
    if result.pose is not None and result.covariance is not None:
        ring = _ellipse(result.covariance) + [result.pose.x, result.pose.y]
        ax.plot(ring[:, 0], ring[:, 1], color="tab:red", lw=1.0, label="2-sigma covariance")
    if result.truth_pose is not None:
        t = result.truth_pose
        ax.plot(
            [t.x], [t.y], marker="*", color="tab:green", ms=12, ls="none", label="true final pose", zorder=7
        )


@unicode_fonts  # storey names in any script: DejaVu Sans, then any CJK font installed
def render_report(
    path: Path,
    result: SessionResult,
    storey: StoreyModel,
    title: str,
    world_segments: np.ndarray | None = None,
) -> None:
    """Floor plan, true path, odometry path mapped through the final pose, features, hypotheses
    at each matching step, and the final pose with its covariance ellipse. ``world_segments``:
    (S, 4) outlines of the simulated site as built (hoardings, door leaves, clutter), drawn under
    the BIM where the simulated world is not the BIM."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.artist import Artist
    from matplotlib.collections import LineCollection

    fig, ax = plt.subplots(figsize=(13, 8))
    if world_segments is not None and len(world_segments):
        ax.add_collection(
            LineCollection(
                list(world_segments.reshape(-1, 2, 2)),
                colors="tab:orange",
                linewidths=1.0,
                alpha=0.7,
                label="site as built (simulated)",
            )
        )
    lines = [((w.x1, w.y1), (w.x2, w.y2)) for w in storey.walls]
    ax.add_collection(LineCollection(lines, colors="0.25", linewidths=0.6, label="walls (BIM)"))
    markers = {"Door": "s", "Lift": "^", "Stairs": "D"}
    for category in sorted({f.category for f in storey.features}):
        fs = [f for f in storey.features if f.category == category]
        ax.scatter(
            [f.x for f in fs],
            [f.y for f in fs],
            marker=markers.get(category, "o"),
            s=22,
            facecolors="none",
            edgecolors="tab:gray",
            zorder=4,  # above the detections' marks: a lift is not hidden by the cross on it
            label=f"BIM {category}",
        )
    if result.true_path:
        true = np.array(result.true_path)
        ax.plot(true[:, 0], true[:, 1], color="tab:green", lw=1.2, label="true path")
    transform = result.transform
    if transform is not None and result.odom_path:
        mapped = transform.apply(np.array(result.odom_path)[:, :2])
        ax.plot(
            mapped[:, 0], mapped[:, 1], color="tab:blue", lw=1.0, ls="--", label="odometry through final pose"
        )
        if result.features:
            fx = transform.apply(np.array([f.xy for f in result.features]))
            ax.scatter(
                fx[:, 0],
                fx[:, 1],
                marker="x",
                color="tab:red",
                s=25,
                lw=0.8,
                zorder=3,
                label="detected features",
            )
            by_id = {f.id: f for f in storey.features}
            for (x, y), fid in zip(fx, result.matched_ids, strict=False):
                if fid in by_id:
                    ax.plot([x, by_id[fid].x], [y, by_id[fid].y], color="tab:red", lw=0.8)
    cmap = plt.get_cmap("viridis")
    steps = [s for s in result.match_steps if s.poses]
    for k, step in enumerate(steps):
        colour = cmap(k / max(1, len(steps) - 1))
        poses = np.array(step.poses)
        ax.quiver(
            poses[:, 0],
            poses[:, 1],
            np.cos(poses[:, 2]),
            np.sin(poses[:, 2]),
            color=colour,
            scale=40,
            width=0.003,
            alpha=0.8,
            label=f"hypotheses, {step.features} features ({step.verdict})",
        )
    _draw_poses(ax, result)
    ax.set_aspect("equal")
    ax.autoscale_view()
    limits = _plan_limits(storey, result)
    if limits is not None:  # cropped to the building: a hypothesis far outside is clipped
        ax.set_xlim(*limits[0])
        ax.set_ylim(*limits[1])
    ax.set_xlabel("x (m, BIM frame)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    handles, labels = ax.get_legend_handles_labels()
    seen: dict[str, Artist] = {}
    for h, lab in zip(handles, labels, strict=True):
        seen.setdefault(lab, h)
    legend = ax.legend(
        list(seen.values()), list(seen.keys()), fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0)
    )
    if result.pose is not None:
        # under the legend: beside a plan wider than tall the legend reaches below the middle
        ax.apply_aspect()
        below = legend.get_window_extent().transformed(ax.transAxes.inverted())
        gap = INSET_GAP_PT * fig.dpi / 72.0 / ax.get_window_extent().height
        _zoom(ax, result, storey, world_segments, min(INSET_HEIGHT, float(below.y0) - gap))
    fig.savefig(path, dpi=130, bbox_inches="tight")  # the legend and the inset in, no blank canvas
    plt.close(fig)
