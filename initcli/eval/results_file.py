"""``results.jsonl`` (one trial per line, appended as trials finish) and ``table.csv`` / ``table.md``."""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from pathlib import Path
from typing import IO

from bimkit.atomic import write_text_atomic
from bimkit.checks import parse_json, read_text
from bimkit.errors import InputError
from initcli.eval.records import TrialRecord

__all__ = [
    "REQUIRED",
    "ResultsWriter",
    "parse_record",
    "read_results",
    "record_line",
    "truncate_partial_line",
    "write_csv",
]

REQUIRED = ("site", "start", "method", "success", "reason")
_FIELDS = {f.name for f in dataclasses.fields(TrialRecord)}


def record_line(record: TrialRecord) -> str:
    return json.dumps(dataclasses.asdict(record), separators=(",", ":"))


_KINDS = {
    "site": "str",
    "start": "int",
    "method": "str",
    "success": "bool",
    "reason": "str",
    "features": "int",
    "distance_m": "number",
    "error_translation_m": "number?",
    "error_rotation_deg": "number?",
    "confident_wrong": "bool",
    "seconds": "number",
    "localised": "bool",
    "seed": "int",
    "start_pose": "numbers",
    "pose": "numbers?",
    "truth": "numbers?",
    "sweep_key": "str",
    "sweep_value": "str",
    "refused": "bool",
    "nees": "number?",
    "sigma_m": "number?",
    "kidnap_m": "number?",
    "lost_after_m": "number?",
    "recovered_after_m": "number?",
    "control_m": "number",
    "false_alarms": "int",
    "wrong_recovery": "bool",
}


def _is_number(value: object) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _type_problem(key: str, value: object) -> str | None:
    """What is wrong with one field of a resumed record (None: nothing)."""
    kind = _KINDS.get(key, "")
    if kind.endswith("?"):
        if value is None:
            return None
        kind = kind[:-1]
    ok = {
        "str": isinstance(value, str),
        "int": isinstance(value, int) and not isinstance(value, bool),
        "bool": isinstance(value, bool),
        "number": _is_number(value),
        "numbers": isinstance(value, list) and all(_is_number(v) for v in value),
    }.get(kind, True)
    return (
        None
        if ok
        else f"expected {kind.replace('numbers', 'a list of finite numbers')}, got {json.dumps(value)[:40]}"
    )


def parse_record(doc: object, where: str) -> TrialRecord:
    if not isinstance(doc, dict):
        raise InputError(f"{where}: expected a JSON object")
    missing = [k for k in REQUIRED if k not in doc]
    if missing:
        raise InputError(f"{where}: missing {missing[0]!r}")
    known = {k: v for k, v in doc.items() if k in _FIELDS}
    for key, value in known.items():
        problem = _type_problem(key, value)
        if problem:
            raise InputError(f"{where}: {key!r}: {problem}")
    try:
        return TrialRecord(**known)
    except TypeError as exc:
        raise InputError(f"{where}: {exc}") from None


def read_results(path: Path) -> list[TrialRecord]:
    """The records of ``results.jsonl``. A last line cut short (an interrupted run) is dropped."""
    path = Path(path)
    text = read_text(path, "results")
    lines = text.split("\n")
    out = []
    seen: dict[object, int] = {}  # (trial key, seed) -> its line
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            doc = parse_json(line, str(path), line=number, finite=False)  # depth and digits bounded
        except InputError as exc:
            if number == len(lines) and not text.endswith("\n"):
                break  # the interrupted last line: that trial runs again
            problem = str(exc).removeprefix(f"{path}:{number}: ")
            raise InputError(f"{path}:{number}: invalid JSON ({problem})") from None
        record = parse_record(doc, f"{path}:{number}")
        first = seen.setdefault((record.key, record.seed), number)
        if first != number:  # counted twice, every table and rate would be skewed
            k = record.key
            sweep = f", {k.sweep_key}={k.sweep_value}" if k.sweep_key else ""
            raise InputError(
                f"{path}:{number}: the trial of site {k.site!r}, start {k.start}, method {k.method!r}{sweep},"
                f" seed {record.seed} is already on line {first} (a results file written twice?)"
            )
        out.append(record)
    return out


def truncate_partial_line(path: Path) -> None:
    """Cut an unfinished last line so appended records start on a line of their own."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        path.write_bytes(data[: data.rfind(b"\n") + 1])


class ResultsWriter:
    """Appends one line per trial and flushes it, so an interrupted run loses no finished trial."""

    def __init__(self, path: Path, append: bool):
        path.parent.mkdir(parents=True, exist_ok=True)
        if append and path.exists():
            truncate_partial_line(path)
        self.handle: IO[str] = open(path, "a" if append else "w", encoding="utf-8")  # noqa: SIM115

    def write(self, record: TrialRecord) -> None:
        self.handle.write(record_line(record) + "\n")
        self.handle.flush()

    def close(self) -> None:
        self.handle.close()

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def write_csv(path: Path, columns: list[str], rows: list[dict[str, object]]) -> None:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    write_text_atomic(path, buffer.getvalue())
