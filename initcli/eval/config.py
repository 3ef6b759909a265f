"""The evaluation config (``eval.yaml``): sites, starts, methods, the failure rule, baseline settings.

See ``schemas/eval_config.schema.json`` and ``sample_models/eval.yaml``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bimkit.errors import InputError
from bimkit.schemas import schema_path, validate_document
from initcli.config import read_yaml
from initcli.core.filters.global_localisation import GlobalLocalisationParams
from initcli.eval.records import DEFAULT_METHODS, METHODS, FailureRule
from initcli.sim.markers import MarkerParams

__all__ = [
    "DEFAULT_CONFIG",
    "EvalConfig",
    "EvalSite",
    "SAMPLES",
    "SCHEMA_PATH",
    "load_eval_config",
    "parse_eval_config",
    "parse_methods",
    "site_name",
]

SCHEMA_PATH = schema_path("eval_config.schema.json")
SAMPLES = Path(__file__).resolve().parents[2] / "sample_models"  # in a source checkout only
DEFAULT_CONFIG = SAMPLES / "eval.yaml"


@dataclass
class EvalSite:
    name: str
    config: Path  # the bim-init run site config
    starts: int
    start_poses: list[tuple[float, float, float]] | None = None  # x, y, yaw (radians)
    paper: str | None = None  # NTU | BlockA | BlockB


@dataclass
class EvalConfig:
    sites: list[EvalSite]
    seed: int = 1
    methods: tuple[str, ...] = DEFAULT_METHODS
    rule: FailureRule = field(default_factory=FailureRule)
    amcl: dict[str, Any] = field(default_factory=dict)
    markers: dict[str, Any] = field(default_factory=dict)
    source: Path | None = None


def site_name(config_path: Path) -> str:
    name = config_path.name
    for suffix in (".yaml", ".yml"):
        name = name.removesuffix(suffix)
    return name.removesuffix(".site")


def parse_eval_config(doc: Any, source: Path) -> EvalConfig:
    where = str(source)
    if not isinstance(doc, dict):
        raise InputError(f"{where}: expected a mapping with a sites list")
    validate_document(doc, SCHEMA_PATH, where)
    starts = int(doc.get("starts", 100))
    sites = []
    seen: set[str] = set()
    for i, entry in enumerate(doc["sites"]):
        path = (source.parent / entry["config"]).resolve()
        try:
            found = path.is_file()
        except OSError as exc:  # a name too long for the file system, a loop of links
            raise InputError(f"{where}: sites.{i}.config: {exc.strerror or exc}") from None
        if not found:
            raise InputError(f"{where}: sites.{i}.config: {path} does not exist")
        name = entry.get("name") or site_name(path)
        if name in seen:
            raise InputError(f"{where}: sites.{i}.name: {name!r} is used twice (give each site a name)")
        seen.add(name)
        poses = entry.get("start_poses")
        explicit = [(float(x), float(y), math.radians(float(yaw))) for x, y, yaw in poses] if poses else None
        sites.append(
            EvalSite(
                name=name,
                config=path,
                starts=len(explicit) if explicit else int(entry.get("starts", starts)),
                start_poses=explicit,
                paper=entry.get("paper"),
            )
        )
    failure = doc.get("failure", {})
    paper_rule = FailureRule()
    rule = FailureRule(
        max_distance_m=float(failure.get("max_distance", paper_rule.max_distance_m)),
        max_error_m=float(failure.get("max_error", paper_rule.max_error_m)),
        wrong_error_m=float(failure.get("wrong_error", paper_rule.wrong_error_m)),
        wrong_error_deg=float(failure.get("wrong_error_deg", paper_rule.wrong_error_deg)),
    )
    methods = tuple(dict.fromkeys(doc.get("methods", DEFAULT_METHODS)))
    for section, params in (("amcl", GlobalLocalisationParams), ("markers", MarkerParams)):
        defaults = params()
        settable = {
            f.name: getattr(defaults, f.name)
            for f in dataclasses.fields(defaults)
            if not dataclasses.is_dataclass(getattr(defaults, f.name))
        }
        for key, value in doc.get(section, {}).items():
            if key not in settable:
                raise InputError(
                    f"{where}: {section}.{key}: unknown parameter (one of {', '.join(settable)})"
                )
            default = settable[key]
            if isinstance(default, bool) != isinstance(value, bool):
                want = "true or false" if isinstance(default, bool) else "a number"
                raise InputError(f"{where}: {section}.{key}: expected {want}")
    return EvalConfig(
        sites=sites,
        seed=int(doc.get("seed", 1)),
        methods=methods,
        rule=rule,
        amcl=dict(doc.get("amcl", {})),
        markers=dict(doc.get("markers", {})),
        source=source,
    )


def load_eval_config(path: Path | None) -> EvalConfig:
    """The eval config at ``path``, or the source tree's sample one (the three sample models).

    The sample models are not part of the installed package: without a source tree ``--config``
    is required.
    """
    if path is None:
        if not DEFAULT_CONFIG.is_file():
            raise InputError(
                f"no eval config given and no sample config at {DEFAULT_CONFIG} (the sample models ship "
                "with the source tree, not the package): pass --config EVAL.yaml"
            )
        path = DEFAULT_CONFIG
    path = Path(path)
    return parse_eval_config(read_yaml(path, "eval config"), path)


def parse_methods(text: str) -> tuple[str, ...]:
    """``--methods bim,bim+pf`` (comma or space separated)."""
    names = [m for m in text.replace(",", " ").split() if m]
    unknown = [m for m in names if m not in METHODS]
    if unknown or not names:
        raise InputError(f"--methods: expected some of {', '.join(METHODS)}, got {text!r}")
    return tuple(dict.fromkeys(names))
