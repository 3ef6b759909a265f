"""initcli.detector.calibrate: a tiny YOLO dataset measured through a fake detector gives the recall
bins, false boxes per image and confusion that the fake's behaviour implies."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from bimkit.errors import InputError
from initcli.detector.calibrate import ProfileAccumulator, calibrate_model, merged_edges
from initcli.detector.runtime import Detection

SHORT, TALL = 20.0, 200.0  # px: box heights of the two kinds of image (320 x 320: the model's input)


def _dataset(root: Path, n: int = 20) -> Path:
    """``n`` 320x320 images, image k filled with the value k: one door, 20 px tall in the even
    images and 200 px tall in the odd ones, centred at (160, 160); image 0 also has a lift."""
    (root / "images" / "val").mkdir(parents=True)
    (root / "labels" / "val").mkdir(parents=True)
    for k in range(n):
        cv2.imwrite(str(root / "images" / "val" / f"{k:03d}.png"), np.full((320, 320, 3), k, np.uint8))
        h = (SHORT if k % 2 == 0 else TALL) / 320
        rows = [f"0 0.5 0.5 0.1 {h}"] + (["1 0.1 0.1 0.1 0.1"] if k == 0 else [])
        (root / "labels" / "val" / f"{k:03d}.txt").write_text("\n".join(rows) + "\n")
    (root / "data.yaml").write_text(
        yaml.safe_dump({"path": ".", "val": "images/val", "names": ["door", "lift"]})
    )
    return root / "data.yaml"


@dataclass
class FakeDetector:
    """Finds every tall door and the short ones of images 0, 4, 8, ... (every other short one),
    calls the tall door of image 1 a lift, and adds a false stairs box at the corner of images 0,
    5, 10, 15 and a box below the score threshold to every image."""

    path: Path
    names: tuple[str, ...] = ("door", "lift", "stairs")
    input_size: tuple[int, int] = (320, 320)

    def detect(self, image: np.ndarray, conf: float | None = None) -> list[Detection]:
        k = int(image[0, 0, 0])
        h = SHORT if k % 2 == 0 else TALL
        box = (144.0, 160 - h / 2, 176.0, 160 + h / 2)
        out = [Detection("door", 0.1, (0.0, 0.0, 50.0, 50.0), 0)]  # below conf: not counted
        if k % 2 == 1 or k % 4 == 0:
            cls = 1 if k == 1 else 0
            out.append(Detection(self.names[cls], 0.6 + 0.01 * k, box, cls))
        if k % 5 == 0:
            out.append(Detection("stairs", 0.4, (280.0, 280.0, 320.0, 320.0), 2))
        return out


def test_merged_edges_hold_enough_boxes_per_bin() -> None:
    assert merged_edges([20.0] * 10 + [200.0] * 10, 320, min_boxes=8) == (0.0, 24.0, 320.0)
    assert merged_edges([20.0] * 3, 320, min_boxes=8) == (0.0, 320.0)  # too few: one bin
    edges = merged_edges(list(np.linspace(1, 319, 200)), 320, min_boxes=8)
    assert edges[0] == 0 and edges[-1] == 320 and len(edges) > 8


def test_calibrate_on_a_tiny_dataset_with_a_fake_detector(tmp_path: Path) -> None:
    data = _dataset(tmp_path / "ds")
    model = tmp_path / "fake.onnx"
    model.write_bytes(b"weights")
    profile, warnings = calibrate_model("fake", data, detector=FakeDetector(model), conf=0.25)
    assert warnings == []
    assert profile.images == 20 and profile.boxes == {"door": 20, "lift": 1}
    door = profile.recall["door"]
    assert door.edges == (0.0, 24.0, 320.0)
    assert door.boxes == (10, 10) and door.found == (5, 10)  # the short: 0, 4, 8, 12, 16
    assert profile.recall_of("door", 20.0) == pytest.approx(0.5)
    assert profile.recall_of("door", 200.0) == pytest.approx(1.0)
    assert profile.recall["lift"].found == (0,)
    assert sum(profile.recall["all"].boxes) == 21
    assert profile.confusion == {"door": {"door": 14, "lift": 1}}
    assert profile.false_boxes == {"door": 0.0, "lift": 0.0, "stairs": pytest.approx(4 / 20)}
    assert profile.false_boxes_per_image() == pytest.approx(0.2)
    assert min(profile.true_scores) == pytest.approx(0.6) and max(profile.false_scores) == pytest.approx(0.4)
    assert profile.model == "fake.onnx" and len(profile.sha256) == 64


def test_box_heights_are_measured_in_the_models_input() -> None:
    acc = ProfileAccumulator(320, 320)
    # a 640x480 image letterboxed into 320x320: half size; a 100 px box is 50 px of the input
    acc.add((640, 480), np.array([[0, 0, 40, 100.0]]), ["door"], np.zeros((0, 4)), np.zeros(0), [])
    assert acc.heights["door"] == [pytest.approx(50.0)]


def test_a_detection_finds_one_box_only_and_a_poor_overlap_is_a_false_box() -> None:
    acc = ProfileAccumulator(320, 320, conf=0.25, iou=0.5)
    gt = np.array([[0, 0, 100, 100.0]])
    boxes = np.array([[0, 0, 100, 100.0], [0, 0, 100, 100.0], [0, 0, 30, 30.0]])
    acc.add((320, 320), gt, ["door"], boxes, np.array([0.9, 0.8, 0.7]), ["door", "door", "lift"])
    profile = acc.profile("m", "0" * 64, ["door", "lift"], "d", "val")
    assert profile.recall["door"].found == (1,)
    assert profile.false_boxes == {"door": 1.0, "lift": 1.0}


def test_an_empty_split_is_refused(tmp_path: Path) -> None:
    data = _dataset(tmp_path / "ds", n=2)
    with pytest.raises(InputError, match="the train split has no images"):
        calibrate_model("fake", data, split="train", detector=FakeDetector(tmp_path / "x"))
