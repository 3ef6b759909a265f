"""The synthetic dataset writer: YOLO layout, labels, manifest, determinism."""

from __future__ import annotations

import json

import jsonschema
import numpy as np
import yaml

from initcli.detector.synth.dataset import SynthOptions, load_placements, render_sample, write_dataset
from tests.helpers import SCHEMAS


def test_synth_dataset(site_a, tmp_path):
    """A small dataset: YOLO layout, normalised labels inside the image, deterministic per (seed, i)."""
    out = tmp_path / "ds"
    doc = write_dataset(
        [site_a], out, SynthOptions(images=12, width=160, height=120, seed=3, val_fraction=0.25, workers=1)
    )
    data = yaml.safe_load((out / "data.yaml").read_text())
    assert set(data) >= {"path", "train", "val", "names"} and data["names"] == ["door", "lift", "stairs"]
    assert doc["images"] == {"train": 9, "val": 3}
    schema = json.loads((SCHEMAS / "synth_manifest.schema.json").read_text())
    jsonschema.validate(json.loads((out / "synth.json").read_text()), schema)
    assert len(list((out / "images" / "train").glob("*.jpg"))) == 9
    assert len(list((out / "depth" / "val").glob("*.png"))) == 3
    rows = [line.split() for p in (out / "labels").rglob("*.txt") for line in p.read_text().splitlines()]
    assert rows, "no labels in 12 images"
    for r in rows:
        assert len(r) == 5 and r[0] in {"0", "1", "2"}
        cx, cy, w, h = map(float, r[1:])
        assert 0 <= cx - w / 2 and cx + w / 2 <= 1.0001 and 0 <= cy - h / 2 and cy + h / 2 <= 1.0001
    placements = load_placements([site_a])
    opts = SynthOptions(width=160, height=120, seed=3)
    a, b = render_sample(placements, 5, opts), render_sample(placements, 5, opts)
    assert np.array_equal(a.image_rgb, b.image_rgb) and a.pose == b.pose
