"""Particle-filter fine tuning (§3.3.5, Eq. 18), AMCL-style position tracking on the BIM map.

bel(x_t) = eta * p(z_t | x_t, m) * integral p(x_t | x_{t-1}, u_t, m) bel(x_{t-1}) dx   (Eq. 18)

- motion model p(x_t | x_{t-1}, u_t): the odometry model (rot1, trans, rot2) with AMCL's
  alpha1..alpha4 noise;
- measurement model p(z_t | x_t, m): the likelihood field of the map's occupied cells
  (z_hit * N(d; 0, sigma_hit) + z_rand / range_max per beam);
- low-variance resampling when the effective sample size falls below half the particles.

Pure numpy; the map is an :class:`~bimtools.site.occupancy_map.OccupancyGrid`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from bimtools.site.records import OCCUPIED, OccupancyGrid
from initcli.core.filters.grid_cache import GridCache
from initcli.core.geometry.se2 import Pose2D, wrap_angle

__all__ = [
    "FilterNoise",
    "LaserModel",
    "LikelihoodField",
    "ParticleFilter",
    "PoseEstimate",
    "beam_log_likelihood",
    "likelihood_field",
    "low_variance_indices",
    "sample_motion",
    "scan_fit",
    "valid_beams",
    "weighted_pose_stats",
]


@dataclass(frozen=True)
class FilterNoise:
    """AMCL odometry-model alphas (Nav2 defaults are 0.2; the tracking filter here uses less)."""

    alpha1: float = 0.05  # rotation noise from rotation
    alpha2: float = 0.05  # rotation noise from translation
    alpha3: float = 0.05  # translation noise from translation
    alpha4: float = 0.05  # translation noise from rotation


@dataclass(frozen=True)
class LaserModel:
    z_hit: float = 0.5
    z_rand: float = 0.5
    sigma_hit: float = 0.1  # m (Nav2 default 0.2; a BIM map is sharper than a SLAM map)
    max_distance: float = 2.0  # m, laser_likelihood_max_dist
    beams: int = 60  # max_beams
    temperature: float = 4.0  # log-likelihoods are divided by this: beams are not independent
    # Beam skipping (AMCL do_beamskip): a beam that fits the map for too few particles hit something
    # unmapped (clutter, a worker) and is left out.
    beam_skip_distance: float = 0.25  # m (AMCL 0.5; tighter for clutter standing against walls)
    beam_skip_threshold: float = 0.3  # fraction of particles
    beam_skip_error_threshold: float = 0.9  # skip nothing if more than this fraction would be skipped


MIN_RANGE_M = 0.05  # m: a beam shorter than this hit the robot or read nothing


def valid_beams(ranges: np.ndarray, range_max: float) -> np.ndarray:
    """The beams of a scan that ended on something: finite, shorter than ``range_max`` (a beam at
    ``range_max`` saw nothing), longer than :data:`MIN_RANGE_M`."""
    ok: np.ndarray = np.isfinite(ranges) & (ranges < range_max) & (ranges > MIN_RANGE_M)
    return ok


class LikelihoodField:
    """Distance from every cell to the nearest occupied cell, for the beam end-point model."""

    def __init__(self, grid: OccupancyGrid, max_distance: float = 2.0):
        self.grid = grid
        free_of_walls = (grid.cells != OCCUPIED).astype(np.uint8)
        dist = cv2.distanceTransform(free_of_walls, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * grid.resolution
        self.distance = np.minimum(dist, max_distance).astype(np.float32)
        self.max_distance = max_distance
        self.rows, self.cols = grid.cells.shape
        self.known = grid.cells != 205
        # The field with a border of max_distance: a point off the map reads the border (its cell
        # indices clipped into it), which spares masking every lookup.
        self._padded = np.pad(self.distance, 1, constant_values=np.float32(max_distance))
        self._near: dict[float, np.ndarray] = {}

    def lookup(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The distance field at world points (max_distance off the map)."""
        distance: np.ndarray = self._padded[self.padded_row(y), self.padded_col(x)]
        return distance

    def interpolated(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The distance field at world points, interpolated bilinearly between cell centres (smooth
        for a local fit, where :meth:`lookup` steps from cell to cell; max_distance off the map)."""
        res, (ox, oy) = self.grid.resolution, self.grid.origin[:2]
        u, v = (np.asarray(x) - ox) / res - 0.5, (np.asarray(y) - oy) / res - 0.5
        c0, r0 = np.floor(u), np.floor(v)  # r0 counts rows up from the bottom
        fc, fr = u - c0, v - r0
        col = np.clip(c0.astype(np.int64) + 1, 0, self.cols + 1)
        col1 = np.clip(c0.astype(np.int64) + 2, 0, self.cols + 1)
        row = np.clip(self.rows - r0.astype(np.int64), 0, self.rows + 1)
        row1 = np.clip(self.rows - r0.astype(np.int64) - 1, 0, self.rows + 1)
        f = self._padded
        below = (1 - fc) * f[row, col] + fc * f[row, col1]
        above = (1 - fc) * f[row1, col] + fc * f[row1, col1]
        value: np.ndarray = (1 - fr) * below + fr * above
        return value

    def padded_col(self, x: np.ndarray) -> np.ndarray:
        """The column of the padded field holding each world ``x`` (the border off the map)."""
        col = np.floor((x - self.grid.origin[0]) / self.grid.resolution).astype(np.int64)
        col += 1
        np.maximum(col, 0, out=col)  # np.clip on integers costs more than the two bounds
        clipped: np.ndarray = np.minimum(col, self.cols + 1, out=col)
        return clipped

    def padded_row(self, y: np.ndarray) -> np.ndarray:
        """The row of the padded field holding each world ``y`` (the border off the map)."""
        row = self.rows - np.floor((y - self.grid.origin[1]) / self.grid.resolution).astype(np.int64)
        np.maximum(row, 0, out=row)
        clipped: np.ndarray = np.minimum(row, self.rows + 1, out=row)
        return clipped

    def near_walls(self, tolerance: float) -> np.ndarray:
        """The padded field's cells within ``tolerance`` (m) of a wall, as a flat boolean array
        (index ``row * (cols + 2) + col``); kept per tolerance."""
        if tolerance not in self._near:
            self._near[tolerance] = (self._padded < tolerance).ravel()
        return self._near[tolerance]


_FIELDS: GridCache[LikelihoodField] = GridCache()


def likelihood_field(grid: OccupancyGrid, max_distance: float = 2.0) -> LikelihoodField:
    """The map's :class:`LikelihoodField`, built once per map content and ``max_distance`` in this
    process (the sessions, fine tuning and AMCL of an evaluation share it)."""
    return _FIELDS.get(grid, max_distance, lambda: LikelihoodField(grid, max_distance))


def sample_motion(
    particles: np.ndarray, delta: tuple[float, float, float], noise: FilterNoise, rng: np.random.Generator
) -> np.ndarray:
    """Odometry motion model, sampled for every particle (x, y, yaw)."""
    rot1, trans, rot2 = delta
    n = len(particles)
    a = noise
    s_rot1 = math.sqrt(a.alpha1 * rot1**2 + a.alpha2 * trans**2)
    s_trans = math.sqrt(a.alpha3 * trans**2 + a.alpha4 * (rot1**2 + rot2**2))
    s_rot2 = math.sqrt(a.alpha1 * rot2**2 + a.alpha2 * trans**2)
    r1 = rot1 + rng.normal(0.0, s_rot1, n) if s_rot1 > 0 else np.full(n, rot1)
    tr = trans + rng.normal(0.0, s_trans, n) if s_trans > 0 else np.full(n, trans)
    r2 = rot2 + rng.normal(0.0, s_rot2, n) if s_rot2 > 0 else np.full(n, rot2)
    heading = particles[:, 2] + r1
    out = particles.copy()
    out[:, 0] += tr * np.cos(heading)
    out[:, 1] += tr * np.sin(heading)
    out[:, 2] = wrap_angle(heading + r2)
    return out


def beam_log_likelihood(
    particles: np.ndarray,
    angles: np.ndarray,
    ranges: np.ndarray,
    range_max: float,
    field: LikelihoodField,
    model: LaserModel,
) -> np.ndarray:
    """log p(z | x, m) per particle with the likelihood-field model (Eq. 18's measurement term)."""
    ok = valid_beams(ranges, range_max)
    angles, ranges = angles[ok], ranges[ok]
    if len(ranges) == 0:
        return np.zeros(len(particles))
    if len(ranges) > model.beams:
        pick = np.linspace(0, len(ranges) - 1, model.beams).astype(int)
        angles, ranges = angles[pick], ranges[pick]
    heading = particles[:, 2:3] + angles[None, :]
    ex = particles[:, 0:1] + ranges[None, :] * np.cos(heading)
    ey = particles[:, 1:2] + ranges[None, :] * np.sin(heading)
    d = field.lookup(ex, ey)
    p = model.z_hit * np.exp(-(d * d) / (2 * model.sigma_hit**2)) + model.z_rand / range_max
    logp = np.log(p)
    if model.beam_skip_threshold > 0 and len(particles) > 1:
        fits = (d < model.beam_skip_distance).mean(axis=0)
        keep = fits >= model.beam_skip_threshold
        if keep.mean() >= 1.0 - model.beam_skip_error_threshold:
            logp = logp[:, keep]
    loglik: np.ndarray = logp.sum(axis=1) / model.temperature
    return loglik


@dataclass
class PoseEstimate:
    pose: Pose2D
    covariance: np.ndarray  # 3x3 (x, y, yaw)


class ParticleFilter:
    def __init__(
        self, field: LikelihoodField, n: int, noise: FilterNoise, model: LaserModel, rng: np.random.Generator
    ):
        self.field = field
        self.n = n
        self.noise = noise
        self.model = model
        self.rng = rng
        self.particles = np.zeros((n, 3))
        self.weights = np.full(n, 1.0 / n)
        self.last_likelihood = 0.0

    def seed(self, pose: Pose2D, sigma_xy: float, sigma_yaw: float) -> None:
        self.particles = np.column_stack(
            [
                self.rng.normal(pose.x, sigma_xy, self.n),
                self.rng.normal(pose.y, sigma_xy, self.n),
                wrap_angle(self.rng.normal(pose.yaw, sigma_yaw, self.n)),
            ]
        )
        self.weights = np.full(self.n, 1.0 / self.n)

    def seed_uniform(self, xy: np.ndarray) -> None:
        """Spread particles over the given free positions with random headings (global localisation)."""
        pick = self.rng.integers(0, len(xy), self.n)
        jitter = self.rng.uniform(-0.5, 0.5, (self.n, 2)) * self.field.grid.resolution
        self.particles = np.column_stack([xy[pick] + jitter, self.rng.uniform(-math.pi, math.pi, self.n)])
        self.weights = np.full(self.n, 1.0 / self.n)

    def weight_by_landmarks(
        self, robot_odom: Pose2D, odom_xy: np.ndarray, bim_xy: np.ndarray, sigma: float
    ) -> None:
        """Weight particles by how well their implied odom->BIM transform maps the matched features.

        A particle at BIM pose P implies T = P * odom^-1; the matched features s_j (odom frame) should
        land on their BIM features b_j. Used once, at seeding: the coarse match's evidence as a prior.
        """
        if len(odom_xy) == 0:
            return
        rel = robot_odom.apply_inverse(np.asarray(odom_xy, dtype=float))  # features in the robot frame
        c, s = np.cos(self.particles[:, 2]), np.sin(self.particles[:, 2])
        mx = self.particles[:, 0:1] + c[:, None] * rel[None, :, 0] - s[:, None] * rel[None, :, 1]
        my = self.particles[:, 1:2] + s[:, None] * rel[None, :, 0] + c[:, None] * rel[None, :, 1]
        r2 = (mx - bim_xy[None, :, 0]) ** 2 + (my - bim_xy[None, :, 1]) ** 2
        logw = np.log(np.maximum(self.weights, 1e-300)) - r2.sum(axis=1) / (2 * sigma**2)
        w = np.exp(logw - logw.max())
        self.weights = w / w.sum()
        self.resample()

    def predict(self, delta: tuple[float, float, float]) -> None:
        self.particles = sample_motion(self.particles, delta, self.noise, self.rng)

    def update(self, angles: np.ndarray, ranges: np.ndarray, range_max: float) -> None:
        loglik = beam_log_likelihood(self.particles, angles, ranges, range_max, self.field, self.model)
        logw = np.log(np.maximum(self.weights, 1e-300)) + loglik
        logw -= logw.max()
        w = np.exp(logw)
        self.weights = w / w.sum()
        self.last_likelihood = float(
            np.exp(loglik.max() * self.model.temperature / self._beams_used(ranges, range_max))
        )
        if self.effective_size() < self.n / 2:
            self.resample()

    def _beams_used(self, ranges: np.ndarray, range_max: float) -> int:
        valid = int(valid_beams(ranges, range_max).sum())
        return max(1, min(self.model.beams, valid))

    def effective_size(self) -> float:
        return float(1.0 / np.sum(self.weights**2))

    def resample(self) -> None:
        """Low-variance (systematic) resampling."""
        self.particles = self.particles[low_variance_indices(self.weights, self.n, self.rng)]
        self.weights = np.full(self.n, 1.0 / self.n)

    def estimate(self) -> PoseEstimate:
        return PoseEstimate(*weighted_pose_stats(self.particles, self.weights))


def low_variance_indices(weights: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Low-variance (systematic) resampling: ``count`` indices into ``weights`` (normalised).

    The tracking filter draws as many particles as it has; KLD-sampling draws another count.
    """
    positions = (rng.random() + np.arange(count)) / count
    idx = np.searchsorted(np.cumsum(weights), positions)
    return np.minimum(idx, len(weights) - 1)


def weighted_pose_stats(particles: np.ndarray, weights: np.ndarray) -> tuple[Pose2D, np.ndarray]:
    """Weighted mean (circular in yaw) and 3x3 covariance of a particle set; ``weights`` sum to 1."""
    w = weights
    x = float(np.sum(w * particles[:, 0]))
    y = float(np.sum(w * particles[:, 1]))
    c, s = float(np.sum(w * np.cos(particles[:, 2]))), float(np.sum(w * np.sin(particles[:, 2])))
    yaw = math.atan2(s, c)
    dev = np.column_stack([particles[:, 0] - x, particles[:, 1] - y, wrap_angle(particles[:, 2] - yaw)])
    return Pose2D(x, y, yaw), (dev * w[:, None]).T @ dev


def scan_fit(
    pose: Pose2D,
    angles: np.ndarray,
    ranges: np.ndarray,
    range_max: float,
    field: LikelihoodField,
    tolerance: float = 0.25,
) -> float:
    """Fraction of a scan's valid beams whose end points lie within ``tolerance`` of an occupied
    map cell, seen from ``pose``, with no beam skipped: a check of a final estimate. Beam skipping
    (above) lets a whole cloud in the wrong place keep only the beams that happen to agree with it;
    at the right pose most beams end on mapped walls even with clutter about."""
    ok = valid_beams(ranges, range_max)
    if not ok.any():
        return 0.0
    heading = pose.yaw + angles[ok]
    ex = pose.x + ranges[ok] * np.cos(heading)
    ey = pose.y + ranges[ok] * np.sin(heading)
    return float((field.lookup(ex, ey) < tolerance).mean())
