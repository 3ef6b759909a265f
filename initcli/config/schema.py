"""The JSON Schema of ``site.yaml``, generated from the settings records.

``python -m initcli.config --write`` writes it to ``bimkit/schemas/site_config.schema.json``; a test
fails when the committed file differs.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from bimkit.schemas import schema_path
from bimkit.settings import schema_of
from initcli.config.session import SessionConfig

__all__ = ["SCHEMA_PATH", "main", "site_config_schema"]

SCHEMA_PATH = schema_path("site_config.schema.json")
SCHEMA_ID = "https://bim-init.example/schemas/site_config.schema.json"


def site_config_schema() -> dict[str, Any]:
    """The JSON Schema of site.yaml, generated from the records (``python -m initcli.config
    --write`` writes it to :data:`SCHEMA_PATH`; a test fails when the committed file differs)."""
    body = schema_of(SessionConfig)
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": SCHEMA_ID,
        "title": "bim-init run session config (site.yaml)",
        **body,
    }


def main(argv: list[str] | None = None) -> int:
    """``python -m initcli.config``: print the site config's JSON Schema, generated from its
    records; ``--write``: write it to ``bimkit/schemas/site_config.schema.json`` (atomically)."""
    from bimkit.atomic import write_text_atomic

    args = sys.argv[1:] if argv is None else argv
    text = json.dumps(site_config_schema(), indent=2) + "\n"
    if args == ["--write"]:
        write_text_atomic(SCHEMA_PATH, text)
        print(f"wrote {SCHEMA_PATH}")
    elif not args:
        sys.stdout.write(text)
    else:
        print("usage: python -m initcli.config [--write]", file=sys.stderr)
        return 2
    return 0
