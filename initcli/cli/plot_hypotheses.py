"""``--plot``: the floor plan with the top hypotheses' paths, current poses and mapped features.

Like the paper's Fig. 10: each hypothesis maps the odom path and the confirmed features into the
BIM frame with its odom -> BIM transform; the robot's current pose is an arrow at the path's end.
"""

from __future__ import annotations

import io
import math
from pathlib import Path

import matplotlib

__all__ = ["MARKERS", "plot_hypotheses"]

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bimkit.atomic import write_bytes_atomic  # noqa: E402
from initcli.match.report import MatchReport  # noqa: E402

PLOT_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg")  # the formats --plot writes
MARKERS = {"door": "s", "lift": "^", "stairs": "D"}


def _extent(report: MatchReport, storeys: list[str]) -> tuple[float, float]:
    """Width and height (m) of what is drawn: the storeys' features and walls, and the mapped paths."""
    pts = [np.zeros((0, 2))]
    site = report.site_model
    for storey in storeys:
        model = site.storeys.get(storey) if site is not None else None
        if model is not None:
            pts.append(np.array([[f.x, f.y] for f in model.features]).reshape(-1, 2))
            pts.append(
                np.array([[w.x1, w.y1] for w in model.walls] + [[w.x2, w.y2] for w in model.walls]).reshape(
                    -1, 2
                )
            )
    for h in report.hypotheses:
        pts.append(h.transform.apply(report.odom_path[:, :2]))
    allp = np.vstack(pts)
    if len(allp) == 0:
        return 1.0, 1.0
    span = np.ptp(allp, axis=0)
    return float(span[0]) + 2.0, float(span[1]) + 2.0


def plot_hypotheses(report: MatchReport, out_path: Path | str, dpi: int = 120) -> Path:
    """Draw the report's hypotheses on their storeys' floor plans and save a PNG."""
    out_path = Path(out_path)
    site = report.site_model
    storeys = list(dict.fromkeys(h.storey for h in report.hypotheses)) or list(report.storeys[:1])
    storeys = storeys[:4]
    extent = _extent(report, storeys)
    aspect = extent[1] / max(extent[0], 1e-6)
    height = float(np.clip(9.0 * aspect + 2.0, 3.5, 10.0))
    fig, axes = plt.subplots(len(storeys), 1, figsize=(11, height * len(storeys)), squeeze=False)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    s_xy = np.array([[f.x, f.y] for f in report.features]).reshape(-1, 2)
    for ax, storey in zip(axes[:, 0], storeys, strict=False):
        model = site.storeys.get(storey) if site is not None else None
        if model is not None:
            for w in model.walls:
                ax.plot([w.x1, w.x2], [w.y1, w.y2], color="0.55", lw=0.8, zorder=1)
            for cls in sorted({f.category for f in model.features}):
                pts = np.array([[f.x, f.y] for f in model.features if f.category == cls])
                ax.scatter(
                    pts[:, 0],
                    pts[:, 1],
                    marker=MARKERS.get(cls.lower().rstrip("s"), "o"),
                    s=28,
                    facecolors="none",
                    edgecolors="0.35",
                    lw=0.8,
                    label=f"BIM {cls}",
                    zorder=2,
                )
        for h in report.hypotheses:
            if h.storey != storey:
                continue
            c = colours[(h.rank - 1) % len(colours)]
            path = h.transform.apply(report.odom_path[:, :2])
            ax.plot(
                path[:, 0],
                path[:, 1],
                color=c,
                lw=1.6,
                alpha=0.85,
                zorder=3,
                label=f"#{h.rank} J={h.cost:.2f} conf={h.confidence:.2f}",
            )
            mapped = h.transform.apply(s_xy) if len(s_xy) else s_xy
            ax.scatter(mapped[:, 0], mapped[:, 1], marker="x", color=c, s=40, zorder=4)
            if model is not None:
                ids = {f.id: f for f in model.features}
                for (mx, my), bid in zip(mapped, h.matches, strict=False):
                    if bid is not None and bid in ids:
                        ax.plot([mx, ids[bid].x], [my, ids[bid].y], color=c, lw=0.7, ls=":", zorder=4)
            p = h.reported_pose
            ax.quiver(
                p.x,
                p.y,
                math.cos(p.yaw),
                math.sin(p.yaw),
                color=c,
                angles="xy",
                scale_units="xy",
                scale=0.8,
                width=0.006,
                zorder=5,
            )
        if report.truth is not None:
            t = report.truth
            ax.plot(t.x, t.y, marker="*", color="k", ms=12, zorder=6, label="truth")
        ax.set_aspect("equal")
        ax.set_title(f"storey {storey!r}" if storey else "floor plan")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, borderaxespad=0.0)
    fig.suptitle(f"bim-init match: {report.verdict}")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, dpi=dpi, format=out_path.suffix.lower().lstrip(".") or "png")
    plt.close(fig)
    write_bytes_atomic(out_path, buffer.getvalue())
    return out_path
