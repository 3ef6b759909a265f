"""YOLO and COCO dataset loading: Roboflow-style paths, empty and missing label files, sparse COCO ids."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest

from bimkit.errors import InputError
from initcli.detector.datasets import DROPPED_FLAT, DROPPED_OUTSIDE, label_path, load_dataset


def _image(path: Path, w: int = 64, h: int = 48) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), np.full((h, w, 3), 128, np.uint8))


def _coco(images: list[dict], annotations: list[dict], categories: list[dict]) -> dict:
    return {"images": images, "annotations": annotations, "categories": categories}


def test_yolo_ultralytics_layout(tmp_path):
    root = tmp_path / "ds"
    for split, name in (("train", "a"), ("train", "b"), ("train", "c"), ("val", "d")):
        _image(root / "images" / split / f"{name}.jpg")
    labels = root / "labels" / "train"
    labels.mkdir(parents=True)
    (labels / "a.txt").write_text("0 0.5 0.5 0.2 0.4\n2 0.25 0.5 0.1 0.2\n\n")
    (labels / "b.txt").write_text("")  # empty: a background image
    # c.txt missing: also background
    (root / "labels" / "val").mkdir(parents=True)
    (root / "labels" / "val" / "d.txt").write_text("1 0.1 0.2 0.3 0.2 0.3 0.4 0.1 0.4\n")  # a polygon
    (root / "data.yaml").write_text(
        "path: .\ntrain: images/train\nval: images/val\nnames: {0: door, 1: lift, 2: stairs}\n"
    )
    ds = load_dataset(root / "data.yaml")
    assert ds.names == ["door", "lift", "stairs"]
    by_name = {it.image.stem: it for it in ds.train}
    assert sorted(by_name) == ["a", "b", "c"]
    assert by_name["a"].classes.tolist() == [0, 2]
    assert np.allclose(by_name["a"].boxes[0], [0.4, 0.3, 0.6, 0.7])
    assert len(by_name["b"].classes) == 0 and len(by_name["c"].classes) == 0
    assert np.allclose(ds.val[0].boxes[0], [0.1, 0.2, 0.3, 0.4]) and ds.val[0].classes.tolist() == [1]
    assert ds.instance_counts("train") == [1, 0, 1]


def test_yolo_moved_dataset_and_image_list(tmp_path):
    """``path`` that no longer exists falls back to the YAML's folder; .txt image lists work."""
    root = tmp_path / "moved"
    _image(root / "images" / "x.png")
    (root / "labels").mkdir(parents=True)
    (root / "labels" / "x.txt").write_text("0 0.5 0.5 1 1\n")
    (root / "train.txt").write_text("./images/x.png\n")
    (root / "data.yaml").write_text(
        "path: /nonexistent/original/place\ntrain: train.txt\nval: train.txt\nnames: [Door]\n"
    )
    ds = load_dataset(root)
    assert len(ds.train) == len(ds.val) == 1 and ds.train[0].classes.tolist() == [0]


def test_roboflow_yolo_export(tmp_path):
    """Roboflow writes data.yaml next to train/ valid/ test/ with '../train/images' paths and no path key."""
    root = tmp_path / "Doors.v2i.yolov8"
    _image(root / "train" / "images" / "img1_jpg.rf.abc.jpg")
    _image(root / "valid" / "images" / "img2_jpg.rf.def.jpg")
    (root / "train" / "labels").mkdir(parents=True)
    (root / "train" / "labels" / "img1_jpg.rf.abc.txt").write_text("1 0.5 0.5 0.5 0.5\n")
    (root / "valid" / "labels").mkdir(parents=True)
    (root / "valid" / "labels" / "img2_jpg.rf.def.txt").write_text("")
    (root / "data.yaml").write_text(
        "train: ../train/images\nval: ../valid/images\ntest: ../test/images\n\n"
        "nc: 2\nnames: ['door', 'elevator']\n"
        "roboflow:\n  workspace: w\n  project: p\n  version: 2\n"
    )
    ds = load_dataset(root / "data.yaml")
    assert ds.names == ["door", "elevator"]
    assert len(ds.train) == 1 and ds.train[0].classes.tolist() == [1]
    assert len(ds.val) == 1 and len(ds.val[0].classes) == 0


def test_label_path_uses_last_images_folder():
    p = Path("/data/images/set/images/train/a.jpeg")
    assert label_path(p) == Path("/data/images/set/labels/train/a.txt")


@pytest.mark.parametrize(
    ("yaml_text", "label", "message"),
    [
        ("train: images\nval: images\nnames: [door]\n", "3 0.5 0.5 0.1 0.1\n", "not one of 0..0"),
        ("train: images\nval: images\nnames: [door]\n", "0 0.5 0.5\n", "expected 5 values"),
        ("train: images\nval: images\nnames: [door]\n", "0 a b c d\n", "expected numbers"),
        ("train: nowhere\nnames: [door]\n", "", "not found"),
        ("train: images\n", "", "names: required"),
        ("- just\n- a list\n", "", "expected a mapping"),
        ("train: images\nnc: 2\nnames: [door]\n", "", "nc is 2"),
    ],
)
def test_yolo_bad_input(tmp_path, yaml_text, label, message):
    _image(tmp_path / "images" / "a.jpg")
    (tmp_path / "labels").mkdir()
    (tmp_path / "labels" / "a.txt").write_text(label)
    (tmp_path / "data.yaml").write_text(yaml_text)
    with pytest.raises(InputError, match=message):
        load_dataset(tmp_path / "data.yaml")


