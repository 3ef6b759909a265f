"""Which BIM features a camera sees from many robot poses at once: the simulator's model, no noise.

Used by ``bim-init survey`` (what the camera would see while exploring) and by the verification of a
hypothesis (which BIM features it says were in view). The same tests as
:func:`initcli.sim.synthetic_log.render_image` (and the simulated detector built on it): the
feature's box centre at ``centre_height`` of its height projected with the inverse of Eq. 1-2 must
fall in the image (less ``margin`` at the borders), its optical depth within ``[min_range,
max_range]``, the line of sight within ``max_view_angle`` of its normal, and the segment from the
camera to a point just in front of the host wall must cross no wall or obstacle edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, odom_to_pixel
from initcli.core.geometry.raycast import sight_blocked
from initcli.core.geometry.se2 import Pose2D

__all__ = ["CameraModel", "FeatureArrays", "PAIR_CHUNK", "sight_lines_blocked", "visible"]

PAIR_CHUNK = 20_000  # (pose, feature) pairs tested against the walls at once


@dataclass(frozen=True)
class CameraModel:
    """The camera and the detector's visibility limits (the simulator's defaults)."""

    camera: CameraIntrinsics
    mount: CameraMount
    min_range: float = 0.5  # m of optical depth
    max_range: float = 6.0  # m
    max_view_angle_deg: float = 75.0  # from the element's normal
    centre_height: float = 0.5  # box centre at this fraction of the element's height
    margin: float = 0.0  # share of the image width and height at each border that does not count


@dataclass(frozen=True)
class FeatureArrays:
    """B_object of one storey as arrays: positions, normals, heights and canonical classes."""

    xy: np.ndarray  # (F, 2)
    normal: np.ndarray  # (F, 2)
    height: np.ndarray  # (F,)
    cls: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.xy)

    def with_feature(
        self, x: float, y: float, nx: float, ny: float, height: float, cls: str
    ) -> FeatureArrays:
        return FeatureArrays(
            np.vstack([self.xy, [[x, y]]]),
            np.vstack([self.normal, [[nx, ny]]]),
            np.append(self.height, height),
            (*self.cls, cls),
        )


def visible(poses: np.ndarray, features: FeatureArrays, walls: np.ndarray, model: CameraModel) -> np.ndarray:
    """(P, F) bool: does the image taken at BIM pose ``poses[p]`` (x, y, yaw) show feature f?"""
    poses = np.asarray(poses, dtype=float).reshape(-1, 3)
    n_p, n_f = len(poses), len(features)
    out = np.zeros((n_p, n_f), dtype=bool)
    if n_p == 0 or n_f == 0:
        return out
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    dx = features.xy[None, :, 0] - poses[:, 0:1]
    dy = features.xy[None, :, 1] - poses[:, 1:2]
    local = np.stack([c * dx + s * dy, -s * dx + c * dy], axis=-1).reshape(-1, 2)  # robot frame
    z = np.broadcast_to(features.height * model.centre_height, (n_p, n_f)).reshape(-1, 1)
    u, v, depth = odom_to_pixel(np.hstack([local, z]), model.camera, model.mount, Pose2D.identity())
    eye = np.column_stack(
        [
            poses[:, 0] + c[:, 0] * model.mount.x - s[:, 0] * model.mount.y,
            poses[:, 1] + s[:, 0] * model.mount.x + c[:, 0] * model.mount.y,
        ]
    )
    to_eye = eye[:, None, :] - features.xy[None, :, :]
    dist = np.hypot(to_eye[..., 0], to_eye[..., 1])
    cos_view = np.einsum("pfk,fk->pf", to_eye, features.normal) / np.maximum(dist, 1e-12)
    cam = model.camera
    mu, mv = model.margin * cam.width, model.margin * cam.height
    with np.errstate(invalid="ignore"):
        ok: np.ndarray = (
            (depth >= model.min_range)
            & (depth <= model.max_range)
            & (u >= mu)
            & (u <= cam.width - mu)
            & (v >= mv)
            & (v <= cam.height - mv)
        ).reshape(n_p, n_f) & (cos_view >= math.cos(math.radians(model.max_view_angle_deg)))
    pp, ff = np.nonzero(ok)
    if len(pp) and len(walls):
        targets = features.xy[ff] + 0.05 * features.normal[ff]  # just in front of the wall surface
        blocked = sight_lines_blocked(eye[pp], targets, walls)
        ok[pp[blocked], ff[blocked]] = False
    return ok


def sight_lines_blocked(eyes: np.ndarray, targets: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """For each pair (``eyes`` and ``targets`` (n, 2) each), does a wall (x1, y1, x2, y2) cross the
    sight line ``eye -> target``? ``PAIR_CHUNK`` pairs at a time."""
    blocked = np.zeros(len(eyes), dtype=bool)
    for lo in range(0, len(eyes), PAIR_CHUNK):
        hi = min(lo + PAIR_CHUNK, len(eyes))
        blocked[lo:hi] = _crossing(eyes[lo:hi], targets[lo:hi], walls)
    return blocked


def _crossing(a: np.ndarray, b: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """sight_blocked restricted to the walls near each segment's bounding box (same answer, faster)."""
    lo = np.minimum(a, b).min(axis=0)
    hi = np.maximum(a, b).max(axis=0)
    w = walls
    near = (
        (np.maximum(w[:, 0], w[:, 2]) >= lo[0])
        & (np.minimum(w[:, 0], w[:, 2]) <= hi[0])
        & (np.maximum(w[:, 1], w[:, 3]) >= lo[1])
        & (np.minimum(w[:, 1], w[:, 3]) <= hi[1])
    )
    if len(a) > 64:
        # split spatially so each part meets only its own walls
        order = np.argsort(a[:, 0])
        half = len(a) // 2
        out = np.zeros(len(a), dtype=bool)
        out[order[:half]] = _crossing(a[order[:half]], b[order[:half]], w[near])
        out[order[half:]] = _crossing(a[order[half:]], b[order[half:]], w[near])
        return out
    return sight_blocked(a, b, w[near])
