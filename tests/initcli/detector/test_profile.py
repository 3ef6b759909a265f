"""initcli.detector.profile: the file round-trips, bad files are one line, the shipped profiles are
those of the shipped model, and the draws follow the profile."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest

from bimkit.errors import InputError
from initcli.detector import DEFAULT_MODEL, MODELS_DIR
from initcli.detector.profile import (
    PROFILE_NAMES,
    DetectorProfile,
    RecallTable,
    read_profile,
    resolve_profile,
    write_profile,
)


def profile(**change: object) -> DetectorProfile:
    fields: dict = {
        "model": "m.onnx",
        "sha256": "0" * 64,
        "classes": ("door", "lift"),
        "input_width": 320,
        "input_height": 320,
        "data": "data.yaml",
        "split": "val",
        "images": 10,
        "conf": 0.25,
        "iou": 0.5,
        "recall": {
            "door": RecallTable((0.0, 50.0, 320.0), (10, 10), (2, 9)),
            "all": RecallTable((0.0, 320.0), (20,), (11,)),
        },
        "false_boxes": {"door": 0.5, "lift": 0.25},
        "confusion": {"door": {"door": 3, "lift": 1}},
        "true_scores": (0.3, 0.6, 0.9),
        "false_scores": (0.25, 0.3),
        "boxes": {"door": 20},
    }
    fields.update(change)
    return DetectorProfile(**fields)


def test_a_profile_round_trips_through_its_file(tmp_path: Path) -> None:
    path = tmp_path / "p.json"
    write_profile(profile(), path)
    assert read_profile(path) == profile()


def test_recall_by_height_and_the_pooled_table_for_a_class_without_one() -> None:
    p = profile()
    assert p.recall_of("door", 10.0) == pytest.approx(0.2)
    assert p.recall_of("door", 100.0) == pytest.approx(0.9)
    assert p.recall_of("door", 5000.0) == pytest.approx(0.9)  # taller than the last edge: the last bin
    assert p.recall_of("stairs", 100.0) == pytest.approx(11 / 20)
    assert p.input_scale(640, 480) == pytest.approx(0.5)


def test_draws_follow_the_confusion_matrix_and_the_score_quantiles() -> None:
    p, rng = profile(), np.random.default_rng(0)
    given = [p.given_class("door", rng) for _ in range(4000)]
    assert given.count("lift") / len(given) == pytest.approx(0.25, abs=0.03)
    assert {p.given_class("lift", rng) for _ in range(20)} == {"lift"}  # no row: unchanged
    scores = np.array([p.score(rng, true=True) for _ in range(4000)])
    assert scores.min() >= 0.3 and scores.max() <= 0.9 and np.median(scores) == pytest.approx(0.6, abs=0.03)


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (lambda d: d.pop("recall"), r"\(top level\): required|recall: required"),
        (lambda d: d["recall"]["door"].update(found=[2, 11]), r"more boxes found than there are"),
        (lambda d: d["recall"]["door"].update(edges=[0, 320]), r"one more edge than bins"),
        (lambda d: d["false_boxes"]["classes"].update(door=-1), r"false_boxes.classes.door: -1"),
        (lambda d: d.update(format="x"), r"format"),
    ],
)
def test_a_bad_profile_is_one_line_naming_the_file(tmp_path: Path, edit, message: str) -> None:
    path = tmp_path / "p.json"
    doc = profile().to_dict()
    edit(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(InputError, match=message) as info:
        read_profile(path)
    assert str(path) in str(info.value) and "\n" not in str(info.value)


def test_a_missing_or_broken_profile_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such detector profile"):
        read_profile(tmp_path / "none.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(InputError, match="not valid JSON"):
        read_profile(tmp_path / "bad.json")


def test_names_resolve_to_the_shipped_profiles_and_paths_to_the_configs_folder(tmp_path: Path) -> None:
    assert resolve_profile("default-real") == MODELS_DIR / "default.real.profile.json"
    assert resolve_profile("Default-Renders") == MODELS_DIR / "default.renders.profile.json"
    assert resolve_profile("my.json", tmp_path) == tmp_path / "my.json"
    assert resolve_profile(str(tmp_path / "a.json"), Path("/else")) == tmp_path / "a.json"


def test_the_shipped_profiles_were_measured_with_the_shipped_model() -> None:
    """When default.onnx changes, ``make profiles`` measures them again."""
    digest = hashlib.sha256(DEFAULT_MODEL.read_bytes()).hexdigest()
    for name, path in PROFILE_NAMES.items():
        p = read_profile(path)
        assert p.sha256 == digest, f"{name}: measured with another model: run make profiles"
        assert p.model == DEFAULT_MODEL.name and p.conf == 0.25
    real = read_profile(PROFILE_NAMES["default-real"])
    assert real.split == "val" and set(real.boxes) == {"door"}  # DoorDetect's hold-out: doors only
    renders = read_profile(PROFILE_NAMES["default-renders"])
    assert set(renders.boxes) == {"door", "lift", "stairs"} and renders.images == 500
