"""The session config: the bundled sample configs load, the JSON Schema's defaults are the code's."""

from __future__ import annotations

import json

from tests.helpers import SAMPLES

SAMPLE_SITES = ("block_a", "block_b", "ntu_hallway")


def test_sample_configs_are_valid():
    from initcli.config import load_config

    for name in SAMPLE_SITES:
        config = load_config(SAMPLES / f"{name}.site.yaml")
        assert config.site_path() == (SAMPLES / f"{name}.ifc").resolve()


def test_schema_defaults_match_the_code():
    from initcli.config import SCHEMA_PATH, SessionConfig, config_to_dict

    schema = json.loads(SCHEMA_PATH.read_text())
    defaults = config_to_dict(SessionConfig())

    def walk(node, values, where):
        for key, sub in node["properties"].items():
            if "properties" in sub:
                walk(sub, values[key], f"{where}{key}.")
            else:
                assert sub.get("default") == values[key], f"{where}{key}"

    walk(schema, defaults, "")
