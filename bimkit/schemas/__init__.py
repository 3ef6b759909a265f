"""JSON Schemas of every file format bim-init reads or writes, shipped inside the package.

The top-level ``schemas/`` folder of the source tree is a link to this one: the published copy and
the packaged copy are the same files.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["SCHEMA_DIR", "schema_path"]

SCHEMA_DIR = Path(__file__).resolve().parent


def schema_path(name: str) -> Path:
    """The packaged schema file ``name`` (for example ``"site_config.schema.json"``)."""
    return SCHEMA_DIR / name
