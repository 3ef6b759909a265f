"""Synthetic YOLO datasets rendered from site models, with domain randomisation.

``bim-init detector synth`` writes::

    DATASET/
      data.yaml                  path, train, val, names (Ultralytics / YOLO format)
      images/{train,val}/*.jpg   RGB renders
      labels/{train,val}/*.txt   one row per visible feature: class cx cy w h (normalised)
      depth/{train,val}/*.png    16-bit depth in millimetres (0 = no return)
      synth.json                 what was rendered: sites, options, counts per class

Each image is a random robot pose in the circulation area (free space connected to the
features' fronts, away from walls), looking along the corridor or towards a feature, with random
camera height, field of view and pitch (principal point), colours and textures of walls, floor,
ceiling, doors, lifts and stairs, lighting, clutter in front of the walls and walking people
(partial occlusion), posters and signs, exposure, white balance, blur, noise, small roll and
JPEG compression. Image ``i`` depends only on ``(seed, i)``, so any number of workers gives the
same dataset.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np
import yaml

from bimkit.errors import InputError
from bimtools.site.load import load_site
from initcli.core.geometry.raster import distance_to_outside
from initcli.detector import CLASS_NAMES
from initcli.detector.synth.look import random_look
from initcli.detector.synth.render import View, cast_rays, render_view
from initcli.detector.synth.scene import (
    CLUTTER_BOX,
    CLUTTER_PERSON,
    DECOR_CABINET,
    DECOR_POSTER,
    DECOR_SWITCH,
    DECOR_WINDOW,
    Camera,
    Clutter,
    Panels,
    Scene,
    panels_from_rows,
    standard_decorations,
)

__all__ = [
    "CELL",
    "CLASS_COLOURS_BGR",
    "Label",
    "NoCirculation",
    "Placement",
    "Sample",
    "SynthOptions",
    "contact_sheet",
    "dataset_preview",
    "draw_boxes",
    "load_placements",
    "placement_for",
    "render_sample",
    "write_dataset",
]

CELL = 0.1  # m, raster of the free space used to place the camera
SYNTH_MARKERS = ("synth.json",)  # a folder holding one was written by bim-init detector synth
SYNTH_WRITES = ("images", "labels", "depth", "data.yaml", "synth.json")  # what synth writes there


@dataclass
class SynthOptions:
    images: int = 500
    width: int = 320
    height: int = 240
    seed: int = 0
    val_fraction: float = 0.1
    workers: int = 0  # 0: one per CPU core (at most 2 here)
    depth: bool = True
    clearance: float = 0.35  # m from walls
    min_in_image: float = 0.3  # a feature is labelled when this much of it lies in the image,
    min_unoccluded: float = 0.4  # this much of that part is not hidden,
    min_box_h: float = 12.0  # and its box is at least this tall
    min_box_w: float = 4.0  # and wide (pixels)
    shuffle_classes: float = 0.0  # chance that a feature is drawn (and labelled) as a random class
    sites: list[str] = field(default_factory=list)


@dataclass
class Label:
    class_index: int
    box: tuple[float, float, float, float]  # u1, v1, u2, v2 pixels


@dataclass
class Sample:
    image_rgb: np.ndarray
    depth: np.ndarray
    labels: list[Label]
    pose: tuple[float, float, float]
    site: str


class NoCirculation(InputError):
    """A storey with no closed free space in front of its features (open to the outside, or too narrow)."""


@dataclass
class Placement:
    """Where a camera may stand in one scene: the corridor cells, away from walls."""

    scene: Scene
    cells: np.ndarray  # (N, 2) world xy of usable cells
    site: str


def placement_for(scene: Scene, site: str, clearance: float = 0.35) -> Placement:
    """Free space connected to the features' fronts (the circulation area), eroded by ``clearance``."""
    w = scene.walls
    if len(w) == 0:
        raise InputError(f"{site}: storey {scene.name!r} has no walls")
    lo = np.minimum(w[:, 0:2], w[:, 2:4]).min(axis=0) - 1.0
    hi = np.maximum(w[:, 0:2], w[:, 2:4]).max(axis=0) + 1.0
    shape = (int(math.ceil((hi[1] - lo[1]) / CELL)), int(math.ceil((hi[0] - lo[0]) / CELL)))
    solid = np.zeros(shape, dtype=np.uint8)

    def px(xy: np.ndarray) -> np.ndarray:
        return np.round((np.asarray(xy) - lo) / CELL).astype(np.int32)

    if scene.footprint is not None:
        polys = list(scene.footprint.geoms) if hasattr(scene.footprint, "geoms") else [scene.footprint]
        for p in polys:
            part = np.zeros(shape, dtype=np.uint8)
            cv2.fillPoly(part, [px(p.exterior.coords)], 1)
            for hole in p.interiors:
                cv2.fillPoly(part, [px(hole.coords)], 0)
            solid |= part
    for s in w:  # also draws two-sided wall lines
        cv2.line(solid, tuple(px(s[0:2])), tuple(px(s[2:4])), 1, 1)
    free = solid == 0
    _, labels = cv2.connectedComponents(free.astype(np.uint8), connectivity=4)  # 0: not free
    border = set(np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]])))
    keep = set()
    for f in scene.features:
        q = px(np.array([f.x, f.y]) + 0.6 * np.array(f.normal))
        if 0 <= q[1] < shape[0] and 0 <= q[0] < shape[1] and labels[q[1], q[0]] > 0:
            keep.add(int(labels[q[1], q[0]]))
    keep -= border
    if not keep:
        raise NoCirculation(
            f"{site}: storey {scene.name!r}: no enclosed free space in front of any feature "
            "(its space is open to the outside)"
        )
    region = np.isin(labels, sorted(keep))
    dist = distance_to_outside(region) * CELL
    rows, cols = np.nonzero(region & (dist >= clearance))
    if len(rows) == 0:
        raise NoCirculation(
            f"{site}: storey {scene.name!r}: the circulation area is narrower than {2 * clearance:.2f} m"
        )
    cells = np.column_stack([lo[0] + cols * CELL, lo[1] + rows * CELL])
    return Placement(scene, cells, site)


