"""Robot pose in the BIM frame for one match: the paper's method (Eq. 10-13) and rigid Kabsch.

*paper* (§3.3.3): the position (x_g, y_g) by trilateration on the last three matched features
(Eq. 10, non-linear least squares by Levenberg-Marquardt), d_i being the robot's measured (odom)
distance to feature i; the heading theta_g from the last matched feature seen in the robot frame
(Eq. 11-13).
Eq. 10 has two minima when the three features are (nearly) collinear -- doors along one corridor
wall -- mirror images across that line; the paper does not say which one it takes. Here the
least squares runs from every pairwise circle intersection and the minimum whose handedness
(the side of the feature line the robot is on) agrees with the odom frame is kept: a rigid
motion cannot change that side.

*rigid*: the least-squares rigid transform odom -> BIM over all matched features (2D
Kabsch/Umeyama without scale), applied to the robot's current odom pose.
"""

from __future__ import annotations

import math

import numpy as np

from initcli.core.geometry.least_squares import levenberg_marquardt
from initcli.core.geometry.se2 import Pose2D, wrap_angle

__all__ = [
    "POSE_METHODS",
    "SIDE_TOLERANCE",
    "estimate_pose",
    "heading_from_feature",
    "paper_pose",
    "rigid_align",
    "rigid_align_batch",
    "rigid_pose",
    "trilaterate",
    "trilateration_residuals",
]

POSE_METHODS = ("paper", "rigid")
SIDE_TOLERANCE = 0.05  # m: below this offset from the feature line the side is not trusted


def trilateration_residuals(xy: np.ndarray, anchors: np.ndarray, dists: np.ndarray) -> np.ndarray:
    """Eq. 10 residuals: d_i^2 - ((x - x_i)^2 + (y - y_i)^2), one per feature."""
    residuals: np.ndarray = dists**2 - ((xy[0] - anchors[:, 0]) ** 2 + (xy[1] - anchors[:, 1]) ** 2)  # Eq. 10
    return residuals


def _circle_points(c1: np.ndarray, r1: float, c2: np.ndarray, r2: float) -> list[np.ndarray]:
    """Intersections of two circles; the closest-approach point if they do not meet."""
    d = float(np.hypot(*(c2 - c1)))
    if d < 1e-12:
        return []
    e = (c2 - c1) / d
    a = (r1 * r1 - r2 * r2 + d * d) / (2.0 * d)
    h2 = r1 * r1 - a * a
    mid = c1 + a * e
    if h2 <= 0.0:
        return [mid]
    h = math.sqrt(h2)
    perp = np.array([-e[1], e[0]])
    return [mid + h * perp, mid - h * perp]


