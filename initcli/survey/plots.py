"""The survey map: the distance to a unique match over the floor plan, never-unique places marked."""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from bimkit.atomic import write_bytes_atomic
from bimtools.fonts import unicode_fonts
from initcli.survey.landmarks import Landmark
from initcli.survey.run import StoreySurvey
from initcli.survey.spaces import SHUT_IN_LABEL

LIDAR_TWIN_LABEL = "lidar twin, doors shut: camera off, alike to the lidar"

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import PathCollection
    from matplotlib.colors import Normalize

__all__ = ["survey_png"]


def _panel(
    ax: Axes,
    result: StoreySurvey,
    title: str,
    landmarks: list[Landmark],
    norm: Normalize,
    points_per_m: float,
) -> PathCollection:
    plan = result.plan
    for x1, y1, x2, y2 in plan.occluders:
        ax.plot([x1, x2], [y1, y2], color="0.35", lw=0.6, zorder=1)
    value = result.position_distance
    never = result.position_never >= 0.5
    pos = plan.positions
    size = result.params.spacing
    sc = ax.scatter(
        pos[~never, 0],
        pos[~never, 1],
        c=value[~never],
        cmap="viridis_r",
        norm=norm,
        marker="s",
        s=(size * points_per_m) ** 2,  # one square per sample position, edge to edge
        linewidths=0,
        zorder=2,
    )
    if never.any():
        ax.scatter(
            pos[never, 0],
            pos[never, 1],
            marker="x",
            color="crimson",
            s=14,
            lw=0.8,
            zorder=3,
            label="never unique (most headings)",
        )
    _shut_in(ax, result, points_per_m)
    _lidar_twins(ax, result)
    base = len(plan.features) - len(landmarks)
    f = plan.features
    for cls in sorted(set(f.cls[:base])):
        idx = [i for i in range(base) if f.cls[i] == cls]
        ax.scatter(
            f.xy[idx, 0], f.xy[idx, 1], s=16, marker="o", edgecolors="k", linewidths=0.5, zorder=4, label=cls
        )
    for k, lm in enumerate(landmarks):
        ax.scatter([lm.x], [lm.y], s=110, marker="*", color="orange", edgecolors="k", zorder=5)
        # Numbered, above and below in turn: neighbouring suggestions do not write over each other.
        ax.annotate(
            str(k + 1),
            (lm.x, lm.y),
            textcoords="offset points",
            xytext=(4, 6 if k % 2 == 0 else -12),
            fontsize=8,
            fontweight="bold",
        )
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper right", fontsize=6, markerscale=0.8)
    return sc


MAX_ROOM_LABELS = 12  # more shut-in rooms than this: the legend names them, not each room


def _shut_in(ax: Axes, result: StoreySurvey, points_per_m: float) -> None:
    """Grey squares over the rooms closed off by their doors, labelled: a robot there is shut in."""
    plan = result.plan
    if not plan.shut_in or plan.shut_in_cells is None:
        return
    grid = plan.circulation.grid
    step = max(1, round(result.params.spacing / grid.resolution))
    rows, cols = np.nonzero(plan.shut_in_cells)
    pick = (rows % step == 0) & (cols % step == 0)
    x, y = grid.cell_centre(rows[pick], cols[pick])
    size = step * grid.resolution
    ax.scatter(x, y, marker="s", s=(size * points_per_m) ** 2, color="0.82", linewidths=0, zorder=1.5)
    ax.scatter([], [], marker="s", s=16, color="0.82", label=f"shut in: {SHUT_IN_LABEL}")  # the legend's
    if len(plan.shut_in) <= MAX_ROOM_LABELS:
        for room in plan.shut_in:
            ax.annotate(
                SHUT_IN_LABEL, (room.x, room.y), fontsize=5, ha="center", va="center", color="0.3", zorder=6
            )


def _lidar_twins(ax: Axes, result: StoreySurvey) -> None:
    """Hatching over the spaces a lidar alone cannot tell from their twins (doors shut)."""
    plan = result.plan
    cells = plan.lidar_twin_cells
    if not plan.lidar_twins or cells is None:
        return
    grid = plan.circulation.grid
    x, _ = grid.cell_centre(0, np.arange(cells.shape[1]))
    _, y = grid.cell_centre(np.arange(cells.shape[0]), 0)
    ax.contourf(x, y, cells.astype(float), levels=[0.5, 1.5], colors="none", hatches=["///"], zorder=2.5)
    ax.fill([], [], facecolor="none", edgecolor="0.2", hatch="///", label=LIDAR_TWIN_LABEL)  # the legend's


@unicode_fonts  # storey names in any script: DejaVu Sans, then any CJK font installed
def survey_png(
    path: Path,
    result: StoreySurvey,
    with_landmarks: StoreySurvey | None = None,
    landmarks: list[Landmark] | None = None,
) -> None:
    """``survey_<storey>.png``: the heat map; with landmarks, a second panel with them placed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize

    panels: list[tuple[StoreySurvey, str, list[Landmark]]] = [(result, "distance to a unique match", [])]
    if with_landmarks is not None:
        panels.append((with_landmarks, f"with {len(landmarks or [])} suggested landmark(s)", landmarks or []))
    norm = Normalize(0.0, max(20.0, float(result.position_distance.max(initial=0.0))))
    occ = result.plan.occluders.reshape(-1, 4)
    width = float(np.ptp(occ[:, [0, 2]])) if len(occ) else 1.0
    height = float(np.ptp(occ[:, [1, 3]])) if len(occ) else 1.0
    aspect = max(width, 1.0) / max(height, 1.0)
    # Wide floors (a corridor block) one above the other, compact ones side by side.
    stacked = aspect > 1.4 and len(panels) > 1
    rows, cols = (len(panels), 1) if stacked else (1, len(panels))
    panel_w = 9.0 if stacked else 6.5
    panel_h = min(max(panel_w / aspect, 2.2), 7.0) + 0.9
    fig, axes = plt.subplots(
        rows, cols, figsize=(panel_w * cols + 1.2, panel_h * rows), squeeze=False, layout="constrained"
    )
    flat = list(axes.flat)
    # Data metres to points in each panel (its axes fill about the panel less labels and legend).
    points_per_m = 72.0 * min((panel_w - 1.0) / (1.05 * width), (panel_h - 1.2) / (1.05 * height))
    scatters = []
    for ax, (res, title, lms) in zip(flat, panels, strict=True):
        mean = float(res.position_distance.mean()) if len(res.position_distance) else float("nan")
        twin = res.plan.twin
        alike = (
            ""
            if twin is None
            else f"\nself-similar, the same turned {twin.degrees:.0f} deg (+): no start initialises"
        )
        scatters.append(
            _panel(ax, res, f"{res.plan.name}: {title} (mean {mean:.1f} m){alike}", lms, norm, points_per_m)
        )
        if twin is not None:
            ax.plot(*twin.centre, marker="+", markersize=10, color="crimson", zorder=7)
    fig.colorbar(scatters[-1], ax=flat, label="m driven to a unique match\n(mean over headings)", shrink=0.9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())