def load_placements(
    sites: Sequence[str | Path], clearance: float = 0.35, warn: Callable[[str], None] | None = None
) -> list[Placement]:
    """The camera placements of every storey with features; storeys without a closed circulation area
    (open to the outside) are skipped with a ``warn`` message. Fails when no storey is left."""
    out = []
    skipped: list[str] = []
    for s in sites:
        site = load_site(Path(s), with_maps=False)
        for storey in site.storeys.values():
            scene = Scene.from_storey(storey, decorate=False)
            if not scene.features:
                continue
            try:
                out.append(placement_for(scene, str(s), clearance))
            except NoCirculation as exc:
                skipped.append(str(exc))
                if warn is not None:
                    warn(f"skipped {exc}")
    if not out:
        reasons = f" ({'; '.join(skipped)})" if skipped else ""
        raise InputError(
            f"{', '.join(map(str, sites))}: no storey with doors, lifts or stairs to render{reasons}"
        )
    return out


def _random_pose(rng: np.random.Generator, pl: Placement) -> tuple[float, float, float]:
    p = pl.cells[rng.integers(len(pl.cells))] + rng.uniform(-CELL / 2, CELL / 2, 2)
    feats = pl.scene.feature_panels
    if len(feats) and rng.random() < 0.7:
        rel = p - feats.centre
        dist = np.hypot(rel[:, 0], rel[:, 1])
        front = np.einsum("ij,ij->i", rel, feats.normal) > 0.15 * dist
        ok = np.flatnonzero(front & (dist > 0.8) & (dist < 14.0))
        if len(ok):  # every class equally likely to be looked at, whatever the counts in the model
            kinds = feats.kind[ok]
            present = np.unique(kinds)
            pick = ok[kinds == present[rng.integers(len(present))]]
            k = pick[rng.integers(len(pick))]
            d = feats.centre[k] - p
            return float(p[0]), float(p[1]), math.atan2(d[1], d[0]) + float(rng.normal(0.0, 0.35))
    yaw = float(rng.uniform(-math.pi, math.pi))
    if rng.random() < 0.8:  # mostly look along the corridor rather than at the nearest wall
        for _ in range(6):
            d = np.array([[math.cos(yaw), math.sin(yaw)]])
            t, _, _ = cast_rays(p, d, pl.scene.walls)
            if t.min() > 2.0:
                break
            yaw = float(rng.uniform(-math.pi, math.pi))
    return float(p[0]), float(p[1]), yaw


