"""Global lidar submap registration against the BIM map (beyond the paper): a pose with no camera.

The beam end points of the recent scans (:class:`~initcli.core.lidar.scan_fit.BeamEnds`, in the robot frame
at the last scan, odometry joining them) are a local submap. It is placed over every storey's map by
the score of the fine-tuning filter's end-point model (Eq. 18's likelihood field, with no beam
skipped): the share of beam ends within a tolerance of a mapped wall.

* **Coarse**: for each heading of a ``turn_step_deg`` grid the submap is rasterised into a template
  of ``cell`` m cells and correlated with a soft wall map of the same cells (``1 - d / reach`` for a
  cell whose nearest wall is ``d`` away, max-pooled, so that the rounding to coarse cells costs no
  fit) by ``cv2.matchTemplate``; only positions on free cells count (the robot stood there).
* **Peaks**: the best coarse poses, no two closer than ``peak_m`` and ``peak_deg``.
* **Fine**: each peak refined by :func:`~initcli.core.lidar.scan_fit.best_scan_alignment` (two grids),
  its fit the share of beams on walls at ``tolerance``. The map placed and scored on is the map with
  the model's doors shut (:func:`shut_doorways`): a section may leave a doorway free where the door
  stands shut in its frame on site.
* **Unique**: the best fit must reach ``min_fit``, and every refined peak ``distinct_m`` or
  ``distinct_deg`` away from it (a rival) must trail it by ``margin``: a corridor or rooms that
  repeat leave two places alike and no pose is reported.
* **Through walls**: a rival within ``margin`` is ruled out when more of its beams (by
  ``see_through``) cross a mapped wall well before their end than the best pose's do, and the best
  pose's hardly any: beams through an open door or a doorway that the place alike has a wall at (a
  plan that repeats, or turned half round, but whose doors do not); only on a submap of at least
  ``through_min_sampled`` beams, where a door the model lacks is no large share. The walls crossed
  are those of the map as drawn (doors closed) or, when that rules nothing out, of the map with the
  model's doors open (:func:`open_doorways`): a beam through a door the model has there crosses
  nothing, as the door may stand open on site.

Pure numpy (and OpenCV's correlation); the session decides what to do with the result.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import cv2
import numpy as np

from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.se2 import Pose2D, wrap_angle
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import BeamEnds, best_scan_alignment

__all__ = [
    "Candidate",
    "GRID",
    "Registration",
    "RegistrationMap",
    "open_doorways",
    "SearchGrid",
    "register",
    "shut_doorways",
    "thin_points",
    "wall_crossings",
]


@dataclass(frozen=True)
class SearchGrid:
    """The coarse search's grids (fixed: measured on the samples, not settings)."""

    cell: float = 0.25  # m: coarse grid of positions and of the template
    turn_step_deg: float = 5.0  # degrees between the coarse headings
    reach: float = 0.5  # m: the coarse wall map falls to 0 this far from a wall
    peaks: int = 24  # coarse peaks refined (and local maxima kept per heading)
    peak_m: float = 1.0  # m: coarse peaks at least this far apart ...
    peak_deg: float = 15.0  # ... or turned this much
    max_points: int = 1500  # beam ends kept (thinned on a grid of cell / 2)
    through_beams: int = 1000  # beams sampled for the wall-crossing test ...
    through_short: float = 0.75  # m: ... a wall crossed this far or more before a beam's end ...
    through_clear: float = 0.5  # m: ... by a beam that then gets this far from every wall counts ...
    through_best: float = 0.02  # ... and the best pose may have at most this share of such beams
    through_min_sampled: int = 500  # beams a submap needs for the test at all: on a single scan's 59
    # one beam through a wall ruled out 17 places alike (a pose 33 m off), and six beams through a
    # door the model lacks the true place (CHANGELOG, the first registration at 0 m)
    door_slack: float = 0.3  # m: a door's opening widened by this on each side (built off its place) ...
    door_depth: float = 0.6  # m: ... and opened this far behind its face (the wall's thickness) ...
    door_front: float = 0.2  # m: ... and this far in front of it (a wall standing proud of the door);
    # shut_doorways looks for the jambs of a free opening as far (door_slack beyond its half width,
    # door_depth behind its face, door_front in front of it)


GRID = SearchGrid()
THROUGH_RATIO = 3.0  # a rival ruled out by beams through walls sends this many times the best's through


