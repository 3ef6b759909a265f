"""Property-based: random and mutated inputs to every reader give a valid result or InputError, never
another exception (the log reader, features.csv, the site and eval configs, the categories file)."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from bimkit.errors import InputError
from bimtools.ifc.categories import DEFAULT_CATEGORIES, load_categories
from bimtools.site.features_csv import read_features
from initcli.config import load_config
from initcli.eval.config import load_eval_config
from initcli.io.detection_log import read_log
from tests.helpers import SAMPLES

FUZZ = settings(max_examples=100, deadline=None, suppress_health_check=[HealthCheck.too_slow])

GOOD_LOG = "\n".join(
    [
        '{"type": "meta", "version": 1, "frame": "odom", "camera": {"fx": 320, "fy": 320, "cx": 320, '
        '"cy": 240, "width": 640, "height": 480}, "camera_pose": {"x": 0.2, "y": 0, "z": 1, "roll": 0, '
        '"pitch": 0, "yaw": 0}}',
        '{"type": "odom", "t": 0.0, "x": 0.0, "y": 0.0, "yaw": 0.0}',
        '{"type": "detections", "t": 0.1, "pose": {"x": 0.0, "y": 0.0, "yaw": 0.0}, "objects": '
        '[{"class": "door", "score": 0.9, "bbox": [100, 100, 200, 300], "depth": 3.0}]}',
        '{"type": "feature", "t": 0.2, "class": "door", "x": 1.0, "y": 2.0}',
        '{"type": "scan", "t": 0.3, "angle_min": -3.14, "angle_increment": 0.0175, "range_max": 20, '
        '"ranges": [1.0, null, 2.5]}',
        '{"type": "truth", "t": 0.3, "x": 1.0, "y": 1.0, "yaw": 0.5}',
    ]
)
GOOD_CSV = (
    "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height,Storey,Elevation\n"
    "D1,Doors,1.0,2.0,0,1,0.9,2.1,L1,0\nL1,Lift,5,5,-1,0,1.1,2.2,L1,0\n"
)
GOOD_SITE = (SAMPLES / "ntu_hallway.site.yaml").read_text(encoding="utf-8")
GOOD_EVAL = "sites:\n  - config: site.yaml\nstarts: 2\nfailure:\n  max_error: 5\namcl:\n  particles: 100\n"
GOOD_CATEGORIES = DEFAULT_CATEGORIES.read_text(encoding="utf-8")


def mutate(text: str) -> st.SearchStrategy[bytes]:
    """The good text with bytes replaced, inserted or deleted, cut short, or numbers swapped."""
    data = text.encode("utf-8")
    specials = [
        b"nan",
        b"NaN",
        b".nan",
        b"-.inf",
        b"1e300",
        b"-1",
        b"0",
        b"1e12",
        b"\x00",
        b"\xff",
        b'"',
        b"{",
    ]

    @st.composite
    def build(draw: Callable[..., Any]) -> bytes:
        out = bytearray(data)
        for _ in range(draw(st.integers(1, 4))):
            if not out:
                break
            at = draw(st.integers(0, len(out) - 1))
            kind = draw(st.sampled_from(["replace", "insert", "delete", "cut", "special"]))
            if kind == "replace":
                out[at] = draw(st.integers(0, 255))
            elif kind == "insert":
                out[at:at] = draw(st.binary(min_size=1, max_size=8))
            elif kind == "delete":
                del out[at : at + draw(st.integers(1, 20))]
            elif kind == "cut":
                del out[at:]
            else:
                out[at : at + draw(st.integers(0, 4))] = draw(st.sampled_from(specials))
        return bytes(out)

    return st.one_of(build(), st.binary(max_size=300), st.text(max_size=200).map(lambda t: t.encode("utf-8")))


def check(reader: Callable[[Path], Any], data: bytes, name: str, extra: dict[str, str] | None = None) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        for other, text in (extra or {}).items():
            (Path(tmp) / other).write_text(text, encoding="utf-8")
        path = Path(tmp) / name
        path.write_bytes(data)
        try:
            reader(path)
        except InputError as exc:
            assert str(exc).strip(), "an InputError names what is wrong"


def test_the_good_inputs_are_read() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "log.jsonl").write_text(GOOD_LOG)
        assert len(read_log(root / "log.jsonl").records) == 5
        (root / "features.csv").write_text(GOOD_CSV)
        assert [f.id for f in read_features(root / "features.csv")] == ["D1", "L1"]
        (root / "site.yaml").write_text(GOOD_SITE)
        assert load_config(root / "site.yaml").fine_tuning.particles > 0
        (root / "eval.yaml").write_text(GOOD_EVAL)
        assert load_eval_config(root / "eval.yaml").amcl == {"particles": 100}
        (root / "categories.yaml").write_text(GOOD_CATEGORIES)
        assert load_categories(root / "categories.yaml").names


@FUZZ
@given(mutate(GOOD_LOG))
def test_log_reader(data: bytes) -> None:
    check(read_log, data, "log.jsonl")


@FUZZ
@given(mutate(GOOD_CSV))
def test_features_csv_reader(data: bytes) -> None:
    check(read_features, data, "features.csv")


@FUZZ
@given(mutate(GOOD_SITE))
def test_site_config_loader(data: bytes) -> None:
    check(load_config, data, "site.yaml")


@FUZZ
@given(mutate(GOOD_EVAL))
def test_eval_config_loader(data: bytes) -> None:
    check(load_eval_config, data, "eval.yaml", {"site.yaml": GOOD_SITE})


@FUZZ
@given(mutate(GOOD_CATEGORIES))
def test_categories_loader(data: bytes) -> None:
    check(load_categories, data, "categories.yaml")


YAML_VALUES = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.floats(allow_nan=True, allow_infinity=True)
    | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=8), inner, max_size=3),
    max_leaves=10,
)
SECTIONS = [
    "site",
    "robot",
    "camera",
    "lidar",
    "detector",
    "matching",
    "exploration",
    "fine_tuning",
    "limits",
    "sim",
]


@FUZZ
@given(st.sampled_from(SECTIONS), st.text(max_size=12), YAML_VALUES)
def test_site_config_with_random_values(section: str, key: str, value: Any) -> None:
    """Any value at any key of a valid config: a config or InputError."""
    doc = yaml.safe_load(GOOD_SITE)
    doc.setdefault(section, {})
    if isinstance(doc[section], dict):
        known = list(doc[section]) or [key]
        doc[section][known[hash(key) % len(known)] if key[:1] != "x" else key] = value
    check(load_config, yaml.safe_dump(doc).encode("utf-8"), "site.yaml")


@FUZZ
@given(st.sampled_from(["failure", "amcl", "markers", "starts", "seed", "sites"]), YAML_VALUES)
def test_eval_config_with_random_values(key: str, value: Any) -> None:
    doc = yaml.safe_load(GOOD_EVAL)
    doc[key] = value
    check(load_eval_config, yaml.safe_dump(doc).encode("utf-8"), "eval.yaml", {"site.yaml": GOOD_SITE})
