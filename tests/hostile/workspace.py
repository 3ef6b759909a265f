"""The valid inputs every hostile case starts from (one folder, copied for each case), and helpers
that write the hostile ones."""

from __future__ import annotations

import json
import math
import os
import shutil
from pathlib import Path

import cv2
import numpy as np
import yaml

from benchmarks._recordings import make_recording
from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.ifc.categories import DEFAULT_CATEGORIES
from initcli.io.log_writer import write_log
from initcli.ros.bag_writer import BagMessage, write_bag
from initcli.sim.synthetic_log import SimFeature, make_log, path_from_waypoints
from tests.helpers import SAMPLES

BILLION_LAUGHS = "\n".join(
    ["lol0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    + [f"lol{k}: &l{k} [{', '.join([f'*l{k - 1}'] * 10)}]" for k in range(1, 10)]
)
SUMMARY = {
    "success": True,
    "reason": "unique match, fine-tuned",
    "storey": "Level 1",
    "pose": {"x": 4.0, "y": 1.0, "yaw": 1.5708, "yaw_deg": 90.0},
    "covariance": [[0.01, 0.0, 0.0], [0.0, 0.02, 0.0], [0.0, 0.0, 0.001]],
    "duration_s": 30.0,
}


def recording_messages(duration: float = 2.0) -> list[BagMessage]:
    return make_recording(duration=duration).messages


def build(root: Path) -> Path:
    """The workspace: an IFC model, its site folder, configs for run and eval, a log, a bag, a
    summary, an image, a YOLO dataset stub, a categories file and files of the user's own."""
    root.mkdir(parents=True, exist_ok=True)
    shutil.copy(SAMPLES / "ntu_hallway.ifc", root / "model.ifc")
    write_site(root / "site", extract_site(root / "model.ifc"), preview=False)
    (root / "site.yaml").write_text(yaml.safe_dump({"site": {"path": "site"}}))
    (root / "ifc.site.yaml").write_text(yaml.safe_dump({"site": {"path": "model.ifc"}}))
    (root / "eval.yaml").write_text(yaml.safe_dump({"sites": [{"config": "site.yaml"}], "starts": 1}))
    shutil.copy(DEFAULT_CATEGORIES, root / "categories.yaml")
    features = [SimFeature(f"D{i}", "door", 2.0 + 4 * i, 0.0, 0.0, 1.0) for i in range(5)]
    t, path = path_from_waypoints([(1.0, 1.0), (18.0, 1.0)])
    write_log(root / "good.jsonl", make_log(features, t, path).records)
    write_bag(root / "rec.mcap", recording_messages())
    (root / "summary.json").write_text(json.dumps(SUMMARY))
    image = np.full((480, 640, 3), 200, np.uint8)
    image[80:470, 200:340] = (60, 70, 90)
    cv2.imwrite(str(root / "door.png"), image)
    (root / "imgs").mkdir()
    cv2.imwrite(str(root / "imgs" / "a.png"), image)
    data = root / "data"
    (data / "images" / "train").mkdir(parents=True)
    (data / "labels" / "train").mkdir(parents=True)
    cv2.imwrite(str(data / "images" / "train" / "a.png"), image)
    (data / "labels" / "train" / "a.txt").write_text("0 0.42 0.57 0.22 0.81\n")
    names = ["door", "lift", "stairs"]
    (data / "data.yaml").write_text(yaml.safe_dump({"path": ".", "train": "images/train", "names": names}))
    (root / "model.pt").write_bytes(b"not really a checkpoint")
    (root / "notes.txt").write_text("the user's notes\n")
    (root / "afile").write_text("a file, not a folder\n")
    (root / "other").mkdir()
    (root / "other" / "notes.txt").write_text("someone else's\n")
    (root / "dangling").symlink_to(root / "missing-target")
    return root


# --- hostile files ---------------------------------------------------------------------------------


def text(name: str, content: str):
    def setup(folder: Path) -> None:
        target = folder / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(content, encoding="utf-8")

    return setup


def config_plus(name: str, extra: str):
    """``site.yaml`` with ``extra`` YAML appended, as ``name``."""

    def setup(folder: Path) -> None:
        (folder / name).write_text((folder / "site.yaml").read_text() + extra)

    return setup


def log_lines(name: str, *extra: str, replace_first: str | None = None):
    """``good.jsonl`` with ``extra`` lines appended (or its first odom line replaced), as ``name``."""

    def setup(folder: Path) -> None:
        lines = (folder / "good.jsonl").read_text().splitlines()
        if replace_first is not None:
            k = next(i for i, line in enumerate(lines) if '"type":"odom"' in line.replace(" ", ""))
            lines[k] = replace_first
        (folder / name).write_text("\n".join([*lines, *extra]) + "\n")

    return setup


def summary_with(**change: object):
    def setup(folder: Path) -> None:
        (folder / "summary.json").write_text(json.dumps({**SUMMARY, **change}))

    return setup


def site_copy(name: str, edit):
    """A copy of the site folder as ``name``, then ``edit(folder / name)``."""

    def setup(folder: Path) -> None:
        shutil.copytree(folder / "site", folder / name)
        edit(folder / name)

    return setup


def map_yaml(**change: object):
    def edit(site: Path) -> None:
        path = next(site.glob("map_*.yaml"))
        doc = yaml.safe_load(path.read_text())
        doc.update(change)
        path.write_text(yaml.safe_dump(doc))

    return edit


def manifest(edit_doc):
    def edit(site: Path) -> None:
        doc = json.loads((site / "site.json").read_text())
        edit_doc(doc)
        (site / "site.json").write_text(json.dumps(doc))

    return edit


def fifo(name: str):
    def setup(folder: Path) -> None:
        os.mkfifo(folder / name)

    return setup


def sparse(name: str, size: int, head: bytes = b""):
    """A file of ``size`` bytes that takes no disk (its size is what a reader checks first)."""

    def setup(folder: Path) -> None:
        with open(folder / name, "wb") as handle:
            handle.write(head)
            handle.truncate(size)

    return setup


def link(name: str, target: str, hard: bool = False):
    def setup(folder: Path) -> None:
        if hard:
            os.link(folder / target, folder / name)
        else:
            (folder / name).symlink_to(folder / target)

    return setup


def moved(*pairs: tuple[str, str]):
    """Copy workspace files into a sub-folder layout: (source, destination) pairs."""

    def setup(folder: Path) -> None:
        for source, destination in pairs:
            (folder / destination).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(folder / source, folder / destination)

    return setup


def both(*setups):
    def setup(folder: Path) -> None:
        for s in setups:
            s(folder)

    return setup


def bag_with(name: str, change):
    """The recording with ``change(messages)`` applied, written as the bag ``name``."""

    def setup(folder: Path) -> None:
        messages = recording_messages()
        change(messages)
        write_bag(folder / name, messages)

    return setup


def nan_camera_k(messages: list[BagMessage]) -> None:
    for m in messages:
        if m.topic.endswith("camera_info"):
            m.value["k"][0] = math.nan


def nan_odometry(messages: list[BagMessage]) -> None:
    m = next(m for m in messages if m.topic == "/odom")
    m.value["pose"]["pose"]["position"]["x"] = math.nan


def inf_transform(messages: list[BagMessage]) -> None:
    m = next(m for m in messages if m.topic == "/tf_static")
    m.value["transforms"][0]["transform"]["translation"]["z"] = math.inf


def nan_detection(messages: list[BagMessage]) -> None:
    for m in messages:
        if m.topic == "/detections" and m.value["detections"]:
            m.value["detections"][0]["bbox"]["size_x"] = math.nan
            return


def huge_score(messages: list[BagMessage]) -> None:
    for m in messages:
        if m.topic == "/detections" and m.value["detections"]:
            m.value["detections"][0]["results"][0]["hypothesis"]["score"] = 1e9
            return


def nan_depth(messages: list[BagMessage]) -> None:
    for m in messages:
        if m.topic == "/camera/depth/image":
            m.value["data"] = np.full(m.value["height"] * m.value["width"], np.nan, "<f4").view(np.uint8)


def depthless_log(name: str):
    """``good.jsonl`` with every detection's depth null, as ``name``."""

    def setup(folder: Path) -> None:
        records = [json.loads(line) for line in (folder / "good.jsonl").read_text().splitlines()]
        for record in records:
            for obj in record.get("objects", []) if record["type"] == "detections" else []:
                obj["depth"] = None
        (folder / name).write_text("".join(json.dumps(r) + "\n" for r in records))

    return setup


def storey_elevation(name: str, elevation: float):
    """``model.ifc`` with its storey's elevation set to ``elevation``, as ``name``."""

    def setup(folder: Path) -> None:
        import ifcopenshell

        model = ifcopenshell.open(str(folder / "model.ifc"))
        for storey in model.by_type("IfcBuildingStorey"):
            storey.Elevation = elevation
        model.write(str(folder / name))

    return setup


def thin_image(name: str, width: int, height: int):
    def setup(folder: Path) -> None:
        cv2.imwrite(str(folder / name), np.full((height, width, 3), 128, np.uint8))

    return setup


def latin1_copy(source: str, name: bytes):
    def setup(folder: Path) -> None:
        shutil.copy(folder / source, os.path.join(os.fsencode(folder), name))

    return setup
