"""bimtools.extract.preview: the canvas transform, the category styles and the PNG it writes."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from shapely.geometry import box

from bimtools.extract.preview import CATEGORY_STYLE, Canvas, category_style, render_preview
from bimtools.site.records import Feature, WallSegment


def test_category_style_known_and_extra() -> None:
    assert category_style("Door") == CATEGORY_STYLE["Door"]
    extra0, extra1 = category_style("Ramp", 0), category_style("Ramp", 1)
    assert extra0[1] == "circle" and extra0[0] != extra1[0]


def test_canvas_maps_world_y_up_to_image_rows_down() -> None:
    canvas = Canvas((0.0, 0.0, 10.0, 5.0), max_side=400)
    assert canvas.scale == 40.0
    (a, b) = canvas.px(np.array([[0.0, 5.0], [10.0, 0.0]]))
    assert tuple(a) == (canvas.margin, canvas.margin + 40)
    assert b[0] - a[0] == 400 and b[1] - a[1] == 200
    assert canvas.image.shape[1] >= 400 + 2 * canvas.margin


def test_render_preview_draws_the_plan_and_the_features(tmp_path: Path) -> None:
    walls = [WallSegment("L", "w", "IfcWall", 0.0, 0.0, 10.0, 0.0, (0.0, 1.0))]
    door = Feature("D1", "Door", 5.0, 2.0, 0.0, 1.0, 0.9, 2.1)
    path = tmp_path / "plan.png"
    render_preview(path, "Level 1", [box(0, -0.2, 10, 0)], walls, [door], outline=box(0, -0.2, 10, 4))
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image is not None
    canvas = Canvas((0.0, -0.2, 10.0, 4.0))
    assert image.shape == canvas.image.shape
    (x, y), (wx, wy) = canvas.px(np.array([[5.0, 2.0], [5.0, -0.1]]))
    np.testing.assert_array_equal(image[y, x], CATEGORY_STYLE["Door"][0])  # the door's marker
    assert tuple(image[wy, wx]) == (205, 205, 205)  # the filled obstacle
    ((fx, fy),) = canvas.px(np.array([[2.0, 3.0]]))
    assert tuple(image[fy, fx]) == (255, 255, 255)  # free floor


def test_render_preview_without_outline_uses_the_features(tmp_path: Path) -> None:
    path = tmp_path / "nothing.png"
    render_preview(path, "empty", [], [], [Feature("R1", "Ramp", 1.0, 1.0, 1.0, 0.0, 1.0, 1.0)])
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image.shape[0] >= 300 and image.shape[1] >= 500
    colour = category_style("Ramp", 0)[0]
    assert (np.all(image == colour, axis=2)).sum() > 20  # the extra category's circle is drawn


def test_landmarks_are_drawn_small_without_ids_and_listed_in_the_legend() -> None:
    from bimtools.extract.preview import LANDMARK_MARKER, draw_features

    corner = Feature("wall-CC1", "ConcaveCorner", 2.0, 2.0, 0.70710678, 0.70710678, 1.0, 0.0)
    door = Feature("D1", "Door", 6.0, 2.0, 0.0, 1.0, 0.9, 2.1)
    drawn = {}
    for name, features in (("corner", [corner]), ("door", [door])):
        canvas = Canvas((0.0, 0.0, 10.0, 5.0), max_side=400)
        assert draw_features(canvas, features) == [features[0].category]
        drawn[name] = int((canvas.image != 255).any(axis=2).sum())
    colour = CATEGORY_STYLE["ConcaveCorner"][0]
    assert 0 < drawn["corner"] < (2 * LANDMARK_MARKER + 1) ** 2 + 40  # a dot and a tick, no label
    assert drawn["door"] > 4 * drawn["corner"]  # a door: square, arrow and its ID
    assert colour != CATEGORY_STYLE["ConvexCorner"][0]


def test_ids_never_overlap_and_the_picture_counts_those_left_out() -> None:
    """Doors 0.3 m apart along a corridor wall (GUID-long IDs) are drawn; twelve IDs wanting one
    spot: each placed ID is clear of every other, the rest are left out (None) and not drawn."""
    from bimtools.extract.preview import _label_box, draw_features

    ids = [f"2d24hq3H2EhLi7osekr{k:03d}" for k in range(12)]
    doors = [Feature(i, "Door", 1.0 + 0.3 * k, 0.0, 0.0, 1.0, 1.0, 2.1) for k, i in enumerate(ids)]
    canvas = Canvas((0.0, -1.0, 6.0, 3.0), max_side=600)
    draw_features(canvas, doors)
    taken: list[tuple[int, int, int, int]] = []
    placed = [_label_box(i, 300.0, 300.0, 0.0, 1.0, 20, taken) for i in ids]
    boxes = taken
    for a in range(len(boxes)):
        for b in range(a + 1, len(boxes)):
            p, q = boxes[a], boxes[b]
            assert p[2] < q[0] or q[2] < p[0] or p[3] < q[1] or q[3] < p[1]
    assert placed[0] is not None and None in placed  # twelve at one spot: some left out
    assert len(boxes) == sum(p is not None for p in placed)
