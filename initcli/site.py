"""The site model a session config names: a bim-extract output folder loaded as is, or an IFC model
extracted on the fly; the building the simulated robot lives in (``sim.world``); the storey simulated
and the storeys matched."""

from __future__ import annotations

from pathlib import Path

from bimkit.errors import InputError
from bimtools.site.load import Site, StoreyModel, load_site
from initcli.config import SessionConfig
from initcli.config_checks import profile_path

__all__ = ["choose_storey", "input_paths", "prepare_site", "prepare_world", "world_path", "world_storey"]


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
