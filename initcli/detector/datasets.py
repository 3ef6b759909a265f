"""Detection datasets: YOLO (``data.yaml``, incl. Roboflow-style relative paths) and COCO json.

Both are read into :class:`Dataset`: class names and, per split, the image paths with their
boxes as normalised ``[x1, y1, x2, y2]`` (fractions of the image width and height) and class
indices. No torch here.

YOLO rules (as Ultralytics applies them): ``path`` is the dataset root (relative to the YAML's
folder; when it does not exist the YAML's folder is used, so a moved dataset still loads);
``train``/``val``/``test`` are a folder of images, a ``.txt`` list of images or a list of those,
relative to the root; a Roboflow export's ``../train/images`` is also tried without its ``../``.
The label of ``.../images/x.jpg`` is ``.../labels/x.txt``: one ``class cx cy w h`` row per box
(normalised), or ``class x1 y1 x2 y2 ...`` polygons (turned into their boxes); a missing or
empty label file is a background image. ``names`` is a list or a ``{id: name}`` mapping.

A ``train``/``val`` entry may also be a mapping (a bim-init extension) that remaps another
dataset's classes and holds part of it out by a hash of the file name::

    train:
      - {path: /data/doordetect_train, classes: {0: door}, holdout: 0.2, part: train}
    val:
      - {path: /data/doordetect_train, classes: {0: door}, holdout: 0.2, part: holdout}

``path`` is a folder with ``images/`` and ``labels/`` (or a folder of images); ``classes`` maps
its class ids to our names -- boxes of any other class are dropped and their images kept as
negatives (DoorDetect's handles, cabinet and refrigerator doors); ``part`` picks ``train``, the
``holdout`` (a stable ``holdout`` fraction, by :func:`holdout_fraction` of the file name) or
``all``; ``domain`` (default: the folder's name) names the source for balanced sampling.

COCO rules: ``bbox`` is ``[x_min, y_min, width, height]`` in pixels; category ids may be
1-based and sparse (they are renumbered in id order); crowd annotations are skipped; images are
looked up beside the json, in ``images/`` beside it or beside its folder. A Roboflow COCO
export (``train/_annotations.coco.json`` with a sibling ``valid/``) gives both splits, and a
lone json is split 90/10 (every tenth image is validation).
"""

from __future__ import annotations

import hashlib
import os
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bimkit.checks import parse_json, read_bytes, read_text, read_yaml
from bimkit.errors import InputError
from bimkit.limits import MAX_TEXT_BYTES

__all__ = [
    "DROPPED_CLASS",
    "DROPPED_FLAT",
    "DROPPED_OUTSIDE",
    "DOORDETECT_CLASSES",
    "Dataset",
    "DatasetItem",
    "IMAGE_SUFFIXES",
    "PARTS",
    "holdout_fraction",
    "label_path",
    "load_coco",
    "load_dataset",
    "load_doordetect",
    "load_remapped",
    "load_yolo",
    "read_yolo_labels",
]

IMAGE_SUFFIXES = {".jpg", ".jpeg", ".png", ".bmp", ".webp", ".tif", ".tiff"}


@dataclass
class DatasetItem:
    image: Path
    classes: np.ndarray  # (n,) int
    boxes: np.ndarray  # (n, 4) float, normalised x1 y1 x2 y2
    domain: str = ""  # the source it came from (a mapping entry's 'domain'), for balanced sampling


@dataclass
class Dataset:
    names: list[str]
    train: list[DatasetItem] = field(default_factory=list)
    val: list[DatasetItem] = field(default_factory=list)
    source: Path | None = None
    warnings: list[str] = field(default_factory=list)
    # per split: label rows read but not kept, by reason (see DROPPED)
    dropped: dict[str, Counter[str]] = field(default_factory=lambda: {"train": Counter(), "val": Counter()})

    def split(self, name: str) -> list[DatasetItem]:
        return self.train if name == "train" else self.val

    def instance_counts(self, split: str) -> list[int]:
        counts = [0] * len(self.names)
        for item in self.split(split):
            for c in item.classes:
                counts[int(c)] += 1
        return counts


