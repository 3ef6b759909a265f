"""The Levenberg-Marquardt solver: known minima, its stopping rules, and agreement with SciPy's
``least_squares(method="lm")`` (MINPACK) on the problems the package solves: Eq. 10 and the
planar pose of a marker. SciPy is not a dependency of the package; the tests that compare with it
are skipped where it is not installed."""

from __future__ import annotations

import math
from typing import Any, TypedDict

import numpy as np
import pytest

import initcli.core.features.marker_pose as marker_pose
from initcli.core.geometry.least_squares import LeastSquaresResult, levenberg_marquardt
from initcli.core.geometry.projection import CameraIntrinsics, CameraMount, odom_to_optical
from initcli.core.geometry.se2 import Pose2D
from initcli.core.hypotheses.pose import _circle_points, trilaterate, trilateration_residuals
from initcli.sim.markers import Marker


class Tolerances(TypedDict):
    ftol: float
    xtol: float
    gtol: float


TIGHT = Tolerances(ftol=1e-15, xtol=1e-15, gtol=1e-15)  # trilaterate's tolerances
CAMERA = CameraIntrinsics(320.0, 320.0, 320.0, 240.0, 640, 480)
MOUNT = CameraMount(0.2, 0.0, 1.0)


def rosenbrock(x: np.ndarray) -> np.ndarray:
    return np.array([10.0 * (x[1] - x[0] ** 2), 1.0 - x[0]])


def rosenbrock_jac(x: np.ndarray) -> np.ndarray:
    return np.array([[-20.0 * x[0], 10.0], [-1.0, 0.0]])


@pytest.mark.parametrize("jac", ["forward", "central", rosenbrock_jac])
def test_rosenbrock_minimum(jac: Any) -> None:
    res = levenberg_marquardt(rosenbrock, np.array([-1.2, 1.0]), jac, **TIGHT, max_nfev=1000)
    assert isinstance(res, LeastSquaresResult)
    assert res.success and res.status in (1, 2, 3, 4)
    assert np.allclose(res.x, [1.0, 1.0], atol=1e-10)
    assert res.cost == pytest.approx(0.0, abs=1e-20)
    assert np.allclose(res.jac, rosenbrock_jac(res.x), atol=1e-5)


def test_linear_least_squares_is_solved_exactly() -> None:
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(12, 4)), rng.normal(size=12)
    res = levenberg_marquardt(lambda x: a @ x - b, np.zeros(4), lambda x: a)
    assert np.allclose(res.x, np.linalg.lstsq(a, b, rcond=None)[0], atol=1e-10)


def test_args_and_x_scale() -> None:
    target = np.array([3.0, -2.0])
    res = levenberg_marquardt(lambda x, t: (x - t) * [1.0, 1e3], np.zeros(2), args=(target,), x_scale=1.0)
    assert np.allclose(res.x, target, atol=1e-9)


def test_stops_after_max_nfev() -> None:
    res = levenberg_marquardt(rosenbrock, np.array([-1.2, 1.0]), **TIGHT, max_nfev=3)
    assert res.status == 0 and not res.success and res.nfev == 3
    assert "evaluations" in res.message


def test_bad_input() -> None:
    with pytest.raises(ValueError, match="not finite"):
        levenberg_marquardt(lambda x: np.array([np.nan]), np.zeros(1))
    with pytest.raises(ValueError, match="jac"):
        levenberg_marquardt(rosenbrock, np.zeros(2), "3-point")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="x_scale"):
        levenberg_marquardt(rosenbrock, np.zeros(2), x_scale="auto")  # type: ignore[arg-type]


def test_fewer_residuals_than_unknowns_end_on_a_minimiser() -> None:
    """One feature: Eq. 10 is a circle of minimisers; MINPACK refuses m < n, here one of them is found."""
    for centre, radius in [((1.0, 2.0), 1.5), ((3.0, -5.0), 2.0), ((0.0, 0.0), 1.0), ((-7.3, 0.2), 3.0)]:
        anchors, dists = np.array([centre]), np.array([radius])
        got = trilaterate(anchors, dists)
        assert math.hypot(*(got - anchors[0])) == pytest.approx(radius, abs=1e-9)


# --- agreement with SciPy --------------------------------------------------------------------


