"""Preview plot of one storey: walls, obstacles and features (category, normal, ID), with a legend
and a metric scale bar."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Polygon as PolygonPatch  # noqa: E402
from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar  # noqa: E402

from bimtools.extract.section import polygons_of  # noqa: E402
from bimtools.site.records import Feature, WallSegment  # noqa: E402

CATEGORY_STYLE = {
    "Door": ("tab:blue", "s"),
    "Lift": ("tab:red", "^"),
    "Stairs": ("tab:green", "D"),
}
_EXTRA_COLOURS = ["tab:purple", "tab:orange", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]


def category_style(category: str, index: int = 0) -> tuple[str, str]:
    return CATEGORY_STYLE.get(category, (_EXTRA_COLOURS[index % len(_EXTRA_COLOURS)], "o"))


def _scale_length(span: float) -> float:
    for step in (1, 2, 5, 10, 20, 50, 100):
        if span / step < 6:
            return float(step)
    return 200.0


def draw_floorplan(ax, obstacles, walls: list[WallSegment], outline=None) -> None:
    """Obstacle footprints (grey), wall surfaces (black) and the building outline (dashed)."""
    if outline is not None:
        for poly in polygons_of(outline):
            x, y = poly.exterior.xy
            ax.plot(x, y, color="0.6", lw=0.6, ls="--", zorder=1)
    for area in obstacles:
        for poly in polygons_of(area):
            ax.add_patch(PolygonPatch(list(poly.exterior.coords), closed=True, fc="0.8", ec="none", zorder=2))
    for w in walls:
        ax.plot([w.x1, w.x2], [w.y1, w.y2], color="k", lw=0.7, zorder=3)


def draw_features(ax, features: list[Feature], label_ids: bool = True) -> None:
    extra = sorted({f.category for f in features} - set(CATEGORY_STYLE))
    seen: set[str] = set()
    span = 1.0
    if features:
        xs = [f.x for f in features]
        ys = [f.y for f in features]
        span = max(max(xs) - min(xs), max(ys) - min(ys), 1.0)
    arrow = max(0.6, span / 40)
    for f in features:
        colour, marker = category_style(f.category, extra.index(f.category) if f.category in extra else 0)
        ax.plot(f.x, f.y, marker=marker, color=colour, ms=6, ls="none", zorder=5,
                label=f.category if f.category not in seen else None)
        seen.add(f.category)
        ax.annotate("", xy=(f.x + f.norm_x * arrow, f.y + f.norm_y * arrow), xytext=(f.x, f.y),
                    arrowprops={"arrowstyle": "->", "color": colour, "lw": 1.0}, zorder=6)
        if label_ids:
            ax.text(f.x + f.norm_x * arrow * 1.3, f.y + f.norm_y * arrow * 1.3, f.id, fontsize=4, color=colour,
                    ha="center", va="center", zorder=7)


def add_scale_bar(ax, span: float) -> None:
    length = _scale_length(span)
    bar = AnchoredSizeBar(ax.transData, length, f"{length:g} m", "lower right", pad=0.5, frameon=True,
                          size_vertical=span / 500)
    ax.add_artist(bar)


def render_preview(path: Path, title: str, obstacles, walls: list[WallSegment], features: list[Feature],
                   outline=None) -> None:
    """Write a PNG of the storey plan with its features."""
    bounds = outline.bounds if outline is not None and not outline.is_empty else None
    if bounds is None:
        xs = [w.x1 for w in walls] + [w.x2 for w in walls] + [f.x for f in features]
        ys = [w.y1 for w in walls] + [w.y2 for w in walls] + [f.y for f in features]
        bounds = (min(xs), min(ys), max(xs), max(ys))
    width = max(bounds[2] - bounds[0], 1.0)
    height = max(bounds[3] - bounds[1], 1.0)
    scale = 14.0 / max(width, height)
    fig, ax = plt.subplots(figsize=(max(6.0, width * scale + 1.5), max(4.5, height * scale + 1.5)))
    draw_floorplan(ax, obstacles, walls, outline)
    draw_features(ax, features)
    ax.set_aspect("equal")
    margin = 0.05 * max(width, height)
    ax.set_xlim(bounds[0] - margin, bounds[2] + margin)
    ax.set_ylim(bounds[1] - margin, bounds[3] + margin)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    add_scale_bar(ax, max(width, height))
    if features:
        ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