def test_coco_sparse_ids_and_split(tmp_path):
    images = [{"id": 100 + i, "file_name": f"im{i}.jpg", "width": 200, "height": 100} for i in range(10)]
    for im in images:
        _image(tmp_path / "images" / im["file_name"], 200, 100)
    anns = [
        {"id": 1, "image_id": 100, "category_id": 7, "bbox": [20, 10, 40, 50], "iscrowd": 0},
        {"id": 2, "image_id": 100, "category_id": 3, "bbox": [100, 0, 50, 100], "iscrowd": 0},
        {
            "id": 3,
            "image_id": 100,
            "category_id": 3,
            "bbox": [0, 0, 200, 100],
            "iscrowd": 1,
        },  # crowd: skipped
        {"id": 4, "image_id": 109, "category_id": 7, "bbox": [0, 0, 10, 10]},
    ]
    cats = [
        {"id": 3, "name": "lift", "supercategory": "bim"},
        {"id": 7, "name": "door", "supercategory": "bim"},
        {"id": 0, "name": "bim", "supercategory": "none"},
    ]  # Roboflow's unused project category
    path = tmp_path / "instances.json"
    path.write_text(json.dumps(_coco(images, anns, cats)))
    ds = load_dataset(path)
    assert ds.names == ["lift", "door"]  # id order, the unused supercategory dropped
    assert len(ds.train) == 9 and len(ds.val) == 1
    first = next(it for it in ds.train if it.image.name == "im0.jpg")
    assert first.image.exists()
    assert first.classes.tolist() == [1, 0]
    assert np.allclose(first.boxes, [[0.1, 0.1, 0.3, 0.6], [0.5, 0.0, 0.75, 1.0]])
    assert ds.val[0].image.name == "im9.jpg" and ds.val[0].classes.tolist() == [1]


def test_coco_roboflow_export_and_from_yaml(tmp_path):
    cats = [
        {"id": 0, "name": "doors", "supercategory": "none"},
        {"id": 1, "name": "door", "supercategory": "doors"},
    ]
    for split in ("train", "valid"):
        _image(tmp_path / split / "a.jpg")
        doc = _coco(
            [{"id": 0, "file_name": "a.jpg", "width": 64, "height": 48}],
            [{"id": 0, "image_id": 0, "category_id": 1, "bbox": [8, 8, 16, 24]}],
            cats,
        )
        (tmp_path / split / "_annotations.coco.json").write_text(json.dumps(doc))
    ds = load_dataset(tmp_path / "train" / "_annotations.coco.json")
    assert ds.names == ["door"] and len(ds.train) == 1 and len(ds.val) == 1
    (tmp_path / "data.yaml").write_text(
        "train: train/_annotations.coco.json\nval: valid/_annotations.coco.json\nnames: [door]\n"
    )
    ds2 = load_dataset(tmp_path / "data.yaml")
    assert len(ds2.train) == 1 and ds2.train[0].classes.tolist() == [0]


def test_coco_bad_input(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(InputError, match="invalid JSON"):
        load_dataset(bad)
    bad.write_text(json.dumps({"images": []}))
    with pytest.raises(InputError, match="not a COCO"):
        load_dataset(bad)
    bad.write_text(
        json.dumps(
            _coco(
                [{"id": 1, "file_name": "a.jpg", "width": 10, "height": 10}],
                [{"id": 1, "image_id": 1, "category_id": 5, "bbox": [0, 0, 1, 1]}],
                [{"id": 1, "name": "door"}],
            )
        )
    )
    with pytest.raises(InputError, match="unknown category_id"):
        load_dataset(bad)


def test_labels_without_area_in_the_image_are_dropped_and_counted_by_reason(tmp_path):
    root = tmp_path / "ds"
    _image(root / "images" / "train" / "a.jpg")
    (root / "labels" / "train").mkdir(parents=True)
    rows = ["0 1.5 0.5 0.2 0.2", "0 0.5 -0.4 0.2 0.2", "1 0.5 0.5 0 0.3", "2 0.95 0.5 0.2 0.2"]
    (root / "labels" / "train" / "a.txt").write_text("\n".join(rows) + "\n")
    (root / "data.yaml").write_text("path: .\ntrain: images/train\nnames: [door, lift, stairs]\n")
    ds = load_dataset(root / "data.yaml")
    assert ds.train[0].classes.tolist() == [2]  # clipped to the image, kept
    assert np.allclose(ds.train[0].boxes[0], [0.85, 0.4, 1.0, 0.6])
    assert dict(ds.dropped["train"]) == {DROPPED_OUTSIDE: 2, DROPPED_FLAT: 1}
    assert not ds.dropped["val"]