def _random_decorations(rng: np.random.Generator, scene: Scene, cam: np.ndarray) -> Panels:
    """Lift call panels, exit signs and distractors (posters, cabinets, windows, switches) near the camera."""
    base = standard_decorations(scene, rng)
    w = scene.walls
    if len(w) == 0:
        return base
    mid = (w[:, 0:2] + w[:, 2:4]) / 2
    e = w[:, 2:4] - w[:, 0:2]
    length = np.hypot(e[:, 0], e[:, 1])
    near = np.flatnonzero((np.hypot(*(mid - cam).T) < 14.0) & (length > 0.6))
    rows = []
    fp = scene.feature_panels
    for _ in range(int(rng.integers(2, 12)) if len(near) else 0):
        k = near[rng.integers(len(near))]
        t = e[k] / length[k]
        n = np.array([t[1], -t[0]])
        kind = int(rng.choice([DECOR_POSTER, DECOR_POSTER, DECOR_CABINET, DECOR_WINDOW, DECOR_SWITCH]))
        if kind == DECOR_POSTER:
            hw, bottom, height = rng.uniform(0.15, 0.6), rng.uniform(0.9, 1.5), rng.uniform(0.3, 0.9)
            rgb = rng.uniform(20, 240, 3)
        elif kind == DECOR_CABINET:
            hw, bottom, height = rng.uniform(0.25, 0.45), rng.uniform(0.2, 0.9), rng.uniform(0.5, 0.9)
            rgb = np.array([200.0, 30.0, 30.0]) if rng.random() < 0.6 else rng.uniform(60, 220, 3)
        elif kind == DECOR_WINDOW:
            hw, bottom, height = rng.uniform(0.4, 1.2), rng.uniform(0.9, 1.3), rng.uniform(0.6, 1.2)
            rgb = rng.uniform(60, 240, 3)
        else:
            hw, bottom, height = 0.045, rng.uniform(1.0, 1.4), 0.09
            rgb = rng.uniform(180, 250, 3)
        if length[k] < 2 * hw + 0.1:
            continue
        s = rng.uniform(hw + 0.05, length[k] - hw - 0.05)
        c = w[k, 0:2] + t * s
        if len(fp):  # keep off the features on this wall
            rel = c - fp.centre
            along = np.abs(np.einsum("ij,ij->i", rel, fp.tangent))
            across = np.abs(np.einsum("ij,ij->i", rel, fp.normal))
            if np.any((across < 0.3) & (along < fp.half_width + hw + 0.15)):
                continue
        rows.append((c, n, hw, bottom, bottom + height, kind, tuple(rgb)))
    return base.concat(panels_from_rows(rows))


def _random_clutter(rng: np.random.Generator, scene: Scene, pl: Placement, cam: np.ndarray) -> Clutter:
    """Material stacks against the walls and people in the corridor, near the camera but not on it."""
    boxes: list[tuple[float, float, float, float, float]] = []
    tops: list[float] = []
    kinds: list[int] = []
    colours: list[np.ndarray] = []
    w = scene.walls
    mid = (w[:, 0:2] + w[:, 2:4]) / 2
    e = w[:, 2:4] - w[:, 0:2]
    length = np.hypot(e[:, 0], e[:, 1])
    near = np.flatnonzero((np.hypot(*(mid - cam).T) < 10.0) & (length > 0.8))
    for _ in range(int(rng.poisson(2.5)) if len(near) else 0):
        k = near[rng.integers(len(near))]
        t = e[k] / length[k]
        n = np.array([t[1], -t[0]])
        hl, hw = rng.uniform(0.15, 0.6), rng.uniform(0.12, 0.4)
        c = w[k, 0:2] + t * rng.uniform(0, length[k]) + n * (hw + rng.uniform(0.02, 0.5))
        yaw = math.atan2(t[1], t[0]) + rng.normal(0, 0.15)
        boxes.append((float(c[0]), float(c[1]), hl, hw, yaw))
        tops.append(float(rng.uniform(0.3, 1.9)))
        kinds.append(CLUTTER_BOX)
        colours.append(rng.uniform(40, 230, 3))
    for _ in range(int(rng.poisson(0.5))):
        c = pl.cells[rng.integers(len(pl.cells))]
        if not 1.5 < np.hypot(*(c - cam)) < 12.0:
            continue
        boxes.append((float(c[0]), float(c[1]), 0.2, 0.14, float(rng.uniform(-math.pi, math.pi))))
        tops.append(float(rng.uniform(1.55, 1.9)))
        kinds.append(CLUTTER_PERSON)
        colours.append(rng.uniform(40, 200, 3))
    keep = [i for i, b in enumerate(boxes) if np.hypot(b[0] - cam[0], b[1] - cam[1]) > b[2] + b[3] + 0.3]
    return Clutter.from_boxes(
        [boxes[i] for i in keep],
        [tops[i] for i in keep],
        [kinds[i] for i in keep],
        np.array([colours[i] for i in keep]).reshape(-1, 3),
    )


