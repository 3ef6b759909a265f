"""The survey map: the distance to a unique match over the floor plan, never-unique places marked."""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING

from bimtools.site.atomic import write_bytes_atomic
from initcli.survey.survey import Landmark, StoreySurvey

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import PathCollection
    from matplotlib.colors import Normalize


def _panel(
    ax: Axes, result: StoreySurvey, title: str, landmarks: list[Landmark], norm: Normalize
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
        s=(size * 2.2) ** 2 * 6,
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
    base = len(plan.features) - len(landmarks)
    f = plan.features
    for cls in sorted(set(f.cls[:base])):
        idx = [i for i in range(base) if f.cls[i] == cls]
        ax.scatter(
            f.xy[idx, 0], f.xy[idx, 1], s=16, marker="o", edgecolors="k", linewidths=0.5, zorder=4, label=cls
        )
    for lm in landmarks:
        ax.scatter([lm.x], [lm.y], s=110, marker="*", color="orange", edgecolors="k", zorder=5)
        ax.annotate(lm.cls, (lm.x, lm.y), textcoords="offset points", xytext=(5, 5), fontsize=7)
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.legend(loc="upper right", fontsize=6, markerscale=0.8)
    return sc


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
    fig, axes = plt.subplots(1, len(panels), figsize=(7.5 * len(panels), 6.5), squeeze=False)
    scatters = [
        _panel(ax, res, f"{res.plan.name}: {title}", lms, norm)
        for ax, (res, title, lms) in zip(axes[0], panels, strict=True)
    ]
    fig.colorbar(
        scatters[-1], ax=list(axes[0]), label="m driven to a unique match (mean over headings)", shrink=0.8
    )
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    plt.close(fig)
    write_bytes_atomic(path, buf.getvalue())
