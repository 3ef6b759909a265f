"""AMCL global localisation (the ``amcl`` baseline of §4.3): a particle filter from a uniform prior.

The paper's AMCL baseline "generat[es] 5000 randomly distributed particles on the map", updates
them with the motion and observation models as the robot follows the wall, groups them into
clouds, and stops once the covariance is below the threshold used for PF-based fine tuning
(§4.3). The filter is the recursion of Eq. 18,

    bel(x_t) = eta * p(z_t | x_t, m) * integral p(x_t | x_{t-1}, u_t, m) bel(x_{t-1}) dx,

with the motion and likelihood-field models of :mod:`initcli.core.filters.particle_filter` (the same
ones fine tuning tracks with), started from particles spread uniformly over the free cells of
the occupancy grid with random headings instead of around a rectified pose.

As in ROS AMCL:

- the filter updates only after ``update_min_d`` of translation or ``update_min_a`` of rotation,
  and resamples (low-variance) at every update (``resample_interval`` 1);
- KLD-sampling (Fox, "Adapting the sample size in particle filters through KLD-sampling",
  IJRR 2003) chooses how many particles to draw at each resampling: with k histogram bins
  (0.5 m x 0.5 m x 10 degrees) holding particles, n = (k - 1) / (2 eps) * (1 - 2/(9(k-1)) +
  sqrt(2/(9(k-1))) z)^3 particles bound the KL divergence between the sample-based and the
  true posterior by eps with probability 1 - delta, clamped to [min_particles, particles];
  ROS passes ``kld_z`` (0.99) directly as z, and so does this module;
- particles are clustered by connecting occupied histogram bins (26-neighbourhood, headings
  wrapping at +-180 degrees); the reported pose is the mean of the heaviest cluster and the
  reported covariance is that of the whole particle set (``amcl_node`` publishes
  ``set->cov``, "the overall filter covariance, rather than the covariance for the
  highest-weight cluster"), so a cloud split between symmetric places never looks converged.

Pure numpy; the map is an :class:`~bimtools.site.occupancy_map.OccupancyGrid`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from bimtools.site.records import FREE, OccupancyGrid
from initcli.core.filters.grid_cache import GridCache
from initcli.core.filters.particle_filter import (
    FilterNoise,
    LaserModel,
    LikelihoodField,
    ParticleFilter,
    beam_log_likelihood,
    likelihood_field,
    low_variance_indices,
    weighted_pose_stats,
)
from initcli.core.geometry.se2 import Pose2D, wrap_angle

__all__ = [
    "GlobalEstimate",
    "GlobalLocalisation",
    "GlobalLocalisationParams",
    "PoseHistogram",
    "YAW_BINS_FULL_TURN",
    "free_cell_centres",
    "kld_sample_limit",
]

YAW_BINS_FULL_TURN = 36  # 360 degrees / 10 degrees


@dataclass(frozen=True)
class GlobalLocalisationParams:
    """AMCL global localisation settings; ROS AMCL's defaults where it has them."""

    particles: int = 5000  # max_particles; the paper's 5000 random particles (§4.3)
    min_particles: int = 500  # min_particles (ROS AMCL default)
    kld: bool = True  # KLD-sampling; False keeps ``particles`` particles throughout
    kld_err: float = 0.01  # pf_err: bound on the KL divergence
    kld_z: float = 0.99  # pf_z, used as the normal quantile z_{1-delta} exactly as ROS AMCL does
    bin_xy: float = 0.5  # m, KLD histogram / cluster bin size in x and y (ROS pf_kdtree)
    bin_yaw: float = math.radians(10.0)  # rad, KLD histogram / cluster bin size in heading
    update_min_d: float = 0.25  # m of translation before a filter update (update_min_d)
    update_min_a: float = 0.2  # rad of rotation before a filter update (update_min_a)
    laser: LaserModel = field(default_factory=LaserModel)  # likelihood field, as fine tuning uses
    noise: FilterNoise = field(default_factory=FilterNoise)  # odometry-model alphas


@dataclass
class GlobalEstimate:
    """The filter's answer after an update.

    ``pose``: mean of the heaviest cluster; ``covariance``: 3x3 (x, y, yaw) covariance of the whole
    particle set (what ROS AMCL publishes, and what the convergence test reads);
    ``cluster_covariance``: the heaviest cluster's own covariance; ``clusters``: how many clusters;
    ``cluster_weight``: the heaviest cluster's share of the weight.
    """

    pose: Pose2D
    covariance: np.ndarray
    cluster_covariance: np.ndarray
    clusters: int
    cluster_weight: float
    particles: int