@dataclass(frozen=True)
class Candidate:
    """A refined peak: its storey, the robot's pose at the last scan and its fit."""

    storey: str
    pose: Pose2D
    fit: float
    coarse: float  # the coarse score, share of beam ends

    def apart(self, other: Candidate, params: RegistrationParams) -> bool:
        """Is ``other`` a distinct place (another storey, or ``distinct_m`` / ``distinct_deg`` away)?"""
        if other.storey != self.storey:
            return True
        far = self.pose.distance_to(other.pose) >= params.distinct_m
        return far or self.pose.yaw_error(other.pose) >= math.radians(params.distinct_deg)


@dataclass(frozen=True)
class Registration:
    """The outcome: the refined peaks best first; ``unique`` when the best one stands out."""

    candidates: tuple[Candidate, ...]  # the best pose, then the distinct places, best first
    unique: bool
    why: str
    points: int
    contested: tuple[Candidate, ...] = ()  # distinct places within margin of a best pose fitting min_fit
    through: tuple[float, ...] = ()  # share of beams crossing walls: the best pose, then each contested
    doors_open: bool = False  # ``through`` measured on the map with its doors open (else as drawn)
    lines: float = 0.0  # m: registered on the beams on straight lines this long (0: every beam)

    @property
    def best(self) -> Candidate | None:
        return self.candidates[0] if self.candidates else None

    @property
    def rival(self) -> Candidate | None:
        """The best candidate distinct from the best one (None: none found)."""
        return self.candidates[1] if len(self.candidates) > 1 else None


