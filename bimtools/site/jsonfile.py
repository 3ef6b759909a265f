"""Reading a JSON file with errors worded for the user (file, line, problem)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from bimtools.errors import InputError


def read_json(path: Path) -> Any:
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(f"{path}: cannot read: {exc.strerror or exc}") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}:{exc.lineno}: not valid JSON: {exc.msg}") from None