def kld_sample_limit(bins: np.ndarray | int, params: GlobalLocalisationParams) -> np.ndarray:
    """Fox's KLD bound on the particle count for ``bins`` occupied histogram bins (ROS pf_resample_limit).

    Vectorised over ``bins``; clamped to [min_particles, particles]. One occupied bin needs the
    minimum: Fox's bound is 0 there. (ROS AMCL returns the maximum for k <= 1, so a cloud that
    fits in one bin jumps to max_particles at every resampling; that quirk is not reproduced.)
    """
    k = np.asarray(bins, dtype=float)
    km1 = np.maximum(k - 1.0, 1.0)
    b = 2.0 / (9.0 * km1)
    x = 1.0 - b + np.sqrt(b) * params.kld_z
    n = np.ceil(km1 / (2.0 * params.kld_err) * x**3)
    n = np.where(k <= 1, params.min_particles, n)
    return np.clip(n, params.min_particles, params.particles).astype(np.int64)


class PoseHistogram:
    """The KLD / clustering histogram: 0.5 m x 0.5 m x 10 degree bins (ROS pf_kdtree's leaves)."""

    def __init__(self, grid: OccupancyGrid, bin_xy: float, bin_yaw: float):
        rows, cols = grid.cells.shape
        self.origin = (float(grid.origin[0]), float(grid.origin[1]))
        self.bin_xy = bin_xy
        self.yaw_bins = max(1, round(2 * math.pi / bin_yaw))
        # One bin of margin on every side so neighbours of edge bins encode without clashing.
        self.nx = math.ceil(cols * grid.resolution / bin_xy) + 3
        self.ny = math.ceil(rows * grid.resolution / bin_xy) + 3

    def cells(self, particles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(ix, iy, iyaw) bin indices of every particle; x and y clipped to the histogram."""
        ix = np.clip(
            np.floor((particles[:, 0] - self.origin[0]) / self.bin_xy).astype(np.int64) + 1, 0, self.nx - 1
        )
        iy = np.clip(
            np.floor((particles[:, 1] - self.origin[1]) / self.bin_xy).astype(np.int64) + 1, 0, self.ny - 1
        )
        ia = (
            np.floor((particles[:, 2] + math.pi) / (2 * math.pi) * self.yaw_bins).astype(np.int64)
            % self.yaw_bins
        )
        return ix, iy, ia

    def encode(self, ix: np.ndarray, iy: np.ndarray, ia: np.ndarray) -> np.ndarray:
        code: np.ndarray = (ix * self.ny + iy) * self.yaw_bins + ia
        return code

    def keys(self, particles: np.ndarray) -> np.ndarray:
        return self.encode(*self.cells(particles))

    def clusters(self, particles: np.ndarray) -> np.ndarray:
        """Cluster label per particle: connected components of occupied bins (26-neighbourhood).

        ROS AMCL's pf_kdtree_cluster joins adjacent leaves the same way; here headings wrap.
        """
        ix, iy, ia = self.cells(particles)
        keys = self.encode(ix, iy, ia)
        unique, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
        k = len(unique)
        if k <= 1:
            return np.zeros(len(particles), dtype=np.int64)
        bx, by, ba = ix[first], iy[first], ia[first]
        sources, targets = [], []
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for da in (-1, 0, 1):
                    if (dx, dy, da) <= (0, 0, 0):
                        continue  # each undirected neighbour pair once
                    nb = self.encode(
                        np.clip(bx + dx, 0, self.nx - 1),
                        np.clip(by + dy, 0, self.ny - 1),
                        (ba + da) % self.yaw_bins,
                    )
                    pos = np.minimum(np.searchsorted(unique, nb), k - 1)
                    hit = (unique[pos] == nb) & (pos != np.arange(k))
                    sources.append(np.nonzero(hit)[0])
                    targets.append(pos[hit])
        a, b = np.concatenate(sources), np.concatenate(targets)
        labels = np.arange(k)
        while True:  # min-label propagation with pointer jumping
            m = np.minimum(labels[a], labels[b])
            new = labels.copy()
            np.minimum.at(new, a, m)
            np.minimum.at(new, b, m)
            new = new[new]
            if np.array_equal(new, labels):
                break
            labels = new
        _, compact = np.unique(labels, return_inverse=True)
        return compact[inverse]


_FREE_CELLS: GridCache[np.ndarray] = GridCache()


def free_cell_centres(grid: OccupancyGrid) -> np.ndarray:
    """(N, 2) world centres of the grid's free cells: where global localisation spreads particles
    (read-only; built once per map content in this process)."""

    def build() -> np.ndarray:
        rows, cols = np.nonzero(grid.cells == FREE)
        x, y = grid.cell_centre(rows, cols)
        centres = np.column_stack([x, y])
        centres.flags.writeable = False
        return centres

    return _FREE_CELLS.get(grid, None, build)


class GlobalLocalisation:
    """AMCL global localisation on an occupancy grid (Eq. 18 from a uniform prior, KLD-sampling).

    Drive it like ROS AMCL: :meth:`moved_enough` on the odometry motion since the last update,
    then :meth:`predict` with that motion and :meth:`update` with the scan.
    """

    def __init__(
        self,
        grid: OccupancyGrid,
        params: GlobalLocalisationParams,
        rng: np.random.Generator,
        field: LikelihoodField | None = None,
    ):
        self.params = params
        self.rng = rng
        self.field = field if field is not None else likelihood_field(grid, params.laser.max_distance)
        self.histogram = PoseHistogram(grid, params.bin_xy, params.bin_yaw)
        self.filter = ParticleFilter(self.field, params.particles, params.noise, params.laser, rng)
        free = free_cell_centres(grid)
        if len(free) == 0:
            raise ValueError("the occupancy grid has no free cells to spread particles over")
        self.filter.seed_uniform(free)
        # float32 halves the memory traffic of the beam end points; 1e-5 m at 100 m is plenty.
        self.filter.particles = self.filter.particles.astype(np.float32)
        self.updates = 0

    @property
    def particles(self) -> np.ndarray:
        return self.filter.particles

    @property
    def count(self) -> int:
        return len(self.filter.particles)

    def moved_enough(self, delta: tuple[float, float, float]) -> bool:
        """ROS AMCL's update gate: ``update_min_d`` of translation or ``update_min_a`` of rotation."""
        rot1, trans, rot2 = delta
        return (
            abs(trans) >= self.params.update_min_d or abs(wrap_angle(rot1 + rot2)) >= self.params.update_min_a
        )

    def predict(self, delta: tuple[float, float, float]) -> None:
        """Motion update: sample p(x_t | x_{t-1}, u_t) for every particle (Eq. 18's integral)."""
        self.filter.predict(delta)  # sample_motion copies the float32 array and keeps its dtype

    def update(self, angles: np.ndarray, ranges: np.ndarray, range_max: float) -> None:
        """Measurement update p(z_t | x_t, m) (Eq. 18), then (KLD-)resampling."""
        particles = self.filter.particles
        loglik = beam_log_likelihood(
            particles,
            np.asarray(angles, dtype=np.float32),
            np.asarray(ranges, dtype=np.float32),
            range_max,
            self.field,
            self.params.laser,
        )
        logw = np.log(np.maximum(self.filter.weights, 1e-300)) + loglik
        w = np.exp(logw - logw.max())
        self.filter.weights = w / w.sum()
        self.resample()
        self.updates += 1

    def resample(self) -> None:
        """Low-variance resampling to ``particles`` or, with KLD, to Fox's bound on the count.

        KLD: draw ``particles`` candidates from the weights in random order and keep the shortest
        prefix whose size exceeds the bound for the bins that prefix occupies (ROS AMCL adds one
        sample at a time and stops the same way); the kept count is then drawn low-variance.
        """
        weights = self.filter.weights
        p = self.params
        count = p.particles
        if p.kld:
            candidates = self.filter.particles[low_variance_indices(weights, p.particles, self.rng)]
            candidates = candidates[self.rng.permutation(p.particles)]
            keys = self.histogram.keys(candidates)
            _, first = np.unique(keys, return_index=True)
            new_bin = np.zeros(p.particles, dtype=np.int64)
            new_bin[first] = 1
            bins = np.cumsum(new_bin)  # occupied bins after 1, 2, ... samples
            drawn = np.arange(1, p.particles + 1)
            enough = np.nonzero((drawn > kld_sample_limit(bins, p)) | (drawn >= p.particles))[0]
            count = max(p.min_particles, int(drawn[enough[0]]))
        idx = low_variance_indices(weights, count, self.rng)
        self.filter.particles = self.filter.particles[idx]
        self.filter.n = count
        self.filter.weights = np.full(count, 1.0 / count)

    def whole_covariance(self) -> np.ndarray:
        """3x3 covariance of the whole set (cheap; the convergence test needs only this)."""
        return weighted_pose_stats(self.filter.particles.astype(np.float64), self.filter.weights)[1]

    def estimate(self) -> GlobalEstimate:
        """Heaviest cluster's mean, whole-set covariance (ROS AMCL's published pose)."""
        particles = self.filter.particles.astype(np.float64)
        weights = self.filter.weights
        _, cov = weighted_pose_stats(particles, weights)
        labels = self.histogram.clusters(particles)
        totals = np.bincount(labels, weights=weights)
        best = int(np.argmax(totals))
        mine = labels == best
        pose, cluster_cov = weighted_pose_stats(particles[mine], weights[mine] / totals[best])
        return GlobalEstimate(
            pose, cov, cluster_cov, len(totals), float(totals[best] / totals.sum()), len(particles)
        )