class RegistrationMap:
    """One storey's map prepared for the coarse search (once per map). ``field_`` is the map as
    drawn, ``through`` the map with its doors open (:func:`open_doorways`; None: ``field_``), the two
    that the wall-crossing test reads; ``fit`` the map with its doors shut (:func:`shut_doorways`;
    None: ``field_``), that the submap is placed and scored on."""

    def __init__(
        self,
        storey: str,
        grid: OccupancyGrid,
        field_: LikelihoodField,
        params: SearchGrid = GRID,
        through: LikelihoodField | None = None,
        fit: LikelihoodField | None = None,
    ):
        self.storey, self.grid, self.field_ = storey, grid, field_
        self.through = through if through is not None else field_
        self.fit = fit if fit is not None else field_
        k = max(1, int(round(params.cell / grid.resolution)))
        self.cell = k * grid.resolution
        rows, cols = grid.cells.shape
        h, w = -(-rows // k), -(-cols // k)
        # rows counted up from the map's bottom edge (y grows with the row index here)
        soft = np.clip(1.0 - self.fit.distance[::-1] / params.reach, 0.0, 1.0).astype(np.float32)
        free = (grid.cells[::-1] == FREE).astype(np.uint8)
        pad_s = np.zeros((h * k, w * k), np.float32)
        pad_s[:rows, :cols] = soft
        pad_f = np.zeros((h * k, w * k), np.uint8)
        pad_f[:rows, :cols] = free
        self.score = pad_s.reshape(h, k, w, k).max(axis=(1, 3))  # max-pooled soft wall map
        self.free = pad_f.reshape(h, k, w, k).max(axis=(1, 3)) > 0
        self.origin = (float(grid.origin[0]), float(grid.origin[1]))


def open_doorways(
    grid: OccupancyGrid, doors: np.ndarray, slack: float, depth: float, front: float
) -> OccupancyGrid:
    """``grid`` with the openings of ``doors`` free: (N, 5) rows of a door's face centre x, y, its
    unit normal (pointing out of the wall) and its width, all m. Each opening is widened by
    ``slack`` on each side and runs from ``front`` in front of the face to ``depth`` behind it."""
    cells = grid.cells.copy()
    rows, cols = cells.shape
    res = grid.resolution
    for x, y, nx, ny, width in np.asarray(doors, dtype=float).reshape(-1, 5):
        half = width / 2.0 + slack
        reach = math.hypot(half, max(depth, front)) + res
        top, left = grid.world_to_cell(x - reach, y + reach)
        bottom, right = grid.world_to_cell(x + reach, y - reach)
        r0, r1 = max(int(top), 0), min(int(bottom), rows - 1)
        c0, c1 = max(int(left), 0), min(int(right), cols - 1)
        if r0 > r1 or c0 > c1:
            continue
        rr, cc = np.mgrid[r0 : r1 + 1, c0 : c1 + 1]
        cx, cy = grid.cell_centre(rr, cc)
        along = (cx - x) * -ny + (cy - y) * nx
        out = (cx - x) * nx + (cy - y) * ny
        inside = (np.abs(along) <= half) & (out >= -depth) & (out <= front)
        cells[rr[inside], cc[inside]] = FREE
    return replace(grid, cells=cells)


def shut_doorways(
    grid: OccupancyGrid, doors: np.ndarray, reach: float, depth: float, front: float
) -> OccupancyGrid:
    """``grid`` with the openings of ``doors`` (rows as for :func:`open_doorways`) drawn occupied
    across the wall's thickness: a shut leaf stands somewhere in its frame, and a beam that ends on
    it then fits. The wall is found at the door, not assumed: each line across the opening, from
    ``depth`` m behind the face to ``front`` m in front of it, is filled where its free run through
    the door's centre ends in a wall (a jamb or a frame) on both sides within ``reach`` m beyond the
    door's half width; in front of the door and in the room behind it the run goes on, and nothing
    there is filled. A map whose section already shut its doors is unchanged; a door of no width, or
    wider than the map, is left as it is."""
    cells = grid.cells.copy()
    rows, cols = cells.shape
    step = grid.resolution / 2.0
    for x, y, nx, ny, width in np.asarray(doors, dtype=float).reshape(-1, 5):
        if not 0.0 < width <= max(rows, cols) * grid.resolution:
            continue
        n = int(math.ceil((width / 2.0 + reach) / step))
        u = np.arange(-n, n + 1) * step  # m along the wall, the door's centre at index n
        s = np.arange(-depth, front + step / 2, step)  # m out of the wall
        px = x + s[:, None] * nx - u[None, :] * ny
        py = y + s[:, None] * ny + u[None, :] * nx
        r, c = grid.world_to_cell(px, py)
        inside = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
        free = np.zeros(r.shape, dtype=bool)
        free[inside] = cells[r[inside], c[inside]] == FREE
        mid = n
        for k in range(len(s)):
            if not free[k, mid]:
                continue
            blocked = np.flatnonzero(~free[k])
            left, right = blocked[blocked < mid], blocked[blocked > mid]
            if not len(left) or not len(right):
                continue  # open to one side within reach: the corridor or the room, not the opening
            run = slice(int(left[-1]) + 1, int(right[0]))
            if (right[0] - left[-1] - 1) * step < width / 2.0:
                continue  # a gap narrower than half the door is not its opening
            cells[r[k, run], c[k, run]] = OCCUPIED
    return replace(grid, cells=cells)


def thin_points(xy: np.ndarray, cell: float, limit: int) -> np.ndarray:
    """One beam end per ``cell`` grid cell (the first), at most ``limit`` of them, evenly picked: the
    submap's walls weigh by their length, not by how often the robot scanned them."""
    if len(xy) == 0:
        return xy
    keys = np.floor(xy / cell).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    kept = xy[np.sort(first)]
    if len(kept) > limit:
        kept = kept[np.linspace(0, len(kept) - 1, limit).astype(np.intp)]
    return kept


def wall_crossings(
    origins: np.ndarray, ends: np.ndarray, pose: Pose2D, field_: LikelihoodField, short: float, clear: float
) -> float:
    """Share of the beams (from ``origins`` to ``ends``, (N, 2) each in the submap's frame, placed
    by ``pose``) that pass through a wall of the map and on into the open, ``clear`` m or more from
    any wall, ``short`` m or more before their end: beams the map says could not have got there. A
    beam along a wall that a pose a little off puts into it never gets ``clear`` of it."""
    if len(ends) == 0:
        return 0.0
    o, e = pose.apply(origins), pose.apply(ends)
    span = e - o
    length = np.hypot(span[:, 0], span[:, 1])
    reach = length - short
    step = field_.grid.resolution
    k = int(np.ceil(max(float(reach.max()), 0.0) / step)) + 1
    f = np.arange(k) * step  # m along each beam
    unit = span / np.maximum(length, 1e-9)[:, None]
    d = field_.lookup(o[:, 0:1] + unit[:, 0:1] * f[None, :], o[:, 1:2] + unit[:, 1:2] * f[None, :])
    inside = f[None, :] <= reach[:, None]
    walled = np.maximum.accumulate(inside & (d <= 0.0), axis=1)  # a wall cell passed by here
    return float((walled & inside & (d >= clear)).any(axis=1).mean())


def _placements(
    points: np.ndarray, turn: float, m: RegistrationMap
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coarse score of every placement of the submap turned by ``turn`` whose robot stands on a
    free cell of ``m``: (scores (rows, cols) in beam ends, the map rows, the map columns)."""
    cell = m.cell
    c, s = math.cos(turn), math.sin(turn)
    q = np.column_stack([c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1]])
    low = np.floor(q.min(axis=0) / cell)
    idx = (np.floor(q / cell) - low).astype(np.intp)
    th, tw = int(idx[:, 1].max()) + 1, int(idx[:, 0].max()) + 1
    templ = np.zeros((th, tw), np.float32)
    np.add.at(templ, (idx[:, 1], idx[:, 0]), 1.0)
    # the map padded by the template on every side: submap points off the map score 0
    corr = cv2.matchTemplate(np.pad(m.score, ((th, th), (tw, tw))), templ, cv2.TM_CCORR)
    # placement (i, j) puts the template's cell (0, 0) on the map's cell (i - th, j - tw); the robot
    # (the submap's point (0, 0)) is the template's cell -low, so on the map's (i - th - low_y, ...)
    ry = np.arange(corr.shape[0]) - th - int(low[1])
    rx = np.arange(corr.shape[1]) - tw - int(low[0])
    ry, rx = ry[(ry >= 0) & (ry < m.free.shape[0])], rx[(rx >= 0) & (rx < m.free.shape[1])]
    sub = corr[np.ix_(ry + th + int(low[1]), rx + tw + int(low[0]))]
    return np.where(m.free[np.ix_(ry, rx)], sub, np.float32(0.0)), ry, rx


def _coarse(
    points: np.ndarray, maps: list[RegistrationMap], grid: SearchGrid
) -> list[tuple[float, str, Pose2D]]:
    """The coarse peaks over every map: (score as a share of points, storey, pose), best first, no
    two within ``peak_m`` and ``peak_deg`` of each other on one storey. Each heading gives its local
    maxima (over ``peak_m``), so a second place alike is never crowded out by the best one's
    neighbours."""
    turns = np.deg2rad(np.arange(0.0, 360.0, grid.turn_step_deg))
    found: list[tuple[float, str, Pose2D]] = []
    for m in maps:
        r = max(1, int(round(grid.peak_m / m.cell)))
        kernel = np.ones((2 * r + 1, 2 * r + 1), np.uint8)
        for a in turns:
            scores, ry, rx = _placements(points, float(a), m)
            local = (scores >= cv2.dilate(scores, kernel)) & (scores > 0)
            flat = np.flatnonzero(local)
            flat = flat[np.argsort(-scores.ravel()[flat])[: grid.peaks]]
            i, j = np.divmod(flat, scores.shape[1])
            for k, row, col in zip(flat, ry[i], rx[j], strict=True):
                x, y = m.origin[0] + (col + 0.5) * m.cell, m.origin[1] + (row + 0.5) * m.cell
                pose = Pose2D(float(x), float(y), float(wrap_angle(float(a))))
                found.append((float(scores.ravel()[k]) / len(points), m.storey, pose))
    found.sort(key=lambda f: -f[0])
    peaks: list[tuple[float, str, Pose2D]] = []
    for f in found:
        if not any(
            p[1] == f[1]
            and p[2].distance_to(f[2]) < grid.peak_m
            and p[2].yaw_error(f[2]) < math.radians(grid.peak_deg)
            for p in peaks
        ):
            peaks.append(f)
            if len(peaks) == grid.peaks:
                break
    return peaks


def _crossed(best: float, rival: float, more: float) -> bool:
    """Does a rival whose beams cross walls ``rival`` of the time (the best pose's ``best``) send
    ``more`` of them through, and three times as many?"""
    return rival >= best + more and rival >= THROUGH_RATIO * best


def _ruled_out(
    ends: BeamEnds,
    candidates: tuple[Candidate, ...],
    maps: list[RegistrationMap],
    grid: SearchGrid,
    more: float,
) -> tuple[bool, tuple[float, ...], bool]:
    """Are the rivals (``candidates[1:]``) ruled out by their beams through walls, on the maps as
    drawn or else on the maps with their doors open (``RegistrationMap.through``)? The best
    candidate's :func:`wall_crossings` (``grid.through_beams`` beams of ``ends``, evenly picked)
    must be at most ``grid.through_best`` and each rival's :func:`_crossed` against it; the shares
    found on the last map tried, stopping at the first that fails; whether that map had its doors
    open. Nothing is ruled out on fewer than ``grid.through_min_sampled`` beams."""
    if len(ends.xy) < grid.through_min_sampled:
        return False, (), False
    origins = ends.beam_origins()
    pick = np.linspace(0, len(ends.xy) - 1, min(grid.through_beams, len(ends.xy))).astype(np.intp)
    found: list[float] = []
    maps_tried = [False, True] if any(m.through is not m.field_ for m in maps) else [False]  # doors open?
    for doors_open in maps_tried:
        fields = {m.storey: m.through if doors_open else m.field_ for m in maps}
        found = []
        for c in candidates:
            share = wall_crossings(
                origins[pick], ends.xy[pick], c.pose, fields[c.storey], grid.through_short, grid.through_clear
            )
            holds = share <= grid.through_best if not found else _crossed(found[0], share, more)
            found.append(share)
            if not holds:
                break
        else:
            return True, tuple(found), doors_open
    return False, tuple(found), maps_tried[-1]


def register(
    ends: BeamEnds,
    maps: list[RegistrationMap],
    params: RegistrationParams,
    tolerance: float,
    grid: SearchGrid = GRID,
) -> Registration:
    """Place the submap ``ends`` over ``maps`` (module docstring): the refined peaks, best first,
    the best's distinct rival second, and whether the best one is unique."""
    points = thin_points(ends.xy, maps[0].cell / 2.0 if maps else 0.1, grid.max_points)
    if len(points) < 20 or not maps:
        return Registration((), False, f"{len(points)} beam ends", len(points))
    sub = BeamEnds(Pose2D(0.0, 0.0, 0.0), points, np.array([float(len(points))]))
    fields = {m.storey: m.fit for m in maps}
    refined: list[Candidate] = []
    for coarse, storey, pose in _coarse(points, maps, grid):
        field_ = fields[storey]
        step = grid.turn_step_deg
        # two grids: the coarse cell and turn step searched over 1/8 m and a third of the step, then
        # 1/32 m and half a degree round the best
        first = best_scan_alignment(
            pose, sub, field_, tolerance, 2 * grid.cell, math.radians(step), 9, step / 3.0
        )
        assert first is not None
        fit, moved = (
            best_scan_alignment(
                first[1], sub, field_, tolerance, grid.cell / 2, math.radians(step / 3), 9, 0.5
            )
            or first
        )
        refined.append(Candidate(storey, moved, fit, coarse))
    refined.sort(key=lambda c: -c.fit)
    best = refined[0]
    distinct: list[Candidate] = []  # the places apart from the best one and from each other
    for c in refined[1:]:
        if best.apart(c, params) and all(d.apart(c, params) for d in distinct):
            distinct.append(c)
    close = tuple(c for c in distinct if best.fit - c.fit < params.margin)
    ordered = (best, *distinct)
    if best.fit < params.min_fit:
        return Registration(ordered, False, f"best fit {best.fit:.2f} < {params.min_fit:.2f}", len(points))
    through: tuple[float, ...] = ()
    doors_open = False
    if close and params.see_through > 0 and ends.origins is not None:
        ruled_out, through, doors_open = _ruled_out(ends, (best, *close), maps, grid, params.see_through)
        if ruled_out:
            why = (
                f"fit {best.fit:.2f}; {len(close)} place(s) alike ruled out by beams through their walls"
                f" ({min(through[1:]):.3f} or more against {through[0]:.3f})"
            )
            return Registration(ordered, True, why, len(points), close, through, doors_open)
    if close:
        rival = close[0]
        far = best.pose.distance_to(rival.pose)
        crossed = f"; beams through walls {', '.join(f'{c:.3f}' for c in through)}" if through else ""
        why = (
            f"{len(close)} place(s) fit within {params.margin:g}{_elsewhere(best, close)}, one {far:.1f} m"
            f" away{_on(best, rival)} {rival.fit:.2f} against {best.fit:.2f}{crossed}"
        )
        return Registration(ordered, False, why, len(points), close, through, doors_open)
    next_fit = distinct[0].fit if distinct else 0.0
    return Registration(ordered, True, f"fit {best.fit:.2f}, the next place {next_fit:.2f}", len(points))


def _elsewhere(best: Candidate, places: Sequence[Candidate]) -> str:
    """How many of ``places`` lie on each storey other than ``best``'s: " (2 on storey Level 2)",
    or nothing when they all lie on its storey."""
    counts: dict[str, int] = {}
    for c in places:
        if c.storey != best.storey:
            counts[c.storey] = counts.get(c.storey, 0) + 1
    if not counts:
        return ""
    return " (" + ", ".join(f"{n} on storey {name}" for name, n in counts.items()) + ")"


def _on(best: Candidate, place: Candidate) -> str:
    """``" on storey X:"`` when ``place`` lies on another storey than ``best`` (its distance is
    then between the two storeys' plans), else nothing."""
    return f" on storey {place.storey}:" if place.storey != best.storey else ""
