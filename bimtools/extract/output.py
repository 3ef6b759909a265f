"""Write an extracted site into an OUTDIR, all or nothing."""

from __future__ import annotations

from pathlib import Path

from bimkit.atomic import staged_directory
from bimtools import __version__
from bimtools.extract.pipeline import ExtractedSite
from bimtools.extract.preview import render_preview
from bimtools.site.features_csv import write_features
from bimtools.site.manifest import SiteManifest, format_manifest
from bimtools.site.occupancy_map import write_map
from bimtools.site.records import StoreyInfo
from bimtools.site.walls_geojson import write_walls

SITE_MARKERS = ("site.json",)  # a folder holding one was written by bim-extract
SITE_WRITES = ("site.json", "features.csv", "walls.geojson", "map_*", "preview_*")  # what it writes there

__all__ = ["build_manifest", "write_site"]


def build_manifest(site: ExtractedSite, files: list[str]) -> SiteManifest:
    storeys = []
    for result in site.storeys:
        counts: dict[str, int] = {}
        for f in result.features:
            counts[f.category] = counts.get(f.category, 0) + 1
        slug = result.storey.slug
        storeys.append(
            StoreyInfo(
                result.storey.name,
                round(result.storey.elevation, 4),
                counts,
                f"map_{slug}.yaml",
                f"preview_{slug}.png",
            )
        )
    return SiteManifest(
        source_file=site.info.path.name,
        source_sha256=site.info.sha256,
        schema=site.info.schema,
        application=site.info.application,
        length_unit=site.info.length_unit,
        unit_scale=site.info.unit_scale,
        section_height=site.section_height,
        resolution=site.resolution,
        storeys=storeys,
        files=files,
        tool_version=__version__,
        landmarks=site.landmarks,
    )


def write_site(outdir: Path, site: ExtractedSite, preview: bool = True) -> SiteManifest:
    """Write features.csv, walls.geojson, maps, previews and site.json into ``outdir`` (staged: the
    files an earlier extraction wrote there are replaced, every other file is kept)."""
    with staged_directory(Path(outdir), SITE_MARKERS) as stage:
        files = ["features.csv", "walls.geojson"]
        write_features(stage / "features.csv", site.features)
        walls = [w for s in site.storeys for w in s.plan.walls]
        obstacles = [o for s in site.storeys for o in s.plan.obstacle_records()]
        write_walls(stage / "walls.geojson", walls, obstacles)
        for result in site.storeys:
            slug = result.storey.slug
            write_map(stage / f"map_{slug}.yaml", result.grid)
            files += [f"map_{slug}.pgm", f"map_{slug}.yaml"]
            if preview:
                render_preview(
                    stage / f"preview_{slug}.png",
                    f"{site.info.path.name} - {result.storey.name} (cut at {result.plan.cut_height:.2f} m)",
                    [o.area for o in result.plan.obstacles],
                    result.plan.walls,
                    result.features,
                    result.plan.outline,
                )
                files.append(f"preview_{slug}.png")
        files.append("site.json")
        manifest = build_manifest(site, files)
        (stage / "site.json").write_text(format_manifest(manifest), encoding="utf-8")
    return manifest
