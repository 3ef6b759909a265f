"""Real laser logs as test cases: the truth, two maps and windows with drifting odometry.

A CARMEN log "corrected" by SLAM (``../shared/real_lidar``) carries poses that serve as the truth;
its odometry is that truth, so a realistic window adds drift. The maps are drawn from the log
itself, in the frame of its detection log (:func:`initcli.io.carmen.carmen_to_records`):

* the **whole-log map**: every scan ray-traced at its true pose (free along a beam, occupied where
  it ends, as a SLAM map is made);
* the **walls-only map**: the long straight structures of that map only, as a BIM draws walls; the
  cells the robot's scans saw as furniture, people or clutter are free there, though the scans still
  see them.

Nothing here is an algorithm of the package: these are the benchmark's test cases.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from bimtools.site.records import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from initcli.core.geometry.se2 import Pose2D
from initcli.io.log_records import Meta, Odom, Scan

__all__ = [
    "DRIFT",
    "Drift",
    "LogTruth",
    "log_truth",
    "walls_only",
    "whole_log_map",
    "window_records",
    "windows",
    "write_site",
    "drift_scales",
    "drifted_poses",
]

RESOLUTION = 0.05  # m per cell of both maps
FREE_NO_RETURN = 8.0  # m: a beam with no return clears the map this far (glass, open doors)
WALL_MIN_LENGTH = 2.0  # m: a straight run of occupied cells at least this long is a wall
WALL_GAP = 0.3  # m: gaps a wall line bridges (doors and pillars excepted)


@dataclass(frozen=True)
class Drift:
    """Wheel odometry's errors, drawn once per window: a scale error of the distance and of the
    turns (one to a few percent, the README's figure) and a heading random walk per metre."""

    scale_sd: float = 0.02  # share: sd of the distance scale error
    turn_sd: float = 0.02  # share: sd of the turn scale error
    heading_per_m: float = math.radians(0.3)  # rad per sqrt(m): the heading's random walk


DRIFT = Drift()


@dataclass(frozen=True)
class LogTruth:
    """A log's records and its true trajectory, in the detection log's frame."""

    meta: Meta
    odom: list[Odom]  # the true poses, in time order
    scans: list[Scan]
    scan_poses: np.ndarray  # (scans, 3): x, y, yaw of the robot at each scan
    travel: np.ndarray  # (scans,) m travelled up to each scan


def _interpolate(odom: list[Odom], t: np.ndarray) -> np.ndarray:
    times = np.array([o.t for o in odom])
    xy = np.array([[o.x, o.y] for o in odom])
    yaw = np.unwrap(np.array([o.yaw for o in odom]))
    x = np.interp(t, times, xy[:, 0])
    y = np.interp(t, times, xy[:, 1])
    return np.column_stack([x, y, np.interp(t, times, yaw)])


def log_truth(path: Path) -> LogTruth:
    """The CARMEN log at ``path`` read as ``bim-init bag2log`` reads it, with its truth."""
    from initcli.io.carmen import carmen_to_records

    records, _ = carmen_to_records(path)
    meta = records[0]
    assert isinstance(meta, Meta)
    odom = [r for r in records if isinstance(r, Odom)]
    scans = [r for r in records if isinstance(r, Scan)]
    poses = _interpolate(odom, np.array([s.t for s in scans]))
    steps = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    return LogTruth(meta, odom, scans, poses, np.concatenate([[0.0], np.cumsum(steps)]))


def _beams(scan: Scan) -> tuple[np.ndarray, np.ndarray]:
    ranges = np.array(scan.ranges, dtype=float)
    angles = scan.angle_min + scan.angle_increment * np.arange(len(ranges))
    return angles, ranges


def whole_log_map(truth: LogTruth, resolution: float = RESOLUTION) -> OccupancyGrid:
    """Every scan ray-traced at its true pose: occupied where beams end (at least a quarter of the
    beams through a cell end there), free where they pass, unknown elsewhere."""
    ends, passes_xy = [], []
    for scan, (x, y, yaw) in zip(truth.scans, truth.scan_poses, strict=True):
        angles, ranges = _beams(scan)
        hit = np.isfinite(ranges) & (ranges > 0.05) & (ranges < scan.range_max)
        reach = np.where(hit, ranges - resolution, np.minimum(scan.range_max, FREE_NO_RETURN))
        reach = np.where(np.isfinite(reach), reach, FREE_NO_RETURN)
        a = yaw + angles
        ends.append(np.column_stack([x + ranges[hit] * np.cos(a[hit]), y + ranges[hit] * np.sin(a[hit])]))
        steps = np.arange(0.0, float(reach.max(initial=0.0)), resolution / 2)
        inside = steps[None, :] < reach[:, None]
        px = x + steps[None, :] * np.cos(a)[:, None]
        py = y + steps[None, :] * np.sin(a)[:, None]
        passes_xy.append(np.column_stack([px[inside], py[inside]]))
    hits_xy = np.vstack(ends)
    low = hits_xy.min(axis=0) - 1.0
    high = hits_xy.max(axis=0) + 1.0
    cols, rows = (np.ceil((high - low) / resolution)).astype(int) + 1

    def counts(xy: np.ndarray) -> np.ndarray:
        c = np.floor((xy - low) / resolution).astype(np.int64)
        ok = (c[:, 0] >= 0) & (c[:, 0] < cols) & (c[:, 1] >= 0) & (c[:, 1] < rows)
        return np.bincount(c[ok, 1] * cols + c[ok, 0], minlength=rows * cols).reshape(rows, cols)

    hits = counts(hits_xy)
    passes = counts(np.vstack(passes_xy))
    cells = np.full((rows, cols), UNKNOWN, np.uint8)
    cells[passes > 0] = FREE
    cells[(hits > 0) & (4 * hits >= passes)] = OCCUPIED
    return OccupancyGrid(cells[::-1].copy(), resolution, (float(low[0]), float(low[1]), 0.0))


def walls_only(grid: OccupancyGrid) -> OccupancyGrid:
    """The map's long straight structures (at least :data:`WALL_MIN_LENGTH`, by a probabilistic
    Hough transform) drawn two cells thick; every other occupied cell free."""
    occupied = (grid.cells == OCCUPIED).astype(np.uint8) * 255
    length = int(WALL_MIN_LENGTH / grid.resolution)
    lines = cv2.HoughLinesP(
        occupied,
        1,
        np.pi / 360,
        threshold=int(0.6 * length),
        minLineLength=length,
        maxLineGap=int(WALL_GAP / grid.resolution),
    )
    walls = np.zeros_like(occupied)
    for x1, y1, x2, y2 in lines.reshape(-1, 4) if lines is not None else ():
        cv2.line(walls, (int(x1), int(y1)), (int(x2), int(y2)), 255, 2)
    cells = grid.cells.copy()
    cells[cells == OCCUPIED] = FREE
    cells[walls > 0] = OCCUPIED
    return dataclasses.replace(grid, cells=cells)


def windows(truth: LogTruth, length: float, count: int) -> list[tuple[int, int]]:
    """``count`` stretches of ``length`` m of travel, their starts spread evenly over the log:
    (first scan, last scan)."""
    total = float(truth.travel[-1])
    if total < length:
        return []
    found = []
    for start in np.linspace(0.0, total - length, count):
        i = int(np.searchsorted(truth.travel, start))
        j = int(np.searchsorted(truth.travel, start + length))
        if j < len(truth.scans) and (i, j) not in found:
            found.append((i, j))
    return found


def drifted_poses(
    odom: list[Odom], start: Pose2D, drift: Drift, rng: np.random.Generator, scale: float, turn: float
) -> list[Pose2D]:
    """The motion of ``odom`` from ``start`` as drifting wheels count it: each step's distance times
    ``scale``, its turn times ``turn`` plus the heading's random walk."""
    pose, out = start, [start]
    for a, b in zip(odom[:-1], odom[1:], strict=True):
        step = a.pose.inverse() * b.pose
        dist = math.hypot(step.x, step.y)
        noise = rng.normal(0.0, drift.heading_per_m * math.sqrt(dist)) if dist > 0 else 0.0
        pose = pose * Pose2D(step.x * scale, step.y * scale, step.yaw * turn + noise)
        out.append(pose)
    return out


def drift_scales(drift: Drift, rng: np.random.Generator) -> tuple[float, float]:
    """One window's scale errors of the distance and of the turns."""
    return 1.0 + rng.normal(0.0, drift.scale_sd), 1.0 + rng.normal(0.0, drift.turn_sd)


def _drifted(odom: list[Odom], drift: Drift, rng: np.random.Generator) -> list[Odom]:
    scale, turn = drift_scales(drift, rng)
    poses = drifted_poses(odom, odom[0].pose, drift, rng, scale, turn)
    return [odom[0]] + [Odom(b.t, p.x, p.y, p.yaw) for b, p in zip(odom[1:], poses[1:], strict=True)]


def window_records(
    truth: LogTruth, first: int, last: int, drift: Drift, rng: np.random.Generator
) -> tuple[list[Meta | Odom | Scan], Pose2D]:
    """The log between scans ``first`` and ``last`` with drifting odometry, and the robot's true pose
    at the window's last odometry stamp (where ``bim-init match`` reports its pose)."""
    t0, t1 = truth.scans[first].t, truth.scans[last].t
    odom = [o for o in truth.odom if t0 <= o.t <= t1]
    scans = [s for s in truth.scans if t0 <= s.t <= t1]
    end = odom[-1]
    records: list[Meta | Odom | Scan] = [truth.meta, *sorted([*_drifted(odom, drift, rng), *scans], key=_t)]
    return records, Pose2D(end.x, end.y, end.yaw)


def _t(record: Odom | Scan) -> float:
    return record.t


def write_site(grid: OccupancyGrid, name: str, workdir: Path) -> Path:
    """``grid`` as a Nav2 map, then ``bim-extract MAP.yaml -o SITE``'s site (its storey ``name``)."""
    from bimtools.extract.from_map import extract_map_site, write_map_site
    from bimtools.site.occupancy_map import write_map

    yaml_path = workdir / f"{name}.yaml"
    write_map(yaml_path, grid)
    site = workdir / f"{name}_site"
    write_map_site(site, extract_map_site(yaml_path), preview=False)
    return site
