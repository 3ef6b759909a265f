"""The inputs of a match: the detection log and the site read and checked, the site's class mapping,
the robot's odom pose and path, and the storeys searched.

Every problem is an :class:`~bimkit.errors.InputError` naming the file (``bim-init match`` prints it
as one line).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from bimkit.checks import read_yaml
from bimkit.errors import InputError
from bimtools.site.load import Site, load_site
from bimtools.site.records import LIDAR
from initcli.config.matching import MatchOptions
from initcli.core.features.classes import ClassMap
from initcli.core.geometry.se2 import Pose2D
from initcli.io.detection_log import DetectionLog, read_log

__all__ = [
    "check_classes",
    "check_depths",
    "current_odom",
    "read_inputs",
    "site_class_map",
    "storeys_searched",
]


def read_inputs(
    log_path: Path | str, site_path: Path | str, opts: MatchOptions, source: Path | str | None = None
) -> tuple[DetectionLog, Site]:
    """The log (``opts.skip_bad``; refused when no detection has a depth) and the site (its maps
    left out). ``source``: the file the user named, when ``log_path`` was converted from it (a
    bag), for the messages."""
    log = read_log(log_path, skip_bad=opts.skip_bad)
    check_depths(log, source if source is not None else log.path)
    return log, load_site(Path(site_path), with_maps=False)


def site_class_map(site: Site) -> ClassMap:
    """The site's optional class mapping ``{detector class name: feature category}``.

    Looked up in the site folder: ``site.yaml`` (the ``bim-init run`` site config,
    ``detector.classes``; schemas/site_config.schema.json), then ``"classes"`` in ``site.json``.
    A bare features.csv has no mapping (the built-in synonyms still apply).
    """
    root = Path(site.root)
    if not root.is_dir():
        return ClassMap()
    for path, keys in ((root / "site.yaml", ("detector", "classes")), (root / "site.json", ("classes",))):
        if not path.exists():
            continue
        doc = read_yaml(path, "the class mapping")  # YAML also reads JSON
        mapping = doc
        for key in keys:
            mapping = mapping.get(key) if isinstance(mapping, dict) else None
        if mapping is None:
            continue
        if not isinstance(mapping, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in mapping.items()
        ):
            where = ".".join(keys)
            raise InputError(f"{path}: {where} must map detector class names to feature categories")
        return ClassMap(mapping)
    return ClassMap()


def check_classes(log: DetectionLog, cmap: ClassMap, site: Site) -> None:
    """Every class name in the log must map to a known feature class (else one line, exit 2)."""
    categories = [f.category for s in site.storeys.values() for f in s.features]
    known = cmap.known(categories)
    unknown: set[str] = set()
    for rec in log.detections:
        unknown.update(o.cls for o in rec.objects if cmap.canonical(o.cls) not in known)
    unknown.update(f.cls for f in log.features if f.source != LIDAR and cmap.canonical(f.cls) not in known)
    if unknown:
        names = ", ".join(repr(n) for n in sorted(unknown))
        raise InputError(
            f"{log.path}: unknown class name(s) {names}; known: {', '.join(sorted(known))} "
            "(map other names with detector.classes in the site folder's site.yaml)"
        )


def check_depths(log: DetectionLog, name: Path | str) -> None:
    """Refuse a log whose camera detections all lack a depth: Eq. 1 places a box by its depth, so
    none would become a sighting (and the match would end in 0 features with no reason given)."""
    objects = [o for d in log.detections for o in d.objects]
    if objects and not any(o.depth is not None and math.isfinite(o.depth) for o in objects):
        raise InputError(
            f"{name}: none of the {len(objects)} detections has a depth (every 'depth' is null): "
            "a detection is placed by its depth (Eq. 1); record or convert with an aligned depth image"
        )


def current_odom(log: DetectionLog) -> tuple[Pose2D, np.ndarray, list[str]]:
    """The robot's odom pose at the last odom record, the odom path, and a warning if improvised."""
    odom = log.odom
    if odom:
        path = np.array([[o.x, o.y, o.yaw] for o in odom])
        return odom[-1].pose, path, []
    dets = log.detections
    if dets:
        path = np.array([[d.pose.x, d.pose.y, d.pose.yaw] for d in dets])
        return (
            dets[-1].pose,
            path,
            [f"{log.path}: no odom records; using the pose of the last detections record"],
        )
    return (
        Pose2D.identity(),
        np.zeros((1, 3)),
        [f"{log.path}: no odom records; assuming the robot is at the odom origin"],
    )


def storeys_searched(site: Site, opts: MatchOptions) -> list[str]:
    """Every storey (``storey`` None or auto) or the one named (InputError listing the valid ones)."""
    if opts.storey is None or opts.storey == "auto":
        return list(site.storeys)
    site.storey(opts.storey)  # raises InputError listing the valid storeys
    return [opts.storey]