def load_dataset(path: Path | str, val: Path | str | None = None) -> Dataset:
    """A ``data.yaml`` (YOLO) or a COCO ``.json``; ``val`` optionally names a separate COCO val json."""
    path = Path(path)
    if not path.exists():
        raise InputError(f"{path}: no such file")
    if path.is_dir():
        for candidate in ("data.yaml", "data.yml", "dataset.yaml"):
            if (path / candidate).exists():
                return load_yolo(path / candidate)
        raise InputError(f"{path}: a folder without data.yaml (pass the data.yaml or a COCO json)")
    if path.suffix.lower() == ".json":
        return load_coco(path, Path(val) if val else None)
    if path.suffix.lower() in (".yaml", ".yml"):
        return load_yolo(path)
    raise InputError(f"{path}: expected a YOLO data.yaml or a COCO .json")


# --- YOLO ------------------------------------------------------------------------------------------


def _names(doc: dict, where: Path) -> list[str]:
    names = doc.get("names")
    if isinstance(names, dict):
        try:
            keys = sorted(int(k) for k in names)
        except (TypeError, ValueError):
            raise InputError(f"{where}: names: expected integer keys, got {list(names)[:3]}") from None
        if keys != list(range(len(keys))):
            raise InputError(f"{where}: names: ids must be 0..{len(keys) - 1}, got {keys}")
        lookup = {int(k): v for k, v in names.items()}
        out = [str(lookup[k]) for k in keys]
    elif isinstance(names, list) and names:
        out = [str(n) for n in names]
    elif isinstance(doc.get("nc"), int) and doc["nc"] > 0:
        out = [f"class{i}" for i in range(doc["nc"])]
    else:
        raise InputError(f"{where}: names: required (a list or an {{id: name}} mapping)")
    if isinstance(doc.get("nc"), int) and doc["nc"] != len(out):
        raise InputError(f"{where}: nc is {doc['nc']} but names has {len(out)} entries")
    return out


def _resolve(entry: str, root: Path, yaml_dir: Path) -> Path | None:
    p = Path(entry)
    if p.is_absolute():
        return p if p.exists() else None
    candidates = [root / p, yaml_dir / p]
    stripped = entry
    while stripped.startswith("../"):  # Roboflow: '../train/images' next to the data.yaml
        stripped = stripped[3:]
        candidates += [root / stripped, yaml_dir / stripped]
    for c in candidates:
        if c.exists():
            return c.resolve()
    return None


def _list_images(source: Path, where: Path) -> list[Path]:
    if source.is_dir():
        return sorted(p for p in source.rglob("*") if p.suffix.lower() in IMAGE_SUFFIXES)
    if source.suffix.lower() == ".txt":
        out = []
        for line in read_text(source, "an image list (.txt)").splitlines():
            line = line.strip()
            if not line:
                continue
            p = Path(line)
            if not p.is_absolute():
                p = (source.parent / line[2:]) if line.startswith("./") else (source.parent / p)
            out.append(p)
        return out
    if source.suffix.lower() in IMAGE_SUFFIXES:
        return [source]
    raise InputError(f"{where}: {source}: expected a folder of images, a .txt list or a COCO .json")


def label_path(image: Path) -> Path:
    """``.../images/x.jpg`` -> ``.../labels/x.txt`` (the last ``images`` folder); else ``x.txt`` beside it."""
    s = str(image)
    sa, sb = f"{os.sep}images{os.sep}", f"{os.sep}labels{os.sep}"
    if sa in s:
        s = sb.join(s.rsplit(sa, 1))
    return Path(s).with_suffix(".txt")


DROPPED_OUTSIDE = "outside the image (nothing left after clipping to [0, 1])"
DROPPED_FLAT = "of width or height 0"
DROPPED_CLASS = "of a class the mapping leaves out"


