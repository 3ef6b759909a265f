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


def test_nav2_settings_are_read_checked_and_in_the_generated_schema(tmp_path) -> None:
    import json

    import pytest
    import yaml

    from bimkit.errors import InputError
    from bimkit.schemas import schema_path
    from initcli.config import load_config

    schema = json.loads(schema_path("site_config.schema.json").read_text())
    confirm = schema["properties"]["nav2"]["properties"]["confirm"]["properties"]
    assert set(confirm) == {"timeout", "tolerance_m", "tolerance_deg", "amcl_topic", "republish_period"}
    assert confirm["timeout"]["default"] == 10.0
    assert "advertise_delay" in schema["properties"]["nav2"]["properties"]
    path = tmp_path / "site.yaml"
    doc = {
        "site": {"path": "x.ifc"},
        "nav2": {"advertise_delay": 0.2, "confirm": {"timeout": 4, "amcl_topic": "/a"}},
    }
    path.write_text(yaml.safe_dump(doc))
    cfg = load_config(path)
    assert (
        cfg.nav2.advertise_delay == 0.2
        and cfg.nav2.confirm.timeout == 4
        and cfg.nav2.confirm.amcl_topic == "/a"
    )
    assert cfg.nav2.confirm.tolerance_m == 0.3  # the default
    doc["nav2"]["confirm"]["tolerance_m"] = -1
    path.write_text(yaml.safe_dump(doc))
    with pytest.raises(InputError, match="nav2.confirm.tolerance_m"):
        load_config(path)
