"""Reading ``site.yaml``: validated against its schema before anything runs, merged over the
records' defaults, the named reality profile filled in, then checked across fields.

An error names the YAML path and the problem (``camera.fx: expected a number, got "abc"``).
"""

from __future__ import annotations

import copy
import dataclasses
import os
import sys
from pathlib import Path
from typing import Any

from bimkit import checks
from bimkit.errors import InputError
from bimkit.schemas import describe_value, validate_document
from initcli.config.checks import check_config, given_paths
from initcli.config.schema import SCHEMA_PATH
from initcli.config.session import SessionConfig
from initcli.config.sim import REALITY_PROFILES
from initcli.core.filters.particle_filter import LaserModel

__all__ = [
    "RENAMED_KEYS",
    "check_resources",
    "config_to_dict",
    "load_config",
    "parse_config",
    "read_yaml",
    "renamed_keys",
    "with_reality",
]

# Keys renamed since: the old one is still read, as the new one, with one warning line.
RENAMED_KEYS: dict[str, str] = {
    "sim.workers": "sim.people",  # people walking about, not CPU workers (--workers of eval, survey)
}
# The files warned about, kept in the environment so that the worker processes a command starts
# afterwards (eval's trials load the site configs again) do not repeat the warning.
WARNED_ENV = "BIM_INIT_RENAMED_KEYS_WARNED"


def _merge(instance: Any, doc: dict) -> Any:
    for f in dataclasses.fields(instance):
        if f.name not in doc:
            continue
        value = doc[f.name]
        current = getattr(instance, f.name)
        if dataclasses.is_dataclass(current) and isinstance(value, dict):
            _merge(current, value)
        else:
            if isinstance(current, int) and not isinstance(current, bool) and isinstance(value, float):
                value = int(value)  # 2e3 particles (YAML 1.2 numbers); the schema checked it is whole
            setattr(instance, f.name, value)
    return instance


def read_yaml(path: Path, what: str) -> Any:
    """The YAML document at ``path``; unreadable or binary files, syntax errors and numbers that are
    not finite raise :class:`InputError` (:func:`bimkit.checks.read_yaml`)."""
    return checks.read_yaml(path, what)


def renamed_keys(doc: dict, where: str) -> dict:
    """``doc`` with each old key of :data:`RENAMED_KEYS` moved to its new name, and one warning line
    on stderr (once per file) naming the file and the new key; both given is an :class:`InputError`."""
    renamed: list[str] = []
    for old, new in RENAMED_KEYS.items():
        *parents, old_leaf = old.split(".")
        new_parents, new_leaf = new.rsplit(".", 1)
        if new_parents.split(".") != parents:  # pragma: no cover - every rename so far stays in its section
            raise NotImplementedError(new)
        node: Any = doc
        for part in parents:
            node = node.get(part) if isinstance(node, dict) else None
        if not isinstance(node, dict) or old_leaf not in node:
            continue
        if new_leaf in node:
            raise InputError(f"{where}: {old}: renamed {new}, which this file also sets; keep {new} only")
        if not renamed:
            doc = copy.deepcopy(doc)
            node = doc
            for part in parents:
                node = node[part]
        node[new_leaf] = node.pop(old_leaf)
        renamed.append(f"{old} is now {new}")
    if renamed:
        _warn_once(where, f"{where}: {'; '.join(renamed)} (read as such; rename it in the file)")
    return doc


def _warn_once(where: str, message: str) -> None:
    warned = os.environ.get(WARNED_ENV, "")
    if where in warned.split(os.pathsep):
        return
    os.environ[WARNED_ENV] = os.pathsep.join(filter(None, (warned, where)))
    print(f"bim-init: warning: {message}", file=sys.stderr)


def parse_config(doc: Any, source: Path | None = None) -> SessionConfig:
    where = str(source) if source else "config"
    if doc is None:
        doc = {}
    if isinstance(doc, dict):
        doc = renamed_keys(doc, where)
    validate_document(doc, SCHEMA_PATH, where)
    given = given_paths(doc)
    doc = with_reality(doc, (doc.get("sim") or {}).get("reality", "ideal"))
    config = _merge(SessionConfig(), doc)
    config.source = source
    start = config.sim.start
    if start != "random" and not (isinstance(start, list) and len(start) == 3):
        raise InputError(
            f'{where}: sim.start: expected "random" or [x, y, yaw_degrees], got {describe_value(start)}'
        )
    if not config.site.path:
        raise InputError(f"{where}: site.path: required (an IFC file or a bim-extract output folder)")
    check_resources(config, where)
    check_config(config, given, where)
    return config


MAX_FILTER_BYTES = 2**30  # the fine-tuning filter's working arrays: particles x beams
MAX_IMAGE_PIXELS = 4096 * 4096  # the camera image the detector renders


def check_resources(config: SessionConfig, where: str) -> None:
    """Memory the session will need, checked before it starts (not met as a MemoryError later)."""
    beams = min(config.lidar.beams, LaserModel().beams)  # the likelihood field uses at most these
    need = config.fine_tuning.particles * beams * 8 * 8  # ~8 float64 arrays of particles x beams
    if config.fine_tuning.enabled and need > MAX_FILTER_BYTES:
        raise InputError(
            f"{where}: fine_tuning.particles: {config.fine_tuning.particles} particles x {beams} beams need "
            f"~{need / 2**30:.1f} GiB (at most {MAX_FILTER_BYTES / 2**30:.0f} GiB); use fewer particles"
        )
    pixels = config.camera.width * config.camera.height
    if pixels > MAX_IMAGE_PIXELS:
        raise InputError(
            f"{where}: camera.width x camera.height: {config.camera.width} x {config.camera.height} = "
            f"{pixels} pixels is above the maximum {MAX_IMAGE_PIXELS} (4096 x 4096)"
        )


def with_reality(doc: dict, reality: str) -> dict:
    """``doc`` with ``sim.reality`` set and the profile's values under the keys ``doc`` leaves unset."""
    doc = copy.deepcopy(doc)
    sim = doc.setdefault("sim", {})
    sim["reality"] = reality
    for section, values in REALITY_PROFILES[reality].items():
        given = sim.setdefault(section, {})
        for key, value in values.items():
            given.setdefault(key, value)
    return doc


def load_config(path: Path, reality: str | None = None) -> SessionConfig:
    """The session config at ``path``; ``reality``: a named profile that replaces ``sim.reality``."""
    path = Path(path)
    doc = read_yaml(path, "config")
    if doc is not None and not isinstance(doc, dict):
        raise InputError(f"{path}: expected a mapping of sections (site, robot, camera, ...)")
    if reality is not None:
        doc = with_reality(doc or {}, reality)
    return parse_config(doc, path)


def config_to_dict(config: SessionConfig) -> dict:
    doc = dataclasses.asdict(config)
    doc.pop("source", None)
    return doc
