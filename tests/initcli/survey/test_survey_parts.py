"""The survey's pure parts: the camera model against the simulator's, the wall-following loops, the
incremental uniqueness on layouts that are and are not ambiguous, the sequences and the summary."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.features.visibility import CameraModel, FeatureArrays, visible
from initcli.core.geometry.projection import DEFAULT_CAMERA, DEFAULT_MOUNT
from initcli.core.geometry.se2 import Pose2D
from initcli.sim.synthetic_log import SimFeature, SyntheticParams, render_image
from initcli.survey.exploration import follow_loops, join_loop, look_round
from initcli.survey.uniqueness import UniquenessParams, first_unique


def test_visibility_is_the_simulators_render_image():
    rng = np.random.default_rng(3)
    n = 30
    xy = rng.uniform(0, 12, (n, 2))
    ang = rng.uniform(-math.pi, math.pi, n)
    normal = np.column_stack([np.cos(ang), np.sin(ang)])
    height = rng.uniform(1.0, 2.5, n)
    features = FeatureArrays(xy, normal, height, tuple("door" for _ in range(n)))
    walls = np.array([[4.0, 0.0, 4.0, 8.0], [0.0, 9.0, 10.0, 9.0]])
    model = CameraModel(DEFAULT_CAMERA, DEFAULT_MOUNT)
    sim = [SimFeature(str(i), "door", *xy[i], *normal[i], 1.0, height[i]) for i in range(n)]
    params = SyntheticParams(
        min_range=model.min_range,
        max_range=model.max_range,
        max_view_angle=math.radians(model.max_view_angle_deg),
    )
    poses = np.column_stack([rng.uniform(0, 12, (40, 2)), rng.uniform(-math.pi, math.pi, 40)])
    ours = visible(poses, features, walls, model)
    assert ours.any()
    for p, pose in enumerate(poses):
        found = render_image(sim, Pose2D(*pose), model.camera, model.mount, params, walls)
        assert {int(fid) for _, fid in found} == set(np.flatnonzero(ours[p]).tolist())


def _room(width_m: float, height_m: float, res: float = 0.05) -> tuple[OccupancyGrid, np.ndarray, np.ndarray]:
    rows, cols = int(height_m / res) + 2, int(width_m / res) + 2
    cells = np.full((rows, cols), FREE, dtype=np.uint8)
    cells[[0, -1], :] = OCCUPIED
    cells[:, [0, -1]] = OCCUPIED
    grid = OccupancyGrid(cells=cells, resolution=res, origin=(0.0, 0.0, 0.0))
    import cv2

    clearance = (
        cv2.distanceTransform((cells == FREE).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * res
    )
    return grid, cells == FREE, clearance


@pytest.mark.parametrize("side", [1, -1])
def test_a_room_has_one_loop_at_the_wall_distance_with_the_wall_on_the_followed_side(side):
    grid, region, clearance = _room(10.0, 4.0)
    (loop,) = follow_loops(region, clearance, grid, 0.7, side, 0.1)
    length = len(loop) * loop.step
    assert length == pytest.approx(2 * (10.0 - 1.4 + 4.0 - 1.4), rel=0.05)
    # the wall is on the followed side: a point to that side of the path is closer to a wall
    k = len(loop) // 3
    left = np.array([-math.sin(loop.yaw[k]), math.cos(loop.yaw[k])])
    toward = loop.xy[k] + side * 0.4 * left
    r, c = grid.world_to_cell(*toward)
    r0, c0 = grid.world_to_cell(*loop.xy[k])
    assert clearance[r, c] < clearance[r0, c0]
    entry = join_loop(np.array([5.0, 2.0, 0.0]), [loop], np.zeros((0, 4)), side, 0.1)
    assert entry is not None and 0.5 < entry.length < 1.6
    assert side * (entry.approach[-1, 1] - 2.0) > 0  # it joined on the followed side
    look = look_round(np.array([1.0, 1.0, 0.3]), 0.12)
    assert look[0, 2] == pytest.approx(0.3) and look[-1, 2] == pytest.approx(0.3 + 2 * math.pi)


def test_a_periodic_row_of_doors_stays_ambiguous_until_a_sign_with_no_outlier_allowed():
    xy = np.array([[4.0 * i, 0.0] for i in range(10)])  # every 4 m: translation-symmetric
    cls = ["door"] * 10
    params = UniquenessParams()
    assert first_unique(xy, cls, [(2, 3, 4, 5), (3, 4, 5)], params) == [-1, -1]
    with_sign = np.vstack([xy, [[17.0, 1.5]]])
    strict = UniquenessParams(max_outliers=0, min_claim=3)
    got = first_unique(with_sign, [*cls, "landmark_1"], [(3, 4, 10, 5), (3, 4, 5)], strict)
    assert got[1] == -1 and got[0] == 3
    # The session claims a unique match on 4 features (min_claim_inliers): so does the survey.
    claimed = UniquenessParams(max_outliers=0)
    assert claimed.min_claim == 4
    assert first_unique(with_sign, [*cls, "landmark_1"], [(3, 4, 10, 5), (3, 4, 10)], claimed) == [4, -1]
    # with one outlier tolerated, "the sign was a false detection" keeps every shift alive
    assert first_unique(with_sign, [*cls, "landmark_1"], [(3, 4, 10, 5)], params) == [-1]
    # an irregular layout: three features leave "one of them was false" open, a fourth settles it;
    # sequences sharing a prefix get the answers they get alone
    irregular = np.array([[0, 0], [3.1, 0], [7.9, 0], [9.0, 2.5], [14.2, 0], [20.0, 0.5]], dtype=float)
    seqs = [(0, 1, 2), (0, 1, 2, 3), (3, 4, 5), (0, 1, 2)]
    together = first_unique(irregular, ["door"] * 6, seqs, params)
    assert together == [first_unique(irregular, ["door"] * 6, [s], params)[0] for s in seqs]
    assert together[0] == together[3] == -1 and together[1] == 4
