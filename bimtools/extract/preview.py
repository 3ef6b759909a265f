"""Preview image of one storey: obstacles, wall surfaces, features by category with their normal
and ID, a legend and a metric scale bar.

Drawn with OpenCV rather than matplotlib: a preview per storey costs milliseconds, so extraction
stays close to the geometry kernel's own time (see benchmarks/bench_extract.py).
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from shapely.geometry.base import BaseGeometry

from bimtools.extract.section import polygons_of
from bimtools.fonts import put_text
from bimtools.site.records import LIDAR, Feature, WallSegment

# BGR colours
CATEGORY_STYLE: dict[str, tuple[tuple[int, int, int], str]] = {
    "Door": ((180, 119, 31), "square"),
    "Lift": ((40, 39, 214), "triangle"),
    "Stairs": ((44, 160, 44), "diamond"),
    # lidar landmarks: small, without IDs (a storey has hundreds)
    "ConcaveCorner": ((160, 60, 160), "dot"),
    "ConvexCorner": ((0, 140, 255), "dot"),
    "ColumnCorner": ((30, 80, 140), "dot"),
    "Opening": ((170, 170, 0), "bar"),
}
LANDMARK_MARKER = 3  # px: half-size of a landmark's marker
_EXTRA_COLOURS = [(189, 103, 148), (14, 127, 255), (75, 86, 140), (194, 119, 227), (34, 189, 188)]
_FONT = cv2.FONT_HERSHEY_SIMPLEX
_WHITE = (255, 255, 255)


def category_style(category: str, index: int = 0) -> tuple[tuple[int, int, int], str]:
    return CATEGORY_STYLE.get(category, (_EXTRA_COLOURS[index % len(_EXTRA_COLOURS)], "circle"))


class Canvas:
    """World metres -> image pixels (y up in the world, down in the image)."""

    def __init__(
        self,
        bounds: tuple[float, float, float, float],
        max_side: int = 2400,
        min_scale: float = 20.0,
        margin_px: int = 60,
    ):
        minx, miny, maxx, maxy = bounds
        span = max(maxx - minx, maxy - miny, 1.0)
        self.scale = max(min_scale, min(80.0, max_side / span))
        self.margin = margin_px
        self.minx, self.maxy = minx, maxy
        width = int((maxx - minx) * self.scale) + 2 * margin_px
        height = int((maxy - miny) * self.scale) + 2 * margin_px + 40
        self.image = np.full((max(height, 300), max(width, 500), 3), 255, dtype=np.uint8)

    def px(self, xy: np.ndarray) -> np.ndarray:
        xy = np.atleast_2d(np.asarray(xy, dtype=float))
        u = (xy[:, 0] - self.minx) * self.scale + self.margin
        v = (self.maxy - xy[:, 1]) * self.scale + self.margin + 40
        return np.round(np.stack([u, v], axis=1)).astype(np.int32)


def _marker(img: np.ndarray, centre: tuple[int, int], shape: str, colour, size: int = 6) -> None:
    x, y = centre
    if shape == "square":
        cv2.rectangle(img, (x - size, y - size), (x + size, y + size), colour, -1, cv2.LINE_AA)
    elif shape == "triangle":
        pts = np.array([[x, y - size - 2], [x - size - 1, y + size], [x + size + 1, y + size]], np.int32)
        cv2.fillPoly(img, [pts], colour, cv2.LINE_AA)
    elif shape == "diamond":
        pts = np.array([[x, y - size - 2], [x + size + 2, y], [x, y + size + 2], [x - size - 2, y]], np.int32)
        cv2.fillPoly(img, [pts], colour, cv2.LINE_AA)
    elif shape == "bar":
        cv2.rectangle(img, (x - size, y - max(size // 2, 1)), (x + size, y + max(size // 2, 1)), colour, -1)
    else:  # circle, dot
        cv2.circle(img, (x, y), size, colour, -1, cv2.LINE_AA)


def _scale_length(span_m: float) -> float:
    for step in (1, 2, 5, 10, 20, 50, 100):
        if span_m / step < 6:
            return float(step)
    return 200.0


def draw_plan(
    canvas: Canvas, obstacles: list[BaseGeometry], walls: list[WallSegment], outline: BaseGeometry | None
) -> None:
    img = canvas.image
    if outline is not None:
        for poly in polygons_of(outline):
            cv2.polylines(
                img,
                [canvas.px(np.asarray(poly.exterior.coords)[:, :2])],
                True,
                (170, 170, 170),
                1,
                cv2.LINE_AA,
            )
    shapes = [
        canvas.px(np.asarray(p.exterior.coords)[:, :2]) for area in obstacles for p in polygons_of(area)
    ]
    if shapes:
        cv2.fillPoly(img, shapes, (205, 205, 205), cv2.LINE_AA)
    for w in walls:
        (a, b) = canvas.px(np.array([[w.x1, w.y1], [w.x2, w.y2]]))
        cv2.line(img, tuple(int(v) for v in a), tuple(int(v) for v in b), (0, 0, 0), 1, cv2.LINE_AA)


LABEL_SCALE = 0.33  # OpenCV font scale of the features' IDs
LABEL_STEPS = (1.35, 1.9, 2.5, 3.1)  # arrow lengths out along the normal tried for an ID ...
LABEL_SHIFTS = (0.0, -1.2, 1.2)  # ... each also moved this many text heights across


def _label_box(
    text: str, x: float, y: float, nx: float, ny: float, arrow: int, taken: list[tuple[int, int, int, int]]
) -> tuple[int, int] | None:
    """Where the ID ``text`` of a feature at pixel (x, y) facing (nx, ny) goes: out along its
    normal past the arrow, the first spot clear of the labels already ``taken`` (x0, y0, x1, y1,
    to which it is added); None where every spot tried overlaps one."""
    (w, h), base = cv2.getTextSize(text, _FONT, LABEL_SCALE, 1)
    for step in LABEL_STEPS:
        for shift in LABEL_SHIFTS:
            cx = x + nx * arrow * step - ny * shift * (h + 4)
            cy = y - ny * arrow * step - nx * shift * (h + 4)
            box = (int(cx - w / 2) - 1, int(cy - h / 2) - 1, int(cx + w / 2) + 1, int(cy + h / 2 + base) + 1)
            if all(box[2] < t[0] or t[2] < box[0] or box[3] < t[1] or t[3] < box[1] for t in taken):
                taken.append(box)
                return int(cx - w / 2), int(cy + h / 2)
    return None


def draw_features(canvas: Canvas, features: list[Feature]) -> list[str]:
    """Markers, normals (arrows) and IDs (an ID that would overlap another is left out, and the
    picture says how many); returns the categories drawn, in order."""
    img = canvas.image
    taken: list[tuple[int, int, int, int]] = []
    labels: list[tuple[Feature, float, float, tuple[int, int, int]]] = []
    hidden = 0
    extra = sorted({f.category for f in features} - set(CATEGORY_STYLE))
    arrow = max(18, int(0.8 * canvas.scale))
    drawn: list[str] = []
    for f in features:
        colour, shape = category_style(f.category, extra.index(f.category) if f.category in extra else 0)
        ((x, y),) = canvas.px(np.array([[f.x, f.y]]))
        if f.sensor == LIDAR:  # a small marker and a short tick along the normal, no ID
            tick = (int(x + f.norm_x * arrow * 0.4), int(y - f.norm_y * arrow * 0.4))
            cv2.line(img, (int(x), int(y)), tick, colour, 1, cv2.LINE_AA)
            _marker(img, (int(x), int(y)), shape, colour, LANDMARK_MARKER)
            if f.category not in drawn:
                drawn.append(f.category)
            continue
        tip = (int(x + f.norm_x * arrow), int(y - f.norm_y * arrow))
        cv2.arrowedLine(img, (int(x), int(y)), tip, colour, 2, cv2.LINE_AA, tipLength=0.3)
        _marker(img, (int(x), int(y)), shape, colour)
        # the marker and arrow, that no ID may cover
        taken.append(
            (
                min(int(x), tip[0]) - 7,
                min(int(y), tip[1]) - 7,
                max(int(x), tip[0]) + 7,
                max(int(y), tip[1]) + 7,
            )
        )
        labels.append((f, x, y, colour))
        if f.category not in drawn:
            drawn.append(f.category)
    for f, x, y, colour in labels:  # after every marker and arrow is known
        label_at = _label_box(f.id, x, y, f.norm_x, f.norm_y, arrow, taken)
        if label_at is None:
            hidden += 1
        else:
            cv2.putText(img, f.id, label_at, _FONT, LABEL_SCALE, colour, 1, cv2.LINE_AA)
    if hidden:
        note = f"{hidden} ID(s) left out where they would overlap another (features.csv lists every one)"
        cv2.putText(img, note, (60, img.shape[0] - 25), _FONT, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    return drawn


def draw_legend(canvas: Canvas, categories: list[str], counts: dict[str, int]) -> None:
    img = canvas.image
    extra = sorted(set(categories) - set(CATEGORY_STYLE))
    x0, y0 = img.shape[1] - 190, 50
    height = 22 * len(categories) + 56
    cv2.rectangle(img, (x0 - 10, y0 - 18), (x0 + 175, y0 + height - 18), _WHITE, -1)
    cv2.rectangle(img, (x0 - 10, y0 - 18), (x0 + 175, y0 + height - 18), (0, 0, 0), 1)
    for i, category in enumerate(categories):
        colour, shape = category_style(category, extra.index(category) if category in extra else 0)
        y = y0 + 22 * i
        _marker(img, (x0 + 8, y - 4), shape, colour)
        cv2.putText(
            img,
            f"{category} ({counts.get(category, 0)})",
            (x0 + 24, y),
            _FONT,
            0.5,
            (0, 0, 0),
            1,
            cv2.LINE_AA,
        )
    y = y0 + 22 * len(categories)
    cv2.line(img, (x0, y - 4), (x0 + 16, y - 4), (0, 0, 0), 1, cv2.LINE_AA)
    cv2.putText(img, "wall surface", (x0 + 24, y), _FONT, 0.5, (0, 0, 0), 1, cv2.LINE_AA)
    y += 22
    cv2.rectangle(img, (x0, y - 10), (x0 + 16, y + 1), (205, 205, 205), -1)
    cv2.rectangle(img, (x0, y - 10), (x0 + 16, y + 1), (0, 0, 0), 1)
    cv2.putText(img, "walls, columns (cut)", (x0 + 24, y), _FONT, 0.5, (0, 0, 0), 1, cv2.LINE_AA)


def draw_scale_bar(canvas: Canvas, span_m: float) -> None:
    img = canvas.image
    length = _scale_length(span_m)
    pixels = int(length * canvas.scale)
    x1, y = img.shape[1] - 30, img.shape[0] - 25
    x0 = x1 - pixels
    cv2.rectangle(img, (x0, y - 5), (x1, y), (0, 0, 0), -1)
    half = x0 + pixels // 2
    cv2.rectangle(img, (half, y - 5), (x1, y), _WHITE, -1)
    cv2.rectangle(img, (x0, y - 5), (x1, y), (0, 0, 0), 1)
    cv2.putText(img, f"{length:g} m", (x0, y - 10), _FONT, 0.5, (0, 0, 0), 1, cv2.LINE_AA)


def render_preview(
    path: Path,
    title: str,
    obstacles: list[BaseGeometry],
    walls: list[WallSegment],
    features: list[Feature],
    outline: BaseGeometry | None = None,
) -> None:
    """Write a PNG of the storey plan with its features."""
    if outline is not None and not outline.is_empty:
        bounds = outline.bounds
    else:
        xs = [w.x1 for w in walls] + [w.x2 for w in walls] + [f.x for f in features] or [0.0, 1.0]
        ys = [w.y1 for w in walls] + [w.y2 for w in walls] + [f.y for f in features] or [0.0, 1.0]
        bounds = (min(xs), min(ys), max(xs), max(ys))
    canvas = Canvas(bounds)
    draw_plan(canvas, obstacles, walls, outline)
    categories = draw_features(canvas, features)
    counts: dict[str, int] = {}
    for f in features:
        counts[f.category] = counts.get(f.category, 0) + 1
    draw_legend(canvas, categories, counts)
    draw_scale_bar(canvas, max(bounds[2] - bounds[0], bounds[3] - bounds[1]))
    # OpenCV's fonts are ASCII only ("Уровень 1" came out "??????? 1"): the title, a storey name in
    # any script, is drawn with DejaVu Sans and any CJK font installed (bimtools.fonts)
    put_text(canvas.image, title, (20, 30), 18, (0, 0, 0))
    north = (30, canvas.image.shape[0] - 30)
    cv2.arrowedLine(canvas.image, north, (north[0], north[1] - 30), (0, 0, 0), 1, cv2.LINE_AA, tipLength=0.3)
    cv2.putText(canvas.image, "+y", (north[0] + 6, north[1] - 20), _FONT, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    ok, data = cv2.imencode(".png", canvas.image)
    if not ok:
        raise RuntimeError(f"could not encode {path}")
    Path(path).write_bytes(data.tobytes())


__all__ = ["CATEGORY_STYLE", "LANDMARK_MARKER", "category_style", "draw_features", "render_preview"]
