"""Reading a JSON file with errors worded for the user (file, line, problem)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from bimtools.checks import check_finite_tree, read_text
from bimtools.errors import InputError


def read_json(path: Path) -> Any:
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: cannot read: No such file")
    text = read_text(path, "a JSON file")
    try:
        doc = json.loads(text)
    except RecursionError:
        raise InputError(f"{path}: JSON nested too deeply") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}:{exc.lineno}: not valid JSON: {exc.msg}") from None
    check_finite_tree(doc, str(path))
    return doc
