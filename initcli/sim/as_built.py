"""The site as built, not as designed: a seeded world derived from the design model (issue 11).

The BIM is what the robot matches against; the world it drives in, scans and photographs is this one.
Every deviation is drawn from the seed, so a trial is reproducible, and every key defaults to 0 (the
ideal world, today's simulator):

=====================  =====================================================================  ========
key                    what it does                                                           unit
=====================  =====================================================================  ========
missing_doors          share of doors not installed: no leaf (a free doorway), nothing to     share
                       detect
door_shift             doors built off their design place along the host wall (leaf and       m, sigma
                       feature move together; a closed one's design opening is walled up)
wall_offset            every other element (walls, columns, glazing) built off its place      m, sigma
open_doors             share of the installed doors standing open: no obstacle, still a door  share
hoarding               temporary walls not in the BIM, across a corridor or in front of a     per 100 m
                       room front (hiding its doors)                                          corridor
extra_doors            doors on site the model lacks (the detector sees them; no BIM match)   per 100 m
clutter_in_corridor    share of the material stacks (``sim.clutter``) standing out in the     share
                       corridor instead of against a wall
persistent_phantoms    posters or panels detected as a door every time they are in view       per 100 m
never_seen             share of the real features the detector never fires on                 share
=====================  =====================================================================  ========

The building envelope stays closed, as sites keep it: a missing door in an exterior wall (nothing
behind it in the plan) is boarded up (nothing to detect, no way out), and exterior doors are never
left open. Every installed door that is not open is closed in the simulated world: a leaf across its opening
(the feature's width, along its wall), whatever pieces of the door the 1 m plan cut happened to hold
(often only frame parts). Corridor length is estimated as the circulation area over a 2 m corridor
width.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from bimtools.site.records import UNKNOWN, Obstacle
from initcli.config.sim import AsBuiltParams
from initcli.core.geometry.raycast import ray_segment_distances
from initcli.sim.synthetic_log import SimFeature
from initcli.storey.circulation import Circulation
from initcli.storey.doors import closed_doors, door_leaf
from initcli.storey.outlines import box_ring, polygon_edges

__all__ = [
    "AsBuiltWorld",
    "CORRIDOR_WIDTH",
    "DOOR_CLASSES",
    "HOARDING_CLASS",
    "HOARDING_THICKNESS",
    "MIN_PASSAGE",
    "STAND_OUT",
    "corridor_length",
    "derive_as_built",
    "is_exterior",
    "stand_out",
]

CORRIDOR_WIDTH = 2.0  # m: circulation area / this = corridor length for the per-100 m rates
HOARDING_THICKNESS = 0.1  # m
HOARDING_CLASS = "Hoarding"
DOOR_CLASSES = ("door",)  # canonical feature classes that can be missing, shifted or open


@dataclass
class AsBuiltWorld:
    """The obstacles the lidar and the robot meet, and the things the detector can fire on."""

    obstacles: list[Obstacle]
    features: list[SimFeature]  # installed and detectable BIM features (as built), extra doors, phantoms
    hoardings: list[np.ndarray] = field(default_factory=list)  # closed (5, 2) rings, for plots and tests
    changes: dict[str, int] = field(default_factory=dict)  # what was changed, counted


def corridor_length(circulation: Circulation) -> float:
    """Metres of corridor: the circulation area over a 2 m width."""
    area = float(circulation.label.sum()) * circulation.grid.resolution**2
    return area / CORRIDOR_WIDTH


def _count(rate_per_100m: float, length: float, rng: np.random.Generator) -> int:
    return int(rng.poisson(rate_per_100m * length / 100.0)) if rate_per_100m > 0 else 0


def _shift(obstacle: Obstacle, dx: float, dy: float) -> Obstacle:
    ring = tuple((x + dx, y + dy) for x, y in obstacle.exterior)
    holes = tuple(tuple((x + dx, y + dy) for x, y in h) for h in obstacle.holes)
    return replace(obstacle, exterior=ring, holes=holes)


def is_exterior(f: SimFeature, circulation: Circulation) -> bool:
    """A door in the building envelope: behind it (0.5-1.5 m against its normal) the storey map has
    no building (unknown cells, outside the plan)."""
    grid = circulation.grid
    return any(grid.value_at(f.x - d * f.norm_x, f.y - d * f.norm_y) == UNKNOWN for d in (0.5, 0.8, 1.1, 1.5))


def _corridor_walls(model_walls: list, circulation: Circulation, min_length: float) -> list:
    return [
        w
        for w in model_walls
        if w.length >= min_length
        and circulation.contains((w.x1 + w.x2) / 2 + 0.4 * w.normal[0], (w.y1 + w.y2) / 2 + 0.4 * w.normal[1])
    ]


def _wall_features(
    walls: list, count: int, prefix: str, rng: np.random.Generator, keep_off: np.ndarray
) -> list[SimFeature]:
    """Door-like things on corridor walls at random places at least 1.5 m from ``keep_off`` points."""
    out: list[SimFeature] = []
    for _ in range(count * 10):
        if len(out) >= count or not walls:
            break
        w = walls[int(rng.integers(len(walls)))]
        s = rng.uniform(0.15, 0.85)
        x, y = w.x1 + s * (w.x2 - w.x1), w.y1 + s * (w.y2 - w.y1)
        if len(keep_off) and float(np.hypot(keep_off[:, 0] - x, keep_off[:, 1] - y).min()) < 1.5:
            continue
        out.append(SimFeature(f"{prefix}-{len(out)}", "door", x, y, w.normal[0], w.normal[1], 1.0, 2.1))
        keep_off = np.vstack([keep_off.reshape(-1, 2), [[x, y]]])
    return out


def _hoarding(
    circulation: Circulation, segments: np.ndarray, walls: list, rng: np.random.Generator
) -> np.ndarray | None:
    """A temporary wall: across the corridor at a random corridor point (half the time), or 0.4 m in
    front of a corridor wall, 3-6 m long (the front of a room closed off)."""
    cells = circulation.cells(0.6)
    if len(cells) == 0:
        return None
    if rng.random() < 0.5 or not walls:
        x, y = cells[int(rng.integers(len(cells)))]
        angles = np.linspace(0.0, math.pi, 12, endpoint=False)
        origin = np.array([x, y])
        fwd = ray_segment_distances(origin, angles, segments, 10.0)
        back = ray_segment_distances(origin, angles + math.pi, segments, 10.0)
        k = int(np.argmin(fwd + back))  # the narrowest direction is across the corridor
        if fwd[k] + back[k] > 8.0:
            return None  # an open hall: no corridor to close here
        direction = np.array([math.cos(angles[k]), math.sin(angles[k])])
        centre = origin + direction * (fwd[k] - back[k]) / 2
        half = (fwd[k] + back[k]) / 2 - 0.01
        return box_ring(centre, direction, half, HOARDING_THICKNESS / 2)
    w = walls[int(rng.integers(len(walls)))]
    length = min(float(rng.uniform(3.0, 6.0)), w.length)
    s = rng.uniform(length / 2, w.length - length / 2) / w.length
    along = np.array([w.x2 - w.x1, w.y2 - w.y1]) / w.length
    centre = np.array([w.x1 + s * (w.x2 - w.x1), w.y1 + s * (w.y2 - w.y1)]) + 0.4 * np.array(w.normal)
    return box_ring(centre, along, length / 2, HOARDING_THICKNESS / 2)


@dataclass
class _DoorsBuilt:
    """The design obstacles as the doors were built: ``obstacles[k]`` None where a door's piece
    went (missing or open), ``moved`` the pieces shifted with their door, ``closed`` the leaves and
    boards across openings, ``features`` what stays detectable."""

    obstacles: list[Obstacle | None]
    moved: set[int] = field(default_factory=set)
    closed: list[Obstacle] = field(default_factory=list)
    features: list[SimFeature] = field(default_factory=list)
    changes: dict[str, int] = field(
        default_factory=lambda: {"missing_doors": 0, "shifted_doors": 0, "open_doors": 0, "never_seen": 0}
    )

    def remove(self, pieces: list[int]) -> None:
        for k in pieces:
            self.obstacles[k] = None

    def shift(self, pieces: list[int], dx: float, dy: float) -> None:
        for k in pieces:
            piece = self.obstacles[k]
            if piece is not None:
                self.obstacles[k] = _shift(piece, dx, dy)
                self.moved.add(k)


def _build_door(
    built: _DoorsBuilt,
    f: SimFeature,
    pieces: list[int],
    leaf: bool,
    exterior: bool,
    p: AsBuiltParams,
    rng: np.random.Generator,
) -> SimFeature | None:
    """One door as built (``missing_doors``, ``door_shift``, ``open_doors``): the feature where it
    stands, or None when it was never installed. ``leaf``: the feature is a door leaf (IfcDoor)."""
    design = f
    if leaf and p.missing_doors > 0 and rng.random() < p.missing_doors:
        built.remove(pieces)
        built.changes["missing_doors"] += 1
        if exterior:  # the envelope stays closed: a board across the opening
            built.closed.append(door_leaf(f))
        return None
    if p.door_shift > 0:
        s = float(rng.normal(0.0, p.door_shift))
        dx, dy = -f.norm_y * s, f.norm_x * s  # along the host wall
        f = replace(f, x=f.x + dx, y=f.y + dy)
        built.shift(pieces, dx, dy)
        built.changes["shifted_doors"] += 1
    if p.open_doors > 0 and rng.random() < p.open_doors and not exterior:
        built.remove(pieces)
        built.changes["open_doors"] += 1
    elif leaf:
        built.closed.append(door_leaf(f))
        if f is not design:
            # The wall's opening stays where the design has it: a leaf built off its place would
            # leave a gap there beside it (out of a room, out of the building), so the design
            # opening is closed too (by the shifted door's wall).
            built.closed.append(door_leaf(design))
    return f


def _build_doors(
    obstacles: list[Obstacle],
    features: list[SimFeature],
    circulation: Circulation,
    p: AsBuiltParams,
    rng: np.random.Generator,
    doors: frozenset[str],
) -> _DoorsBuilt:
    """Every feature as built: doors missing, shifted or open, and features never seen."""
    by_element: dict[str, list[int]] = {}
    for k, design_piece in enumerate(obstacles):
        by_element.setdefault(design_piece.element, []).append(k)
    built = _DoorsBuilt(list(obstacles))
    for f in features:
        if f.cls in DOOR_CLASSES:
            leaf = f.id in doors
            exterior = leaf and is_exterior(f, circulation)
            placed = _build_door(built, f, by_element.get(f.id, []), leaf, exterior, p, rng)
            if placed is None:
                continue
            f = placed
        if p.never_seen > 0 and rng.random() < p.never_seen:
            built.changes["never_seen"] += 1
            continue
        built.features.append(f)
    return built


def _offset_walls(built: _DoorsBuilt, sigma: float, rng: np.random.Generator) -> None:
    """``wall_offset``: every piece not moved with its door, built off its place."""
    if sigma <= 0:
        return
    for k, element in enumerate(built.obstacles):
        if element is None or k in built.moved:
            continue
        dx, dy = rng.normal(0.0, sigma, 2)
        built.obstacles[k] = _shift(element, float(dx), float(dy))


def derive_as_built(
    obstacles: list[Obstacle],
    walls: list,
    features: list[SimFeature],
    circulation: Circulation,
    params: AsBuiltParams,
    rng: np.random.Generator,
    doors: frozenset[str] = frozenset(),
) -> AsBuiltWorld:
    """The as-built world of one storey from its design ``obstacles``, wall surfaces and ``features``
    (canonical classes). ``doors``: ids of the features that are door leaves (IfcDoor), closed with
    :func:`door_leaf` unless missing or open. With every parameter 0 the world is the design with
    its doors closed, and ``rng`` is not drawn from."""
    p = params
    if p == AsBuiltParams():
        return AsBuiltWorld(list(obstacles) + closed_doors(features, doors), list(features))
    built = _build_doors(obstacles, features, circulation, p, rng, doors)
    _offset_walls(built, p.wall_offset, rng)
    kept = [o for o in built.obstacles if o is not None] + built.closed
    length = corridor_length(circulation)
    corridor_walls = _corridor_walls(walls, circulation, 2.0)
    segments = (
        np.concatenate([polygon_edges(np.asarray(o.exterior)) for o in kept]) if kept else np.zeros((0, 4))
    )
    hoardings: list[np.ndarray] = []
    for _ in range(_count(p.hoarding, length, rng)):
        ring = _hoarding(circulation, segments, corridor_walls, rng)
        if ring is not None:
            hoardings.append(ring)
    for k, ring in enumerate(hoardings):
        kept.append(Obstacle("", f"hoarding-{k}", HOARDING_CLASS, tuple(map(tuple, ring[:-1].tolist()))))
    occupied = np.array([[f.x, f.y] for f in features]).reshape(-1, 2)
    extra = _wall_features(corridor_walls, _count(p.extra_doors, length, rng), "extra", rng, occupied)
    occupied = np.vstack([occupied, [[f.x, f.y] for f in extra]]) if extra else occupied
    phantoms = _wall_features(
        corridor_walls, _count(p.persistent_phantoms, length, rng), "phantom-persistent", rng, occupied
    )
    changes = dict(
        built.changes, hoardings=len(hoardings), extra_doors=len(extra), persistent_phantoms=len(phantoms)
    )
    return AsBuiltWorld(kept, built.features + extra + phantoms, hoardings, changes)


STAND_OUT = 0.6  # m a stack standing out in the corridor is moved off its wall
MIN_PASSAGE = 1.0  # m of corridor a stack standing out leaves free (sites keep escape routes open)


def stand_out(
    boxes: list[np.ndarray], share: float, rng: np.random.Generator, segments: np.ndarray | None = None
) -> list[np.ndarray]:
    """``clutter_in_corridor``: move a ``share`` of the stacks placed against corridor walls 0.6 m out
    into the corridor (along the stack's own depth axis, away from its wall), where that leaves at
    least ``MIN_PASSAGE`` to the obstacles ``segments`` (S, 4) across the corridor."""
    if share <= 0:
        return boxes
    out = []
    for b in boxes:
        if rng.random() < share:
            c = b[:4]
            wall_side = (c[0] + c[1]) / 2
            free_side = (c[2] + c[3]) / 2
            n = free_side - wall_side
            n = n / max(float(np.hypot(*n)), 1e-9)
            moved = b + STAND_OUT * n
            if segments is None or _passage(moved, n, segments) >= MIN_PASSAGE:
                b = moved
        out.append(b)
    return out


def _passage(box: np.ndarray, n: np.ndarray, segments: np.ndarray) -> float:
    """The narrowest free distance from the free face of ``box`` along ``n`` (its ends and middle)."""
    c = box[:4]
    angle = np.array([math.atan2(n[1], n[0])])
    gaps = [
        float(ray_segment_distances(p + 0.01 * n, angle, segments, 10.0)[0])
        for p in (c[2], c[3], (c[2] + c[3]) / 2)
    ]
    return min(gaps)
