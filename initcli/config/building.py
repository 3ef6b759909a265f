"""The site model a session config names: a bim-extract output folder loaded as is, or an IFC model
extracted on the fly; the building the simulated robot lives in (``sim.world``); the storey simulated
and the storeys matched."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bimkit.errors import InputError
from bimtools.site.load import Site, StoreyModel, load_site
from initcli.config import SessionConfig
from initcli.config.checks import profile_path
from initcli.core.lidar.symmetry import TOLERANCE, Turn, self_similar_turn

__all__ = [
    "choose_storey",
    "input_paths",
    "prepare_site",
    "prepare_world",
    "self_similar",
    "twin_reason",
    "world_path",
    "world_storey",
]

SELF_SIMILAR = "self-similar storey"  # the first words of its reason (a stable phrase of summary.json)


def prepare_site(config: SessionConfig, workdir: Path) -> Site:
    """Load the site: a bim-extract OUTDIR as is, an IFC file extracted into ``workdir/site``."""
    return _prepare(config.site_path(), "site.path", config, workdir / "site")


def world_path(config: SessionConfig) -> Path | None:
    """The path ``sim.world`` names (relative to the config file), or None: the BIM itself."""
    if not config.sim.world:
        return None
    base = config.source.parent if config.source else Path.cwd()
    return (base / config.sim.world).resolve()


def input_paths(config: SessionConfig) -> list[Path]:
    """The files and folders a session reads: the config, ``site.path``, ``sim.world`` and the
    detector profile of ``sim.detector.profile``."""
    paths = [config.site_path(), world_path(config), profile_path(config)]
    return [p for p in [config.source, *paths] if p is not None]


def prepare_world(config: SessionConfig, workdir: Path) -> Site | None:
    """The building the simulated robot lives in (``sim.world``), or None: the BIM itself."""
    world = world_path(config)
    return None if world is None else _prepare(world, "sim.world", config, workdir / "world")


def _prepare(path: Path, key: str, config: SessionConfig, target: Path) -> Site:
    where = f"{config.source}: {key}" if config.source else key
    if not path.exists():
        raise InputError(f"{where}: {path} does not exist")
    if path.is_file() and path.suffix.lower() == ".ifc":
        from bimtools.extract.output import write_site
        from bimtools.extract.pipeline import extract_site

        write_site(target, extract_site(path), preview=False)
        path = target
    site = load_site(path)
    if not any(s.grid is not None for s in site.storeys.values()):
        raise InputError(f"{where}: {path} has no occupancy maps (run bim-extract on the IFC model)")
    return site


def choose_storey(config: SessionConfig, site: Site) -> tuple[str, str | None]:
    """(storey simulated, storey matched or None for every storey)."""
    wanted = config.site.storey
    if wanted != "auto":
        site.storey(wanted)  # raises with the valid names
        return wanted, wanted
    with_maps = [s for s in site.storeys.values() if s.grid is not None]
    simulated = max(with_maps, key=lambda s: len(s.camera_features)).name
    return simulated, (None if len(site.storeys) > 1 else simulated)


def world_storey(site: Site, world: Site | None, storey: str) -> StoreyModel:
    """The storey the robot lives in: ``storey`` of ``world`` (same name, else the nearest elevation)."""
    if world is None:
        return site.storeys[storey]
    if storey in world.storeys:
        return world.storeys[storey]
    elevation = site.storeys[storey].elevation
    return min(world.storeys.values(), key=lambda s: abs(s.elevation - elevation))


_TURNS: dict[tuple[object, ...], Turn | None] = {}  # by what the storey holds: an evaluation asks often


def self_similar(storey: StoreyModel) -> Turn | None:
    """The turn that maps the storey's map (walls, columns, closed glazing: every occupied cell)
    and its features (every category, landmarks too) onto themselves, or None
    (:mod:`initcli.core.lidar.symmetry`; tolerance two map cells, 0.1 m or more)."""
    grid = storey.grid
    if grid is None:
        return None
    features = tuple((f.category, f.x, f.y, f.norm_x, f.norm_y) for f in storey.features)
    key = (grid.content_key(), features)
    if key not in _TURNS:
        rows, cols = np.nonzero(grid.occupancy() == 1)
        x, y = grid.cell_centre(rows, cols)
        _TURNS[key] = self_similar_turn(
            np.column_stack([x, y]),
            np.array([f[1:3] for f in features], dtype=float).reshape(-1, 2),
            np.array([f[3:5] for f in features], dtype=float).reshape(-1, 2),
            np.array([f[0] for f in features], dtype=object),
            tolerance=max(TOLERANCE, 2.0 * grid.resolution),
        )
    return _TURNS[key]


def twin_reason(site: Site, storey: str | None) -> str | None:
    """Why no session can initialise on ``storey`` (None: on any storey with a map) from the model
    alone, every storey there being self-similar (:func:`self_similar`), or None."""
    names = [storey] if storey is not None else [n for n, s in site.storeys.items() if s.grid is not None]
    turns = [(name, self_similar(site.storeys[name])) for name in names]
    if not turns or any(turn is None for _, turn in turns):
        return None
    tolerance = max(turn.tolerance for _, turn in turns if turn is not None)
    alike = "; ".join(
        f"{name!r} turned {turn.degrees:.0f} deg about ({turn.centre[0]:.2f}, {turn.centre[1]:.2f})"
        for name, turn in turns
        if turn is not None
    )
    return (
        f"{SELF_SIMILAR}: the model is the same {alike} (walls and features alike within "
        f"{tolerance:.2f} m), so every pose has a twin that no reading tells apart; set the pose by "
        "hand or start on another storey"
    )
