"""One fuzz target per file reader: a valid file, mutated (bytes replaced, inserted, deleted, cut
short, swapped for NaN, huge numbers, NUL or brackets) or replaced by random bytes, handed to the
reader. The promise, as the CLIs keep it: the file is read, or one :class:`InputError` with a
one-line message comes back (exit 2 and one line at the command); any other exception -- a
traceback at the command -- is a failure.

Used by ``tests/fuzz/test_readers.py`` (a few examples each, in the suite) and by
``python -m tests.fuzz.run`` (``make fuzz``: each target for a bounded time).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import yaml
from hypothesis import strategies as st

from bimkit.errors import InputError
from tests.helpers import SAMPLES

SPECIALS = [b"nan", b"NaN", b".nan", b"-.inf", b"Infinity", b"1e999", b"1e300", b"-1", b"0", b"1e12"]
SPECIALS += [b"9" * 5000, b"\x00", b"\xff", b'"', b"{", b"[" * 200, b"&a [*a]", b"*a", b"\n- ", b": :"]


def mutate(data: bytes, cuts: int = 4) -> st.SearchStrategy[bytes]:
    """``data`` with up to ``cuts`` edits, or random bytes, or random text."""

    @st.composite
    def build(draw: Callable[..., Any]) -> bytes:
        out = bytearray(data)
        for _ in range(draw(st.integers(1, cuts))):
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
                out[at : at + draw(st.integers(0, 4))] = draw(st.sampled_from(SPECIALS))
        return bytes(out)

    return st.one_of(build(), st.binary(max_size=300), st.text(max_size=200).map(lambda t: t.encode("utf-8")))


@dataclass(frozen=True)
class Target:
    """A reader fed ``name`` (with ``beside``: other files of the folder, as valid bytes)."""

    name: str
    file: str
    seed: Callable[[], bytes]
    read: Callable[[Path], Any]
    beside: Callable[[], dict[str, bytes]] = dict
    cuts: int = 4

    def strategy(self) -> st.SearchStrategy[bytes]:
        return mutate(self.seed(), self.cuts)

    def check(self, data: bytes) -> None:
        """Read ``data`` as the target's file: a value, or one InputError of one line."""
        with tempfile.TemporaryDirectory(prefix="bim-fuzz-") as tmp:
            folder = Path(tmp)
            for name, content in self.beside().items():
                (folder / name).parent.mkdir(parents=True, exist_ok=True)
                (folder / name).write_bytes(content)
            (folder / self.file).write_bytes(data)
            try:
                self.read(folder / self.file)
            except InputError as exc:
                message = str(exc)
                assert message.strip(), "an InputError names what is wrong"
                assert "\n" not in message.strip(), f"more than one line: {message!r}"


# --- the valid files -------------------------------------------------------------------------------


@cache
def _site_files() -> dict[str, bytes]:
    """The files of a site folder extracted from the ntu_hallway sample (once per process)."""
    from bimtools.extract.output import write_site
    from bimtools.extract.pipeline import extract_site

    folder = Path(tempfile.mkdtemp(prefix="bim-fuzz-site-"))
    try:
        write_site(folder / "site", extract_site(SAMPLES / "ntu_hallway.ifc"), preview=False)
        return {p.name: p.read_bytes() for p in (folder / "site").iterdir() if p.is_file()}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _site_file(name: str) -> Callable[[], bytes]:
    def seed() -> bytes:
        files = _site_files()
        return files[next(k for k in files if k == name or (name == "map.yaml" and k.endswith(".yaml")))]

    return seed


def _site_but(name: str) -> Callable[[], dict[str, bytes]]:
    def beside() -> dict[str, bytes]:
        return {k: v for k, v in _site_files().items() if k != name}

    return beside


def _map_beside() -> dict[str, bytes]:
    return {k: v for k, v in _site_files().items() if k.endswith(".pgm")}


@cache
def _log() -> bytes:
    from initcli.io.log_writer import format_record
    from initcli.sim.synthetic_log import SimFeature, make_log, path_from_waypoints

    features = [SimFeature(f"D{i}", "door", 2.0 + 4 * i, 0.0, 0.0, 1.0) for i in range(3)]
    t, path = path_from_waypoints([(1.0, 1.0), (6.0, 1.0)])
    records = make_log(features, t, path).records[:40]
    return ("\n".join(format_record(r) for r in records) + "\n").encode()