def _side(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> float:
    """cross(q - p, r - p): > 0 if r is left of the line p -> q."""
    return float((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))


def trilaterate(
    anchors: np.ndarray,
    dists: np.ndarray,
    odom_anchors: np.ndarray | None = None,
    odom_robot: np.ndarray | None = None,
) -> np.ndarray:
    """Eq. 10: (x_g, y_g) = argmin sum (d_i^2 - ((x - x_i)^2 + (y - y_i)^2))^2 (Levenberg-Marquardt).

    ``anchors`` are the BIM positions of the features, ``dists`` the measured distances. If the odom
    positions of the same features and of the robot are given, the solution on the robot's side of
    the feature line is preferred (mirror ambiguity of collinear anchors).
    """
    anchors = np.asarray(anchors, dtype=float).reshape(-1, 2)
    dists = np.asarray(dists, dtype=float).reshape(-1)
    starts: list[np.ndarray] = [anchors.mean(axis=0)]
    for i in range(len(anchors)):
        for j in range(i + 1, len(anchors)):
            starts.extend(_circle_points(anchors[i], dists[i], anchors[j], dists[j]))
    solutions: list[tuple[float, np.ndarray]] = []
    for x0 in starts:  # one feature: the minimisers are a circle, the solver ends on one of them
        res = levenberg_marquardt(
            trilateration_residuals, x0, args=(anchors, dists), xtol=1e-15, ftol=1e-15, gtol=1e-15
        )
        solutions.append((float(np.sum(res.fun**2)), res.x))
    if odom_anchors is not None and odom_robot is not None and len(anchors) >= 2:
        odom_anchors = np.asarray(odom_anchors, dtype=float).reshape(-1, 2)
        odom_robot = np.asarray(odom_robot, dtype=float).reshape(2)
        pairs = [(i, j) for i in range(len(anchors)) for j in range(i + 1, len(anchors))]

        def offset(ij: tuple[int, int]) -> float:  # signed distance of the robot from the line i -> j
            p, q = odom_anchors[ij[0]], odom_anchors[ij[1]]
            return _side(p, q, odom_robot) / max(float(np.hypot(*(q - p))), 1e-12)

        i, j = max(pairs, key=lambda ij: abs(offset(ij)))
        want = offset((i, j))
        if abs(want) > SIDE_TOLERANCE:
            agree = [(c, x) for c, x in solutions if _side(anchors[i], anchors[j], x) * want > 0]
            if agree:
                solutions = agree
    return min(solutions, key=lambda cx: cx[0])[1].copy()


def heading_from_feature(position: np.ndarray, feature_bim: np.ndarray, feature_robot: np.ndarray) -> float:
    """Eq. 11-13: the yaw theta_g given the robot position (x_g, y_g), the last feature in the BIM frame
    (o_bx, o_by) and in the robot frame (o_rx, o_ry)."""
    x_g, y_g = float(position[0]), float(position[1])
    o_bx, o_by = float(feature_bim[0]), float(feature_bim[1])
    o_rx, o_ry = float(feature_robot[0]), float(feature_robot[1])
    # Eq. 12: [[o_rx, -o_ry], [o_ry, o_rx]] [cos, sin]^T = [o_bx - x_g, o_by - y_g]^T, solved as Eq. 13:
    return math.atan2(
        (o_by - y_g) * o_rx - (o_bx - x_g) * o_ry, (o_bx - x_g) * o_rx + (o_by - y_g) * o_ry
    )  # Eq. 13


def paper_pose(bim_xy: np.ndarray, odom_xy: np.ndarray, robot_odom: Pose2D) -> Pose2D:
    """The paper's pose (§3.3.3) from the matched features in order (BIM and odom positions, (n, 2)).

    Trilateration (Eq. 10) on the last three, heading (Eq. 13) from the last one.
    """
    bim_xy = np.asarray(bim_xy, dtype=float).reshape(-1, 2)
    odom_xy = np.asarray(odom_xy, dtype=float).reshape(-1, 2)
    last = slice(max(0, len(bim_xy) - 3), len(bim_xy))
    dists = np.hypot(*(odom_xy[last] - robot_odom.xy).T)  # measured distances d_i (odom frame)
    position = trilaterate(bim_xy[last], dists, odom_xy[last], robot_odom.xy)  # Eq. 10
    feature_robot = robot_odom.apply_inverse(odom_xy[-1])  # (o_rx, o_ry): last feature in the robot frame
    yaw = heading_from_feature(position, bim_xy[-1], feature_robot)  # Eq. 13
    return Pose2D(float(position[0]), float(position[1]), float(wrap_angle(yaw)))


def rigid_align(src: np.ndarray, dst: np.ndarray) -> Pose2D:
    """Least-squares rigid transform T (rotation + translation, no scale) with T(src) ~ dst (2D Kabsch)."""
    yaw, t = rigid_align_batch(np.asarray(src, dtype=float)[None], np.asarray(dst, dtype=float)[None])
    return Pose2D(float(t[0, 0]), float(t[0, 1]), float(yaw[0]))


def rigid_align_batch(
    src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Batched 2D Kabsch: src, dst (H, n, 2), weights (H, n) (0 for outliers) -> yaw (H,), t (H, 2).

    Minimises sum_i w_i |R(yaw) src_i + t - dst_i|^2 in closed form:
    yaw = atan2(sum w (x'_s y'_d - y'_s x'_d), sum w (x'_s x'_d + y'_s y'_d)) on centred points.
    """
    src = np.asarray(src, dtype=float)
    dst = np.asarray(dst, dtype=float)
    w = np.ones(src.shape[:2]) if weights is None else np.asarray(weights, dtype=float)
    wsum = np.maximum(w.sum(axis=1, keepdims=True), 1e-300)
    cs = (w[..., None] * src).sum(axis=1) / wsum
    cd = (w[..., None] * dst).sum(axis=1) / wsum
    s = src - cs[:, None, :]
    d = dst - cd[:, None, :]
    num = (w * (s[..., 0] * d[..., 1] - s[..., 1] * d[..., 0])).sum(axis=1)
    den = (w * (s[..., 0] * d[..., 0] + s[..., 1] * d[..., 1])).sum(axis=1)
    yaw = np.arctan2(num, den)
    c, sn = np.cos(yaw), np.sin(yaw)
    t = cd - np.column_stack([c * cs[:, 0] - sn * cs[:, 1], sn * cs[:, 0] + c * cs[:, 1]])
    return yaw, t


def rigid_pose(
    bim_xy: np.ndarray, odom_xy: np.ndarray, robot_odom: Pose2D, window: int | None = None
) -> Pose2D:
    """The rigid alternative: Kabsch over the matched features, then T_bim_odom * robot_odom.

    ``window``: only the last ``window`` matched features (at least 2) are aligned. Odometry drifts
    along a long path, so the recent features fit the current pose best (like the paper's use of
    the last three); None aligns all of them.
    """
    bim_xy = np.asarray(bim_xy, dtype=float).reshape(-1, 2)
    odom_xy = np.asarray(odom_xy, dtype=float).reshape(-1, 2)
    if window is not None and len(bim_xy) > max(2, window):
        bim_xy, odom_xy = bim_xy[-max(2, window) :], odom_xy[-max(2, window) :]
    transform = rigid_align(odom_xy, bim_xy)
    return transform * robot_odom


def estimate_pose(
    method: str, bim_xy: np.ndarray, odom_xy: np.ndarray, robot_odom: Pose2D, window: int | None = None
) -> Pose2D:
    """Dispatch on ``method`` ('paper' or 'rigid'); ``window`` applies to 'rigid'."""
    if method == "paper":
        return paper_pose(bim_xy, odom_xy, robot_odom)
    if method == "rigid":
        return rigid_pose(bim_xy, odom_xy, robot_odom, window)
    raise ValueError(f"unknown pose method {method!r}; use one of {', '.join(POSE_METHODS)}")