def _well_posed_eq10(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Three features around a robot, not collinear, with noisy distances."""
    while True:
        anchors = rng.uniform(-15.0, 15.0, (3, 2))
        (ax, ay), (bx, by), (cx, cy) = anchors
        if abs((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)) > 20.0:  # twice the triangle's area
            break
    robot = rng.uniform(-10.0, 10.0, 2)
    dists = np.abs(np.hypot(*(anchors - robot).T) + rng.normal(0.0, 0.05, 3))
    return anchors, dists


def test_eq10_agrees_with_scipy() -> None:
    optimize = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(7)
    for _ in range(60):
        anchors, dists = _well_posed_eq10(rng)
        starts = [anchors.mean(axis=0)]
        for i in range(3):
            for j in range(i + 1, 3):
                starts += _circle_points(anchors[i], dists[i], anchors[j], dists[j])
        for x0 in starts:
            ours = levenberg_marquardt(trilateration_residuals, x0, args=(anchors, dists), **TIGHT)
            theirs = optimize.least_squares(
                trilateration_residuals, x0, args=(anchors, dists), method="lm", **TIGHT
            )
            assert np.allclose(ours.x, theirs.x, atol=1e-6)
            assert ours.cost == pytest.approx(theirs.cost, rel=1e-9, abs=1e-12)


def test_generic_fit_agrees_with_scipy_at_default_tolerances() -> None:
    optimize = pytest.importorskip("scipy.optimize")
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 3.0, 20)
    for _ in range(50):
        p = rng.uniform([0.5, -1.5, -1.0], [3.0, -0.2, 1.0])
        y = p[0] * np.exp(p[1] * t) + p[2] + rng.normal(0.0, 0.01, t.size)
        x0 = p + rng.normal(0.0, 0.1, 3)

        def residuals(q: np.ndarray, y: np.ndarray = y) -> np.ndarray:
            return np.asarray(q[0] * np.exp(q[1] * t) + q[2] - y)

        ours = levenberg_marquardt(residuals, x0)
        theirs = optimize.least_squares(residuals, x0, method="lm")
        assert ours.success and theirs.success  # (which test stops them can differ by rounding)
        assert np.allclose(ours.x, theirs.x, atol=1e-6)


def _marker_views(marker: Marker, seed: int) -> list[np.ndarray]:
    """Corner pixels of ``marker`` seen 1-2 m away, within 12 degrees of head-on, with corner noise."""
    rng = np.random.default_rng(seed)
    views = []
    for _ in range(40):
        d = rng.uniform(1.0, 2.0)
        a = marker.yaw + math.radians(rng.uniform(-12.0, 12.0))
        cam = np.array([marker.x, marker.y]) + d * np.array([math.cos(a), math.sin(a)])
        yaw = a + math.pi + math.radians(rng.uniform(-5.0, 5.0))
        truth = Pose2D(cam[0] - MOUNT.x * math.cos(yaw), cam[1] - MOUNT.x * math.sin(yaw), yaw)
        optical = odom_to_optical(marker.corners(), MOUNT, truth)
        u = CAMERA.fx * optical[:, 0] / optical[:, 2] + CAMERA.cx
        v = CAMERA.fy * optical[:, 1] / optical[:, 2] + CAMERA.cy
        views.append(np.column_stack([u, v]) + rng.normal(0.0, 0.05 + 0.01 * d * d, (4, 2)))
    return views


def test_marker_pose_agrees_with_scipy(monkeypatch: pytest.MonkeyPatch) -> None:
    """The level fit of a marker pose (3 unknowns, 8 residuals) at default tolerances."""
    optimize = pytest.importorskip("scipy.optimize")
    marker = Marker(3, 4.0, -2.0, 1.6, (0.0, 1.0), math.pi / 2)
    views = [c for seed in range(2) for c in _marker_views(marker, seed)]
    ours = [marker_pose.robot_pose_from_marker(c, marker, CAMERA, MOUNT) for c in views]

    def scipy_lm(fun: Any, x0: np.ndarray) -> Any:
        return optimize.least_squares(fun, x0, method="lm")

    monkeypatch.setattr(marker_pose, "levenberg_marquardt", scipy_lm)
    theirs = [marker_pose.robot_pose_from_marker(c, marker, CAMERA, MOUNT) for c in views]
    for a, b in zip(ours, theirs, strict=True):
        assert a.distance_to(b) < 1e-6 and a.yaw_error(b) < 1e-6