def read_yolo_labels(
    path: Path, nc: int, dropped: Counter[str] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Classes (n,) and normalised x1 y1 x2 y2 boxes (n, 4) of a YOLO label file; missing = empty.

    Boxes with no area inside the image are left out, counted in ``dropped`` by reason."""
    if not path.exists():
        return np.zeros(0, dtype=np.int64), np.zeros((0, 4), dtype=np.float32)
    classes, boxes = [], []
    text = read_bytes(path, "a YOLO label file", MAX_TEXT_BYTES).decode("utf-8", errors="replace")
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        try:
            values = [float(v) for v in parts]
        except ValueError:
            raise InputError(
                f"{path}:{lineno}: expected numbers 'class cx cy w h', got {line.strip()!r}"
            ) from None
        cls = values[0]
        if cls != int(cls) or not 0 <= cls < nc:
            raise InputError(f"{path}:{lineno}: class {parts[0]} is not one of 0..{nc - 1}")
        if len(values) == 5:
            cx, cy, w, h = values[1:]
            box = [cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2]
        elif len(values) >= 7 and len(values) % 2 == 1:  # polygon (segmentation label)
            xy = np.array(values[1:]).reshape(-1, 2)
            box = [xy[:, 0].min(), xy[:, 1].min(), xy[:, 0].max(), xy[:, 1].max()]
        else:
            raise InputError(f"{path}:{lineno}: expected 5 values 'class cx cy w h', got {len(values)}")
        flat = box[2] - box[0] <= 0 or box[3] - box[1] <= 0
        box = list(np.clip(box, 0.0, 1.0))
        if box[2] - box[0] <= 0 or box[3] - box[1] <= 0:
            if dropped is not None:
                dropped[DROPPED_FLAT if flat else DROPPED_OUTSIDE] += 1
            continue
        classes.append(int(cls))
        boxes.append(box)
    return np.array(classes, dtype=np.int64), np.array(boxes, dtype=np.float32).reshape(-1, 4)


def load_yolo(yaml_path: Path) -> Dataset:
    yaml_path = Path(yaml_path)
    doc = read_yaml(yaml_path, "a YOLO data.yaml")
    if not isinstance(doc, dict):
        raise InputError(f"{yaml_path}: expected a mapping with path, train, val and names")
    names = _names(doc, yaml_path)
    yaml_dir = yaml_path.resolve().parent
    root = yaml_dir
    if doc.get("path"):
        p = Path(str(doc["path"]))
        p = p if p.is_absolute() else yaml_dir / p
        if p.exists():
            root = p.resolve()
    ds = Dataset(names=names, source=yaml_path)
    if "train" not in doc and "val" not in doc:
        raise InputError(f"{yaml_path}: neither train nor val is given")
    for split in ("train", "val"):
        entries = doc.get(split) or (doc.get("valid") if split == "val" else None)
        if not entries:
            continue
        entries = entries if isinstance(entries, list) else [entries]
        items: list[DatasetItem] = []
        for entry in entries:
            if isinstance(entry, dict):
                items += _remapped_entry(entry, root, yaml_dir, names, yaml_path, ds.dropped[split])
                continue
            source = _resolve(str(entry), root, yaml_dir)
            if source is None:
                raise InputError(f"{yaml_path}: {split}: {entry!r} not found (relative to {root})")
            if source.suffix.lower() == ".json":
                items += _coco_with_names(source, names)
                continue
            for image in _list_images(source, yaml_path):
                classes, boxes = read_yolo_labels(label_path(image), len(names), ds.dropped[split])
                items.append(DatasetItem(image, classes, boxes))
        ds.split(split).extend(items)
    return ds


# --- remapped sources (DoorDetect) ------------------------------------------------------------------

DOORDETECT_CLASSES = {0: "door"}  # 1 handle, 2 cabinet door, 3 refrigerator door: hard negatives
PARTS = ("train", "holdout", "all")


def holdout_fraction(name: str) -> float:
    """A stable number in [0, 1) from a file name (sha1): independent of the folder and of hash seeds."""
    digest = hashlib.sha1(Path(name).name.encode("utf-8")).digest()
    return int.from_bytes(digest[:8], "big") / 2.0**64


def load_remapped(
    root: Path,
    names: list[str],
    classes: dict[int, str],
    holdout: float = 0.2,
    part: str = "train",
    where: Path | None = None,
    domain: str = "",
    dropped: Counter[str] | None = None,
) -> list[DatasetItem]:
    """Images of another dataset with its classes mapped onto ``names``; other classes' boxes dropped.

    ``part``: 'train' (the images whose :func:`holdout_fraction` is >= ``holdout``), 'holdout' (the
    others) or 'all'.
    """
    where = where or root
    if part not in PARTS:
        raise InputError(f"{where}: part: expected one of {', '.join(PARTS)}, got {part!r}")
    if not 0.0 <= holdout < 1.0:
        raise InputError(f"{where}: holdout: expected a fraction in [0, 1), got {holdout}")
    lookup: dict[int, int] = {}
    for src, name in classes.items():
        if str(name) not in names:
            raise InputError(f"{where}: classes: {name!r} is not one of the dataset's names {names}")
        lookup[int(src)] = names.index(str(name))
    root = Path(root)
    images_dir = root / "images" if (root / "images").is_dir() else root
    if not images_dir.is_dir():
        raise InputError(f"{where}: {root}: no such folder")
    items: list[DatasetItem] = []
    for image in sorted(p for p in images_dir.rglob("*") if p.suffix.lower() in IMAGE_SUFFIXES):
        h = holdout_fraction(image.name)
        if (part == "train" and h < holdout) or (part == "holdout" and h >= holdout):
            continue
        src_classes, boxes = read_yolo_labels(label_path(image), 10**6, dropped)
        keep = np.array([int(c) in lookup for c in src_classes], dtype=bool)
        if dropped is not None and not keep.all():
            dropped[DROPPED_CLASS] += int((~keep).sum())
        mapped = np.array([lookup[int(c)] for c in src_classes[keep]], dtype=np.int64)
        items.append(DatasetItem(image, mapped, boxes[keep].reshape(-1, 4), domain or root.name))
    if not items:
        raise InputError(f"{where}: {root}: no images in part {part!r}")
    return items


def load_doordetect(root: Path, holdout: float = 0.2, part: str = "train") -> Dataset:
    """DoorDetect's YOLO folder as a ``door``/``lift``/``stairs`` dataset: its class 0 is our door."""
    items = load_remapped(Path(root), ["door", "lift", "stairs"], DOORDETECT_CLASSES, holdout, part)
    ds = Dataset(names=["door", "lift", "stairs"], source=Path(root))
    ds.val.extend(items) if part == "holdout" else ds.train.extend(items)
    return ds


def _remapped_entry(
    entry: dict, root: Path, yaml_dir: Path, names: list[str], where: Path, dropped: Counter[str]
) -> list[DatasetItem]:
    if "path" not in entry:
        raise InputError(f"{where}: a mapping entry needs 'path' (and optionally classes, holdout, part)")
    source = _resolve(str(entry["path"]), root, yaml_dir)
    if source is None:
        raise InputError(f"{where}: {entry['path']!r} not found (relative to {root})")
    classes = entry.get("classes") or {i: n for i, n in enumerate(names)}
    if not isinstance(classes, dict):
        raise InputError(f"{where}: classes: expected a mapping {{source id: name}}")
    try:
        cmap = {int(k): str(v) for k, v in classes.items()}
        holdout = float(entry.get("holdout", 0.0))
    except (TypeError, ValueError):
        raise InputError(f"{where}: classes keys must be integers and holdout a number") from None
    part = str(entry.get("part", "all"))
    domain = str(entry.get("domain", ""))
    return load_remapped(source, names, cmap, holdout, part, where, domain, dropped)


# --- COCO ------------------------------------------------------------------------------------------


def _find_image_root(json_path: Path, images: list[dict]) -> Path:
    base = json_path.resolve().parent
    if not images:
        return base
    first = str(images[0].get("file_name", ""))
    for root in (base, base / "images", base.parent / "images", base.parent):
        if (root / first).exists():
            return root
    return base


def _coco_items(json_path: Path, doc: dict, cat_index: dict[int, int]) -> list[DatasetItem]:
    images = doc.get("images")
    if not isinstance(images, list):
        raise InputError(f"{json_path}: images: expected a list")
    root = _find_image_root(json_path, images)
    by_image: dict[Any, list[dict]] = {}
    for a in doc.get("annotations") or []:
        if isinstance(a, dict):
            by_image.setdefault(a.get("image_id"), []).append(a)
    items = []
    for im in images:
        if not isinstance(im, dict) or "file_name" not in im:
            raise InputError(f"{json_path}: images: every image needs file_name")
        w, h = float(im.get("width") or 0), float(im.get("height") or 0)
        classes, boxes = [], []
        for a in by_image.get(im.get("id"), []):
            if a.get("iscrowd"):
                continue
            bbox = a.get("bbox")
            if not (isinstance(bbox, list) and len(bbox) == 4):
                raise InputError(f"{json_path}: annotation {a.get('id')}: bbox must be [x, y, w, h]")
            if a.get("category_id") not in cat_index:
                raise InputError(
                    f"{json_path}: annotation {a.get('id')}: unknown category_id {a.get('category_id')}"
                )
            if w <= 0 or h <= 0:
                raise InputError(f"{json_path}: image {im.get('file_name')}: width and height are required")
            x, y, bw, bh = (float(v) for v in bbox)
            if bw <= 0 or bh <= 0:
                continue
            classes.append(cat_index[a["category_id"]])
            boxes.append(np.clip([x / w, y / h, (x + bw) / w, (y + bh) / h], 0.0, 1.0))
        items.append(
            DatasetItem(
                root / str(im["file_name"]),
                np.array(classes, dtype=np.int64),
                np.array(boxes, dtype=np.float32).reshape(-1, 4),
            )
        )
    return items


def _read_json(path: Path) -> dict:
    text = read_text(path, "a COCO detection file (JSON)")
    try:
        doc = parse_json(text, str(path))  # depth, digits bounded; every number finite
    except InputError as exc:
        raise InputError(str(exc).replace(": not valid JSON: ", ": invalid JSON: ", 1)) from None
    if not isinstance(doc, dict) or "images" not in doc or "categories" not in doc:
        raise InputError(f"{path}: not a COCO detection file (needs images, annotations, categories)")
    return doc


def _categories(path: Path, doc: dict) -> tuple[list[str], dict[int, int]]:
    cats = [c for c in doc.get("categories") or [] if isinstance(c, dict) and "id" in c]
    if not cats:
        raise InputError(f"{path}: categories: none")
    used = {a.get("category_id") for a in doc.get("annotations") or [] if isinstance(a, dict)}
    supers = {c.get("supercategory") for c in cats}
    # Roboflow adds the project as an unused category that is every other one's supercategory.
    cats = [c for c in cats if c["id"] in used or c.get("name") not in supers]
    cats.sort(key=lambda c: c["id"])
    return [str(c.get("name", c["id"])) for c in cats], {c["id"]: i for i, c in enumerate(cats)}


def _coco_with_names(path: Path, names: list[str]) -> list[DatasetItem]:
    """All images of a COCO json whose category names are mapped onto ``names`` (by name)."""
    doc = _read_json(path)
    cnames, index = _categories(path, doc)
    missing = sorted(set(cnames) - set(names))
    if missing:
        raise InputError(f"{path}: categories {missing} are not in the dataset's names {names}")
    return _coco_items(path, doc, {cid: names.index(cnames[i]) for cid, i in index.items()})


def load_coco(path: Path, val: Path | None = None) -> Dataset:
    path = Path(path)
    doc = _read_json(path)
    names, index = _categories(path, doc)
    items = _coco_items(path, doc, index)
    ds = Dataset(names=names, source=path)
    if val is None:  # a Roboflow export: train/_annotations.coco.json beside valid/
        parent = path.resolve().parent
        for sibling in ("valid", "val", "validation"):
            candidate = parent.parent / sibling / path.name
            if parent.name == "train" and candidate.exists():
                val = candidate
                break
    if val is not None:
        ds.train, ds.val = items, _coco_with_names(Path(val), names)
    else:
        ds.train = [it for k, it in enumerate(items) if k % 10 != 9]
        ds.val = [it for k, it in enumerate(items) if k % 10 == 9]
    return ds
