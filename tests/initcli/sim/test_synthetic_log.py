"""Synthetic detection logs validate against the detection-log schema."""

from __future__ import annotations

import io
import json
from pathlib import Path

import jsonschema

from initcli.io.log_writer import LogWriter, format_record
from initcli.sim.synthetic_log import SimFeature, make_log, path_from_waypoints
from tests.helpers import SCHEMAS

SCHEMA = json.loads((SCHEMAS / "detection_log.schema.json").read_text())


def test_synthetic_logs_validate_against_the_schema(tmp_path: Path) -> None:
    t, path = path_from_waypoints([(0.0, 1.0), (8.0, 1.0)])
    log = make_log([SimFeature("d", "door", 4.0, 0.0, 0.0, 1.0)], t, path)
    buf = io.StringIO()
    with LogWriter(buf) as writer:
        writer.write_all(log.records)
    lines = buf.getvalue().splitlines()
    assert len(lines) == len(log.records)
    for line in lines:
        jsonschema.validate(json.loads(line), SCHEMA)
    assert format_record(log.records[0]).startswith('{"type":"meta","version":1,"frame":"odom"')
