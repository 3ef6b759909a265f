"""Load a site model: a ``bim-extract`` OUTDIR, or a bare features.csv (a hand-written Table 1)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from bimkit.errors import InputError
from bimtools.site.features_csv import read_features
from bimtools.site.manifest import SiteManifest, read_manifest
from bimtools.site.occupancy_map import OccupancyGrid, read_map
from bimtools.site.records import Feature, Obstacle, WallSegment, camera_features, lidar_landmarks
from bimtools.site.walls_geojson import read_walls

__all__ = ["Site", "StoreyModel", "load_site"]


@dataclass
class StoreyModel:
    """Everything known of one storey: the BIM features B_object, walls, obstacles, map."""

    name: str
    elevation: float
    features: list[Feature]
    walls: list[WallSegment] = field(default_factory=list)
    obstacles: list[Obstacle] = field(default_factory=list)
    grid: OccupancyGrid | None = None

    @property
    def camera_features(self) -> list[Feature]:
        """B_object as the camera sees it: doors, lifts, stairs (see ``records.sensor_of``)."""
        return camera_features(self.features)

    @property
    def lidar_landmarks(self) -> list[Feature]:
        """The wall corners, column corners and openings a lidar sees (empty unless extracted)."""
        return lidar_landmarks(self.features)


@dataclass
class Site:
    root: Path
    storeys: dict[str, StoreyModel]
    manifest: SiteManifest | None = None

    def storey(self, name: str) -> StoreyModel:
        if name not in self.storeys:
            valid = ", ".join(repr(s) for s in self.storeys) or "none"
            raise InputError(f"{self.root}: no storey {name!r}; valid storeys: {valid}")
        return self.storeys[name]


def _storeys(features: list[Feature], manifest: SiteManifest | None) -> dict[str, StoreyModel]:
    """The manifest's storeys (a map's may hold no feature), then those the features name."""
    storeys: dict[str, StoreyModel] = {}
    for info in manifest.storeys if manifest is not None else []:
        storeys.setdefault(info.name, StoreyModel(info.name, info.elevation, []))
    for f in features:
        model = storeys.setdefault(f.storey, StoreyModel(f.storey, f.elevation, []))
        model.features.append(f)
    return storeys


DOOR_OFF_WALL_M = 1.0  # m: a door feature farther than this from every wall of its storey is off them
DOORS_OFF_REFUSED = 0.5  # share of a storey's doors off its walls that makes the feature table another's
DOORS_CHECKED = 3  # doors a storey needs before the check says anything


def check_doors_on_walls(storey: StoreyModel, csv_path: Path) -> None:
    """Refuse a storey whose doors mostly lie away from its walls (another building's features.csv
    beside this one's walls.geojson): a door stands in a wall. A door or two off the walls is
    possible (a passage drawn without one) and passes."""
    doors = [f for f in storey.features if f.category.lower() == "door"]
    if len(doors) < DOORS_CHECKED or not storey.walls:
        return
    seg = np.array([[w.x1, w.y1, w.x2, w.y2] for w in storey.walls], dtype=float)
    p = np.array([[f.x, f.y] for f in doors], dtype=float)
    a, b = seg[:, :2], seg[:, 2:]
    ab = b - a
    t = np.clip(
        ((p[:, None, :] - a[None]) * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12), 0.0, 1.0
    )
    nearest = np.hypot(*(p[:, None, :] - (a[None] + t[..., None] * ab[None])).transpose(2, 0, 1)).min(axis=1)
    off = int((nearest > DOOR_OFF_WALL_M).sum())
    if off >= DOORS_OFF_REFUSED * len(doors):
        worst = doors[int(np.argmax(nearest))]
        raise InputError(
            f"{csv_path}: {off} of the {len(doors)} doors of storey {storey.name!r} lie more than"
            f" {DOOR_OFF_WALL_M:g} m from every wall of walls.geojson (door {worst.id!r}"
            f" {nearest.max():.1f} m): the feature table and the walls are not of one building"
        )


def _read_maps(path: Path, manifest: SiteManifest, storeys: dict[str, StoreyModel]) -> None:
    """Each storey's occupancy map that site.json names; one it names and the folder lacks (a site
    copied without its maps) is refused, not guessed."""
    for info in manifest.storeys:
        if info.name not in storeys or not info.map_yaml:
            continue
        if not (path / info.map_yaml).exists():
            raise InputError(
                f"{path / 'site.json'}: storey {info.name!r} names the map {info.map_yaml}, which is not"
                f" in {path} (copy the whole folder bim-extract wrote, or extract the model again)"
            )
        storeys[info.name].grid = read_map(path / info.map_yaml)


def load_site(path: Path, with_maps: bool = True) -> Site:
    """Read an OUTDIR (features.csv, walls.geojson, maps, site.json) or a features.csv alone."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file or folder")
    if path.is_dir():
        csv_path = path / "features.csv"
        if not csv_path.exists():
            raise InputError(f"{path}: not a site folder (no features.csv)")
    else:
        csv_path = path
    features = read_features(csv_path)
    manifest = read_manifest(path / "site.json") if path.is_dir() and (path / "site.json").exists() else None
    # A site of a map (bim-extract MAP.yaml) may hold no features: its storeys are the manifest's.
    if not features and (manifest is None or not any(info.map_yaml for info in manifest.storeys)):
        raise InputError(f"{csv_path}: no features")

    storeys = _storeys(features, manifest)
    if path.is_dir() and (path / "walls.geojson").exists():
        walls, obstacles = read_walls(path / "walls.geojson")
        for w in walls:
            if w.storey in storeys:
                storeys[w.storey].walls.append(w)
        for o in obstacles:
            if o.storey in storeys:
                storeys[o.storey].obstacles.append(o)
        for storey in storeys.values():
            check_doors_on_walls(storey, csv_path)
    if with_maps and manifest is not None:
        _read_maps(path, manifest, storeys)
    return Site(root=path, storeys=storeys, manifest=manifest)