@cache
def _bag() -> bytes:
    from benchmarks._recordings import make_recording
    from initcli.ros.bag_writer import write_bag

    folder = Path(tempfile.mkdtemp(prefix="bim-fuzz-bag-"))
    try:
        return write_bag(folder / "rec.mcap", make_recording(duration=1.0).messages).read_bytes()
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _carmen() -> bytes:
    """A short CARMEN log: odometry and 12-beam FLASER scans in a 4 x 4 m room (1 degree beams from
    -90 as the format writes them, here 15 degrees apart for brevity: 12 beams span 165 degrees)."""
    lines = ["# CARMEN Logfile", "PARAM robot_front_laser_max 8.0 nohost 0.0"]
    for k in range(6):
        t = 0.5 * k
        x = 0.3 * k
        ranges = " ".join(f"{1.5 + 0.1 * ((k + b) % 5):.2f}" for b in range(180))
        lines.append(f"ODOM {x:.3f} 0.000 0.000 0.3 0.0 0.0 {t:.3f} nohost {t:.3f}")
        lines.append(f"FLASER 180 {ranges} {x:.3f} 0.000 0.000 {x:.3f} 0.000 0.000 {t:.3f} nohost {t:.3f}")
    return ("\n".join(lines) + "\n").encode()


def _watch_records() -> list[Any]:
    import math

    from initcli.io.log_records import NO_CAMERA, NO_MOUNT, Localiser, Meta, Odom, Scan

    records: list[Any] = [Meta(NO_CAMERA, NO_MOUNT, camera_absent=True)]
    for k in range(8):
        t = 0.1 * k
        records.append(Odom(t, 0.1 * k, 0.0, 0.0))
        records.append(Scan(t + 0.01, -math.pi, math.tau / 16, 8.0, tuple(2.0 for _ in range(16))))
        records.append(Localiser(t + 0.02, 3.0 + 0.1 * k, 1.0, 0.5))
    return records


def _watch_log() -> bytes:
    from initcli.io.log_writer import format_record

    return ("\n".join(format_record(r) for r in _watch_records()) + "\n").encode()


@cache
def _lidar_bag() -> bytes:
    """A bag without a camera: /odom, /scan and the localiser on /amcl_pose."""
    from initcli.io.log_records import Localiser, Odom, Scan
    from initcli.ros.bag_writer import BagMessage, laser_scan, odometry, write_bag
    from initcli.ros.nav2 import initial_pose_message
    from initcli.ros.records import LASER_SCAN, ODOMETRY, POSE_WITH_COVARIANCE_STAMPED, InitialPose

    messages = []
    for r in _watch_records()[1:]:
        if isinstance(r, Odom):
            messages.append(BagMessage("/odom", ODOMETRY, r.t, odometry(r.t, r.pose)))
        elif isinstance(r, Scan):
            messages.append(BagMessage("/scan", LASER_SCAN, r.t, laser_scan(r.t, r)))
        elif isinstance(r, Localiser):
            pose = initial_pose_message(InitialPose(r.t, r.x, r.y, r.yaw, (0.0,) * 36))
            messages.append(BagMessage("/amcl_pose", POSE_WITH_COVARIANCE_STAMPED, r.t, pose))
    folder = Path(tempfile.mkdtemp(prefix="bim-fuzz-bag-"))
    try:
        return write_bag(folder / "lidar.mcap", messages).read_bytes()
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _summary() -> bytes:
    doc = {
        "success": True,
        "reason": "initialised",
        "pose": {"x": 4.0, "y": 1.0, "yaw": 1.5708, "yaw_deg": 90.0},
        "covariance": [[0.01, 0.0, 0.0], [0.0, 0.02, 0.0], [0.0, 0.0, 0.001]],
        "duration_s": 30.0,
    }
    return json.dumps(doc, indent=2).encode()


def _text(path: Path) -> Callable[[], bytes]:
    return lambda: path.read_bytes()


def _eval_config() -> bytes:
    return b"sites:\n  - config: site.yaml\nstarts: 2\nfailure:\n  max_error: 5\namcl:\n  particles: 100\n"


# --- the readers -----------------------------------------------------------------------------------


def _read_ifc(path: Path) -> None:
    from bimtools.ifc.model import open_model

    open_model(path)


def _read_site_config(path: Path) -> None:
    from initcli.config import load_config

    load_config(path)


def _read_eval_config(path: Path) -> None:
    from initcli.eval.config import load_eval_config

    load_eval_config(path)


def _read_categories(path: Path) -> None:
    from bimtools.ifc.categories import load_categories

    load_categories(path)


