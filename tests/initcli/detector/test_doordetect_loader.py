"""DoorDetect-style sources: class remapping (hard negatives kept as background) and the hash hold-out."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from bimkit.errors import InputError
from initcli.detector.datasets import holdout_fraction, load_dataset, load_doordetect, load_remapped

NAMES = ["door", "lift", "stairs"]


def make_doordetect(root: Path, n: int = 40) -> dict[str, list[int]]:
    """n tiny JPEGs; a door (class 0) in every third, a handle (1) and a cabinet door (2) in all."""
    (root / "images").mkdir(parents=True)
    (root / "labels").mkdir()
    truth = {}
    for k in range(n):
        name = f"{k:04x}beef{k}"
        cv2.imwrite(str(root / "images" / f"{name}.jpg"), np.full((24, 32, 3), k * 5 % 255, np.uint8))
        rows = ["1 0.5 0.5 0.05 0.05", "2 0.3 0.3 0.2 0.2"]
        classes = [1, 2]
        if k % 3 == 0:
            rows.insert(0, "0 0.5 0.5 0.4 0.8")
            classes.insert(0, 0)
        if k % 7 == 0:
            rows.append("3 0.7 0.6 0.2 0.6")
            classes.append(3)
        (root / "labels" / f"{name}.txt").write_text("\n".join(rows) + "\n")
        truth[f"{name}.jpg"] = classes
    return truth


def test_doordetect_keeps_doors_drops_hard_negatives(tmp_path):
    truth = make_doordetect(tmp_path / "dd")
    train = load_doordetect(tmp_path / "dd", holdout=0.25, part="train").train
    held = load_doordetect(tmp_path / "dd", holdout=0.25, part="holdout").val
    items = train + held
    assert len(items) == len(truth)  # every image kept, negatives included
    for item in items:
        n_doors = truth[item.image.name].count(0)
        assert list(item.classes) == [0] * n_doors  # only doors, as our class 0
        if n_doors:
            assert np.allclose(item.boxes[0], [0.3, 0.1, 0.7, 0.9])
    assert sum(len(i.classes) == 0 for i in items) == sum(0 not in c for c in truth.values())


def test_hash_split_is_stable_and_disjoint(tmp_path):
    truth = make_doordetect(tmp_path / "dd")
    first = {i.image.name for i in load_doordetect(tmp_path / "dd", 0.25, "holdout").val}
    again = {i.image.name for i in load_doordetect(tmp_path / "dd", 0.25, "holdout").val}
    rest = {i.image.name for i in load_doordetect(tmp_path / "dd", 0.25, "train").train}
    assert first == again and not first & rest and first | rest == set(truth)
    assert first == {n for n in truth if holdout_fraction(n) < 0.25}
    assert 0 < len(first) < len(truth) // 2
    # the split depends on the file name only, not on the folder it lies in
    assert holdout_fraction("/a/b/x.jpg") == holdout_fraction("x.jpg")
    # a larger hold-out contains the smaller one (images never move from hold-out to train)
    bigger = {i.image.name for i in load_doordetect(tmp_path / "dd", 0.5, "holdout").val}
    assert first <= bigger


def test_mapping_entries_in_data_yaml(tmp_path):
    make_doordetect(tmp_path / "dd")
    entry = {"path": str(tmp_path / "dd"), "classes": {0: "door"}, "holdout": 0.25, "domain": "photos"}
    doc = {
        "names": NAMES,
        "train": [{**entry, "part": "train"}],
        "val": [{**entry, "part": "holdout"}],
    }
    (tmp_path / "data.yaml").write_text(yaml.safe_dump(doc))
    ds = load_dataset(tmp_path / "data.yaml")
    assert len(ds.train) + len(ds.val) == 40 and ds.val and ds.train
    assert {i.domain for i in ds.train} == {"photos"}
    assert ds.instance_counts("train")[1:] == [0, 0]


def test_bad_mapping_is_input_error(tmp_path):
    make_doordetect(tmp_path / "dd")
    with pytest.raises(InputError, match="not one of the dataset's names"):
        load_remapped(tmp_path / "dd", NAMES, {0: "window"})
    with pytest.raises(InputError, match="part"):
        load_remapped(tmp_path / "dd", NAMES, {0: "door"}, part="test")
    (tmp_path / "data.yaml").write_text(yaml.safe_dump({"names": NAMES, "train": [{"classes": {0: "door"}}]}))
    with pytest.raises(InputError, match="needs 'path'"):
        load_dataset(tmp_path / "data.yaml")


SHARED = Path("/work/shared/datasets/doordetect_train")


@pytest.mark.skipif(not SHARED.is_dir(), reason="/work/shared/datasets/doordetect_train is not here")
def test_shared_doordetect_split_sizes():
    held = load_doordetect(SHARED, 0.2, "holdout").val
    train = load_doordetect(SHARED, 0.2, "train").train
    assert len(held) + len(train) == len(list((SHARED / "images").iterdir()))
    assert 0.15 < len(held) / (len(held) + len(train)) < 0.25
    assert sum(len(i.classes) for i in held + train) == sum(
        line.split()[0] == "0"
        for p in (SHARED / "labels").glob("*.txt")
        for line in p.read_text().splitlines()
        if line.strip()
    )


def test_one_folder_as_two_domains_weights_the_sampler(tmp_path):
    """The shipped recipe's data.yaml: the renders folder listed twice, split in halves by the hash
    hold-out under two domain names, so that balanced sampling draws renders twice as often as photos."""
    train_mod = pytest.importorskip("initcli.detector.training.train")
    make_doordetect(tmp_path / "photos")
    make_doordetect(tmp_path / "renders", n=60)
    half = {"path": str(tmp_path / "renders"), "classes": {0: "door"}, "holdout": 0.5}
    doc = {
        "names": NAMES,
        "train": [
            {"path": str(tmp_path / "photos"), "classes": {0: "door"}, "domain": "photos"},
            {**half, "part": "train", "domain": "renders_a"},
            {**half, "part": "holdout", "domain": "renders_b"},
        ],
    }
    (tmp_path / "data.yaml").write_text(yaml.safe_dump(doc))
    items = load_dataset(tmp_path / "data.yaml").train
    halves = [{i.image.name for i in items if i.domain == d} for d in ("renders_a", "renders_b")]
    assert halves[0] and halves[1] and not halves[0] & halves[1] and len(halves[0] | halves[1]) == 60
    w = train_mod.balanced_weights(items, len(NAMES))
    share = {
        d: sum(wi for wi, it in zip(w, items, strict=True) if it.domain == d)
        for d in ("photos", "renders_a", "renders_b")
    }
    assert share["photos"] == pytest.approx(1 / 3) and share["renders_a"] == pytest.approx(1 / 3)
    # within the photos, images with a door and images without one are drawn equally often
    doors = sum(wi for wi, it in zip(w, items, strict=True) if it.domain == "photos" and len(it.classes))
    assert doors == pytest.approx(1 / 6)
