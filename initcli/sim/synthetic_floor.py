"""Synthetic floors: parallel corridors lined with doors, lifts and stairs at the corridor ends.

Meant for tests, the benchmark and the simulator; no IFC involved. A floor has ``corridors``
corridors along x, ``spacing`` metres apart (centre lines at y = k * spacing), each ``width`` wide
and ``length`` long, joined at both ends by a cross corridor. Doors sit on both corridor walls at
random gaps (so the layout is repetitive but not periodic unless ``gap_jitter`` is 0); lifts and
staircases face the corridor at its ends. Walls are the corridor wall surfaces with their normals
pointing into the corridor (the format of ``walls.geojson``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from initcli.sim.synthetic_log import SimFeature

__all__ = ["SyntheticFloor", "corridor_walk", "doors_along", "make_floor", "write_site_folder"]


@dataclass
class SyntheticFloor:
    features: list[SimFeature]
    walls: np.ndarray  # (W, 6): x1, y1, x2, y2, nx, ny
    corridors: int
    length: float
    spacing: float
    width: float

    @property
    def xy(self) -> np.ndarray:
        return np.array([[f.x, f.y] for f in self.features])

    @property
    def classes(self) -> list[str]:
        return [f.cls for f in self.features]

    def corridor_y(self, k: int) -> float:
        return k * self.spacing

    def csv_text(self, storey: str = "") -> str:
        """features.csv text (Table 1 columns, plus Storey when given)."""
        head = "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height" + (",Storey" if storey else "")
        rows = [head]
        names = {"door": "Door", "lift": "Lift", "stairs": "Stairs"}
        for f in self.features:
            row = (
                f"{f.id},{names.get(f.cls, f.cls)},{f.x:.4f},{f.y:.4f},{f.norm_x:.6f},{f.norm_y:.6f},"
                f"{f.width:.3f},{f.height:.3f}"
            )
            rows.append(row + (f",{storey}" if storey else ""))
        return "\n".join(rows) + "\n"


def make_floor(
    n_features: int = 100,
    seed: int = 0,
    length: float | None = None,
    spacing: float = 12.0,
    width: float = 2.0,
    mean_gap: float = 4.0,
    gap_jitter: float = 0.5,
    id_offset: int = 1000,
) -> SyntheticFloor:
    """A floor with about ``n_features`` features (doors, plus one lift and one staircase per corridor).

    ``gap_jitter`` is the fraction by which door gaps vary (0: perfectly periodic doors).
    """
    rng = np.random.default_rng(seed)
    if length is None:
        # about 2 * length / mean_gap doors per corridor; aim for roughly square floors
        per_corridor_target = max(8.0, math.sqrt(n_features * spacing / mean_gap * 2.0))
        length = max(20.0, per_corridor_target * mean_gap / 2.0)
    per_corridor = 2.0 * length / mean_gap + 2.0
    corridors = max(1, int(round(n_features / per_corridor)))
    feats: list[SimFeature] = []
    walls: list[tuple[float, float, float, float, float, float]] = []
    next_id = id_offset
    half = width / 2.0
    for k in range(corridors):
        yc = k * spacing
        for side, ny in ((-1.0, 1.0), (1.0, -1.0)):  # bottom wall faces +y, top wall faces -y
            y_wall = yc + side * half
            walls.append((0.0, y_wall, length, y_wall, 0.0, ny))
            x = float(rng.uniform(0.5, mean_gap))
            while x < length - 1.0:
                feats.append(SimFeature(str(next_id), "door", x, y_wall, 0.0, ny, 1.0, 2.1))
                next_id += 1
                x += mean_gap * float(rng.uniform(1.0 - gap_jitter, 1.0 + gap_jitter))
        # a lift at the west end, a staircase at the east end (both facing into the corridor)
        feats.append(SimFeature(str(next_id), "lift", 0.0, yc, 1.0, 0.0, 1.1, 2.1))
        feats.append(SimFeature(str(next_id + 1), "stairs", length, yc, -1.0, 0.0, 1.2, 2.1))
        next_id += 2
    return SyntheticFloor(
        feats, np.array(walls, dtype=float).reshape(-1, 6), corridors, length, spacing, width
    )


def corridor_walk(
    floor: SyntheticFloor, corridor: int, x_start: float, x_end: float
) -> list[tuple[float, float]]:
    """Waypoints along the centre line of one corridor."""
    y = floor.corridor_y(corridor)
    return [(x_start, y), (x_end, y)]


def doors_along(floor: SyntheticFloor, corridor: int, x_start: float, x_end: float) -> list[int]:
    """Indices of the features of one corridor between x_start and x_end, in walking order."""
    y = floor.corridor_y(corridor)
    lo, hi = min(x_start, x_end), max(x_start, x_end)
    idx = [
        i
        for i, f in enumerate(floor.features)
        if abs(f.y - y) <= floor.width / 2.0 + 1e-9 and lo <= f.x <= hi
    ]
    return sorted(idx, key=lambda i: floor.features[i].x, reverse=x_end < x_start)


def write_site_folder(
    folder: Path | str,
    storeys: dict[str, tuple[Sequence[SimFeature], np.ndarray | None]],
    elevations: dict[str, float] | None = None,
) -> Path:
    """Write a minimal site folder (features.csv and, if any storey has walls, walls.geojson).

    ``storeys`` maps a storey name to its features and walls (W, 6: x1, y1, x2, y2, nx, ny).
    """
    from bimtools.site.features_csv import write_features
    from bimtools.site.records import Feature, WallSegment
    from bimtools.site.walls_geojson import write_walls

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    names = {"door": "Door", "lift": "Lift", "stairs": "Stairs"}
    records: list[Feature] = []
    walls: list[WallSegment] = []
    for storey, (features, wall_array) in storeys.items():
        elevation = (elevations or {}).get(storey, 0.0)
        for f in features:
            records.append(
                Feature(
                    f.id,
                    names.get(f.cls, f.cls),
                    f.x,
                    f.y,
                    f.norm_x,
                    f.norm_y,
                    f.width,
                    f.height,
                    storey,
                    elevation,
                    "IfcDoor",
                    f.id,
                )
            )
        if wall_array is not None:
            for i, w in enumerate(np.asarray(wall_array, dtype=float).reshape(-1, 6)):
                walls.append(
                    WallSegment(
                        storey,
                        f"{storey}-w{i}",
                        "IfcWall",
                        float(w[0]),
                        float(w[1]),
                        float(w[2]),
                        float(w[3]),
                        (float(w[4]), float(w[5])),
                    )
                )
    write_features(folder / "features.csv", records)
    if walls:
        write_walls(folder / "walls.geojson", walls, [])
    return folder
