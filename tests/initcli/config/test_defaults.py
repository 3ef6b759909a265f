"""One default per setting: the match record, the site-config dataclasses, the schema and the CLI agree."""

from __future__ import annotations

import dataclasses
import inspect
import json
from typing import Any

import pytest

from bimkit.schemas import schema_path
from initcli.cli.bag_options import bag_options
from initcli.cli.match import match
from initcli.config import SessionConfig, config_to_dict, match_options
from initcli.match.pipeline import MatchOptions

RECORD = MatchOptions()
SCHEMA = json.loads(schema_path("site_config.schema.json").read_text(encoding="utf-8"))

# Where each tunable of ``bim-init match`` is set in site.yaml (section, key).
SITE_KEYS = {
    "storey": ("site", "storey"),
    "alpha": ("matching", "alpha"),
    "beta": ("matching", "beta"),
    "max_outliers": ("matching", "max_outliers"),
    "outlier_share": ("matching", "outlier_share"),
    "revisits": ("matching", "revisits"),
    "pose_method": ("matching", "pose_method"),
    "pose_window": ("matching", "pose_window"),
    "d_thre": ("exploration", "d_thre"),
    "merge_radius": ("matching", "merge_radius"),
    "min_sightings": ("matching", "min_sightings"),
    "score_threshold": ("detector", "score_threshold"),
    "min_depth": ("matching", "min_depth"),
    "max_depth": ("matching", "max_depth"),
    "edge_margin": ("matching", "edge_margin"),
    "drift_window": ("matching", "drift_window"),  # the session's retry window (default 50 m, 0: off)
    "landmarks": ("matching", "landmarks"),
    "landmark_alpha": ("matching", "landmark_alpha"),
    "landmark_drift": ("matching", "landmark_drift"),
    "landmark_window": ("matching", "landmark_window"),
    "landmark_weight": ("matching", "landmark_weight"),
    "landmark_outlier_share": ("matching", "landmark_outlier_share"),
    "registration": ("registration", "enabled"),  # --no-registration: registration.enabled false
}
# Options of ``bim-init match`` that are about input/output, not matching.
# How a BAG is read (bag2log's options, initcli/cli/bag_options.py): not match settings.
BAG_READING = set(inspect.signature(bag_options).parameters)
NOT_SETTINGS = {"ctx", "log", "site", "top", "json_out", "plot", "skip_bad"} | BAG_READING
SESSION_OWN = {"storey", "drift_window"}  # same name and unit, a session-specific default


def _schema_defaults(schema: dict, prefix: tuple[str, ...] = ()) -> dict[tuple[str, ...], Any]:
    out: dict[tuple[str, ...], Any] = {}
    for key, sub in schema.get("properties", {}).items():
        if "default" in sub:
            out[(*prefix, key)] = sub["default"]
        out.update(_schema_defaults(sub, (*prefix, key)))
    return out


def _dig(doc: dict, path: tuple[str, ...]) -> Any:
    for key in path:
        doc = doc[key]
    return doc


def test_every_schema_default_is_the_site_config_default() -> None:
    defaults = _schema_defaults(SCHEMA)
    config = config_to_dict(SessionConfig())
    assert len(defaults) > 60
    for path, value in defaults.items():
        assert _dig(config, path) == value, ".".join(path)


def test_every_site_config_key_is_in_the_schema() -> None:
    def leaves(doc: dict, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
        out = []
        for key, value in doc.items():
            is_section = isinstance(value, dict) and key != "classes"
            out.extend(leaves(value, (*prefix, key)) if is_section else [(*prefix, key)])
        return out

    assert set(leaves(config_to_dict(SessionConfig()))) == set(_schema_defaults(SCHEMA))


@pytest.mark.parametrize("name", sorted(set(SITE_KEYS) - SESSION_OWN))
def test_site_config_and_schema_defaults_are_the_match_record(name: str) -> None:
    section, key = SITE_KEYS[name]
    schema_default = SCHEMA["properties"][section]["properties"][key]["default"]
    config_default = getattr(getattr(SessionConfig(), section), key)
    assert schema_default == getattr(RECORD, name)
    assert config_default == getattr(RECORD, name)


def test_cli_option_defaults_are_the_match_record() -> None:
    params = inspect.signature(match).parameters
    for name, param in params.items():
        if name in NOT_SETTINGS:
            continue
        expected = "auto" if name == "storey" and RECORD.storey is None else getattr(RECORD, name)
        assert param.default == expected, name
    assert params["top"].default == RECORD.top and params["skip_bad"].default == RECORD.skip_bad


def test_every_match_option_can_be_set_in_site_yaml() -> None:
    cli = set(inspect.signature(match).parameters) - NOT_SETTINGS
    assert cli == set(SITE_KEYS)
    for section, key in SITE_KEYS.values():
        assert key in SCHEMA["properties"][section]["properties"], f"{section}.{key}"


def test_site_yaml_values_reach_the_session_match_options() -> None:
    config = SessionConfig()
    changed = {"alpha": 0.7, "beta": 20.0, "max_outliers": 2, "revisits": False, "pose_method": "paper"}
    changed |= {"pose_window": 0, "merge_radius": 0.8, "min_sightings": 4, "min_depth": 0.3}
    changed |= {"max_depth": 8.0, "edge_margin": -1.0}
    for name, value in changed.items():
        setattr(config.matching, name, value)
    config.detector.score_threshold = 0.6
    config.exploration.d_thre = 0.4
    options = match_options(config, "L1")
    for name, value in changed.items():
        assert getattr(options, name) == value, name
    assert (options.score_threshold, options.d_thre, options.storey) == (0.6, 0.4, "L1")
    unchanged = match_options(SessionConfig(), None)
    fields = {f.name for f in dataclasses.fields(MatchOptions)} - {"top"}
    assert {n: getattr(unchanged, n) for n in fields} == {n: getattr(RECORD, n) for n in fields}