def _read_features(path: Path) -> None:
    from bimtools.site.features_csv import read_features

    read_features(path)


def _read_walls(path: Path) -> None:
    from bimtools.site.walls_geojson import read_walls

    read_walls(path)


def _read_map(path: Path) -> None:
    from bimtools.site.occupancy_map import read_map

    read_map(path)


def _read_pgm(path: Path) -> None:
    from bimtools.site.occupancy_map import read_map

    yaml_path = path.with_name("map.yaml")
    yaml_path.write_text(yaml.safe_dump({"image": path.name, "resolution": 0.05, "origin": [0, 0, 0]}))
    read_map(yaml_path)


def _read_site(path: Path) -> None:
    from bimtools.site.load import load_site

    load_site(path.parent)


def _read_log(path: Path) -> None:
    from initcli.io.detection_log import read_log

    read_log(path)
    read_log(path, skip_bad=True)


def _read_bag(path: Path) -> None:
    from initcli.ros.bag_reader import bag_to_records

    bag_to_records(path)


def _read_carmen(path: Path) -> None:
    from initcli.io.carmen import carmen_to_records

    carmen_to_records(path)


def _read_watch_log(path: Path) -> None:
    from initcli.io.detection_log import read_log
    from initcli.watch.replay import check_recording

    check_recording(read_log(path))


def _read_lidar_bag(path: Path) -> None:
    from initcli.ros.bag_reader import bag_to_records
    from initcli.ros.records import Bag2LogOptions

    bag_to_records(path, Bag2LogOptions(lidar_only=True))


def _read_summary(path: Path) -> None:
    from initcli.ros.nav2 import initial_pose_message, read_summary, session_initial_pose

    initial_pose_message(session_initial_pose(read_summary(path), None))


def _read_results(path: Path) -> None:
    from initcli.eval.results_file import read_results

    read_results(path)


def _results() -> bytes:
    line = {"site": "a", "start": 0, "method": "bim", "success": True, "reason": "ok", "features": 4}
    line |= {"distance_m": 12.5, "error_translation_m": 0.2, "error_rotation_deg": 1.5}
    line |= {"confident_wrong": False, "seconds": 3.0}
    return (json.dumps(line) + "\n").encode()


def _read_image(path: Path) -> None:
    from initcli.io.images import read_image

    read_image(path)


def _image() -> bytes:
    import cv2
    import numpy as np

    ok, png = cv2.imencode(".png", np.full((24, 32, 3), 128, np.uint8))
    assert ok
    return png.tobytes()


SITE_YAML = (SAMPLES / "ntu_hallway.site.yaml").read_bytes()

TARGETS = [
    Target("ifc", "model.ifc", _text(SAMPLES / "ntu_hallway.ifc"), _read_ifc, cuts=3),
    Target("site-config", "site.yaml", lambda: SITE_YAML, _read_site_config),
    Target("eval-config", "eval.yaml", _eval_config, _read_eval_config, lambda: {"site.yaml": SITE_YAML}),
    Target("categories", "categories.yaml", lambda: _categories_text(), _read_categories),
    Target("features-csv", "features.csv", _site_file("features.csv"), _read_features),
    Target("walls-geojson", "walls.geojson", _site_file("walls.geojson"), _read_walls),
    Target("map-yaml", "map.yaml", _site_file("map.yaml"), _read_map, _map_beside),
    Target("map-pgm", "map.pgm", lambda: b"P5\n4 3\n255\n" + bytes(range(12)), _read_pgm),
    Target("manifest", "site.json", _site_file("site.json"), _read_site, _site_but("site.json")),
    Target("log", "log.jsonl", _log, _read_log),
    Target("bag", "rec.mcap", _bag, _read_bag, cuts=2),
    Target("carmen", "robot.log", _carmen, _read_carmen),
    Target("watch-log", "watch.jsonl", _watch_log, _read_watch_log),
    Target("lidar-bag", "lidar.mcap", _lidar_bag, _read_lidar_bag, cuts=2),
    Target("summary", "summary.json", _summary, _read_summary),
    Target("results", "results.jsonl", _results, _read_results),
    Target("image", "image.png", _image, _read_image),
]


def _categories_text() -> bytes:
    from bimtools.ifc.categories import DEFAULT_CATEGORIES

    return DEFAULT_CATEGORIES.read_bytes()


def target(name: str) -> Target:
    return next(t for t in TARGETS if t.name == name)