def _postprocess(rng: np.random.Generator, rgb: np.ndarray) -> np.ndarray:
    """Exposure, white balance, gamma, vignetting, blur, sensor noise."""
    img: np.ndarray = rgb.astype(np.float32) / 255.0
    img *= rng.uniform(0.6, 1.4) * rng.uniform(0.9, 1.1, 3).astype(np.float32)
    img = np.clip(img, 0, 1) ** rng.uniform(0.75, 1.35)
    h, w = img.shape[:2]
    if rng.random() < 0.5:
        yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
        r2 = ((xx - w / 2) / (w / 2)) ** 2 + ((yy - h / 2) / (h / 2)) ** 2
        img *= (1.0 - rng.uniform(0.1, 0.4) * r2 / 2.0)[..., None]
    r = rng.random()
    if r < 0.3:
        img = cv2.GaussianBlur(img, (0, 0), rng.uniform(0.3, 1.2))
    elif r < 0.45:
        k = int(rng.integers(3, 8))
        kernel = np.zeros((k, k), np.float32)
        kernel[k // 2, :] = 1.0 / k
        img = cv2.filter2D(img, -1, kernel)
    img = img * 255.0 + rng.normal(0.0, rng.uniform(0.0, 8.0), img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def _labels_from_view(view: View, ids: np.ndarray, opts: SynthOptions, scene: Scene) -> list[Label]:
    """Labels for the features visible enough (see :class:`SynthOptions`), boxes from the id buffer."""
    out = []
    for f in view.features:
        u1, v1, u2, v2 = f.box
        big = (v2 - v1) >= 0.3 * opts.height and (u2 - u1) >= 12  # a close element cut by the image edge
        if f.in_image_fraction < opts.min_in_image and not big:
            continue
        if f.visible_fraction < opts.min_unoccluded * f.in_image_fraction:
            continue
        mask = ids == f.index
        rows = np.flatnonzero(mask.any(axis=1))
        cols = np.flatnonzero(mask.any(axis=0))
        if len(rows) == 0:
            continue
        box = (float(cols[0]), float(rows[0]), float(cols[-1] + 1), float(rows[-1] + 1))
        if box[3] - box[1] < opts.min_box_h or box[2] - box[0] < opts.min_box_w:
            continue
        out.append(Label(scene.features[f.index].class_index, box))
    return out


def _shuffle_classes(rng: np.random.Generator, scene: Scene, p: float) -> Scene:
    """Each feature drawn as a random class with probability ``p`` (labelled as drawn): lifts and
    stairs also appear where the training layouts have doors (corridor ends, far away, frontal)."""
    n_cls = len(scene.class_names)
    feats = []
    for f in scene.features:
        if rng.random() < p:
            k = int(rng.integers(n_cls))
            f = replace(f, class_index=k, class_name=scene.class_names[k])
        feats.append(f)
    return replace(scene, features=feats)


def render_sample(placements: Sequence[Placement], index: int, opts: SynthOptions) -> Sample:
    """Image ``index`` of a dataset: a function of ``(opts.seed, index)`` only."""
    rng = np.random.default_rng([opts.seed, index])
    pl = placements[int(rng.integers(len(placements)))]
    pose = _random_pose(rng, pl)
    cam_xy = np.array(pose[:2])
    hfov = rng.uniform(75.0, 100.0)
    camera = Camera.from_fov(opts.width, opts.height, hfov, float(rng.uniform(0.5, 1.5)))
    pitch_px = rng.normal(0.0, 0.06) * opts.height
    camera = Camera(
        camera.fx,
        camera.fx * rng.uniform(0.97, 1.03),
        camera.cx,
        camera.cy + pitch_px,
        camera.width,
        camera.height,
        camera.z,
        40.0,
    )
    base = _shuffle_classes(rng, pl.scene, opts.shuffle_classes) if opts.shuffle_classes > 0 else pl.scene
    scene = base.with_extras(
        decorations=_random_decorations(rng, base, cam_xy),
        clutter=_random_clutter(rng, base, pl, cam_xy),
        ceiling=float(rng.uniform(2.6, 3.5)),
    )
    look = random_look(rng, scene.feature_panels.kind, scene.class_names)
    view = render_view(scene, pose, camera, look)
    rgb = _postprocess(rng, view.rgb)
    depth, ids = view.depth, view.ids
    if rng.random() < 0.3:  # a little roll: the robot is not perfectly level
        angle = float(rng.uniform(-3.0, 3.0))
        m = cv2.getRotationMatrix2D((opts.width / 2, opts.height / 2), angle, 1.0)
        size = (opts.width, opts.height)
        rgb = cv2.warpAffine(rgb, m, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        depth = cv2.warpAffine(depth, m, size, flags=cv2.INTER_NEAREST, borderValue=0)
        ids = cv2.warpAffine(ids.astype(np.float32), m, size, flags=cv2.INTER_NEAREST, borderValue=-1).astype(
            np.int16
        )
    return Sample(rgb, depth, _labels_from_view(view, ids, opts, scene), pose, pl.site)


# --- dataset writer ------------------------------------------------------------------------------

_WORKER: dict = {}


def _init_worker(sites: Sequence[str | Path], opts: SynthOptions) -> None:
    cv2.setNumThreads(1)
    _WORKER["placements"] = load_placements(sites, opts.clearance)
    _WORKER["opts"] = opts


def _write_range(args: tuple[Path, list[tuple[int, str]]]) -> list[tuple[int, str, list[int]]]:
    root, jobs = args
    placements, opts = _WORKER["placements"], _WORKER["opts"]
    done = []
    for i, split in jobs:
        sample = render_sample(placements, i, opts)
        name = f"{i:06d}"
        rng = np.random.default_rng([opts.seed, i, 7])
        bgr = cv2.cvtColor(sample.image_rgb, cv2.COLOR_RGB2BGR)
        cv2.imwrite(
            str(root / "images" / split / f"{name}.jpg"),
            bgr,
            [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(70, 96))],
        )
        if opts.depth:
            mm = np.clip(sample.depth * 1000.0, 0, 65535).astype(np.uint16)
            cv2.imwrite(str(root / "depth" / split / f"{name}.png"), mm)
        lines = []
        for lab in sample.labels:
            u1, v1, u2, v2 = lab.box
            lines.append(
                f"{lab.class_index} {(u1 + u2) / 2 / opts.width:.6f} {(v1 + v2) / 2 / opts.height:.6f} "
                f"{(u2 - u1) / opts.width:.6f} {(v2 - v1) / opts.height:.6f}"
            )
        (root / "labels" / split / f"{name}.txt").write_text("".join(line + "\n" for line in lines))
        done.append((i, split, [lab.class_index for lab in sample.labels]))
    return done


def write_dataset(
    sites: Sequence[str | Path],
    out: Path,
    opts: SynthOptions,
    progress: Callable[[int], None] | None = None,
    warn: Callable[[str], None] | None = None,
    final: Path | None = None,
) -> dict:
    """Render ``opts.images`` images into a YOLO dataset at ``out``; returns the synth.json document.
    ``final``: where the dataset will be once ``out`` (a staging folder) is moved there."""
    if opts.images < 1:
        raise InputError(f"--images: expected at least 1, got {opts.images}")
    if not 0.0 <= opts.val_fraction <= 1.0:
        raise InputError(f"--val-fraction: expected a number in [0, 1], got {opts.val_fraction}")
    if not 0.0 <= opts.shuffle_classes <= 1.0:
        raise InputError(f"--shuffle-classes: expected a number in [0, 1], got {opts.shuffle_classes}")
    sites = [str(s) for s in sites]
    load_placements(sites, opts.clearance, warn)  # fail early, in this process, on a bad site
    out = Path(out)
    for split in ("train", "val"):
        for sub in ("images", "labels") + (("depth",) if opts.depth else ()):
            (out / sub / split).mkdir(parents=True, exist_ok=True)
    n_val = int(round(opts.images * opts.val_fraction))
    splits = ["val" if i < n_val else "train" for i in range(opts.images)]
    jobs = list(enumerate(splits))
    workers = opts.workers or min(2, os.cpu_count() or 1)
    chunks = [jobs[k : k + 16] for k in range(0, len(jobs), 16)]
    counts = {"train": [0] * len(CLASS_NAMES), "val": [0] * len(CLASS_NAMES)}
    images = {"train": 0, "val": 0}
    empty = 0

    def collect(done: list[tuple[int, str, list[int]]]) -> None:
        nonlocal empty
        for _i, split, classes in done:
            images[split] += 1
            empty += not classes
            for c in classes:
                counts[split][c] += 1
            if progress:
                progress(1)

    if workers <= 1:
        _init_worker(sites, opts)
        for chunk in chunks:
            collect(_write_range((out, chunk)))
    else:
        with ProcessPoolExecutor(workers, initializer=_init_worker, initargs=(sites, opts)) as pool:
            for done in pool.map(_write_range, [(out, c) for c in chunks]):
                collect(done)
    data = {
        "path": str(Path(final or out).resolve()),
        "train": "images/train",
        "val": "images/val",
        "names": list(CLASS_NAMES),
    }
    (out / "data.yaml").write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")
    doc = {
        "format": "bim-init.synth/1",
        "sites": sites,
        "options": {k: v for k, v in asdict(opts).items() if k != "sites"},
        "images": images,
        "background_images": empty,
        "instances": {split: dict(zip(CLASS_NAMES, c, strict=True)) for split, c in counts.items()},
        "names": list(CLASS_NAMES),
    }
    (out / "synth.json").write_text(json.dumps(doc, indent=2), encoding="utf-8")
    return doc


# --- contact sheet -------------------------------------------------------------------------------

CLASS_COLOURS_BGR = [
    (40, 40, 230),
    (230, 140, 30),
    (40, 180, 40),
    (200, 60, 200),
    (0, 200, 230),
    (120, 120, 120),
]


def draw_boxes(
    image_bgr: np.ndarray,
    boxes: Sequence[tuple[int, tuple[float, float, float, float], str]],
    thickness: int = 1,
) -> np.ndarray:
    """Draw ``(class_index, (u1, v1, u2, v2), text)`` boxes on a copy of a BGR image."""
    out = image_bgr.copy()
    for cls, (u1, v1, u2, v2), text in boxes:
        colour = CLASS_COLOURS_BGR[cls % len(CLASS_COLOURS_BGR)]
        p1, p2 = (int(round(u1)), int(round(v1))), (int(round(u2)) - 1, int(round(v2)) - 1)
        cv2.rectangle(out, p1, p2, colour, thickness)
        if text:
            (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.35, 1)
            y = max(p1[1], th + 2)
            cv2.rectangle(out, (p1[0], y - th - 2), (p1[0] + tw + 2, y), colour, -1)
            cv2.putText(
                out, text, (p1[0] + 1, y - 2), cv2.FONT_HERSHEY_SIMPLEX, 0.35, (255, 255, 255), 1, cv2.LINE_AA
            )
    return out


def contact_sheet(tiles: Sequence[np.ndarray], columns: int = 6) -> np.ndarray:
    """Tile BGR images (resized to the first one's size) into one sheet."""
    if not tiles:
        raise InputError("contact sheet: no images")
    h, w = tiles[0].shape[:2]
    rows = math.ceil(len(tiles) / columns)
    sheet = np.full((rows * (h + 2), columns * (w + 2), 3), 255, dtype=np.uint8)
    for k, t in enumerate(tiles):
        t = cv2.resize(t, (w, h)) if t.shape[:2] != (h, w) else t
        r, c = divmod(k, columns)
        sheet[r * (h + 2) : r * (h + 2) + h, c * (w + 2) : c * (w + 2) + w] = t
    return sheet


def dataset_preview(root: Path, out_png: Path, count: int = 24, columns: int = 6) -> None:
    """A contact sheet of the first images of a written dataset with their label boxes."""
    from initcli.detector.datasets import load_dataset

    ds = load_dataset(root / "data.yaml")
    items = (ds.val + ds.train)[:count]
    tiles = []
    for item in items:
        img = cv2.imread(str(item.image))
        if img is None:
            continue
        h, w = img.shape[:2]
        boxes = [
            (int(c), (b[0] * w, b[1] * h, b[2] * w, b[3] * h), ds.names[int(c)])
            for c, b in zip(item.classes, item.boxes, strict=True)
        ]
        tiles.append(draw_boxes(img, boxes))
    if not cv2.imwrite(str(out_png), contact_sheet(tiles, columns)):
        raise InputError(f"{out_png}: cannot write the preview image")
