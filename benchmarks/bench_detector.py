"""Benchmark of the detector pieces (a benchmark, not a timed test).

Sections (``--only`` picks some):

- ``render``: :func:`render_view` frames/s at 320x240 (and 640x480) on block_a, default look, one
  core (numpy). Goal: >= 20 frames/s at 320x240.
- ``synth``: dataset images/s of ``bim-init detector synth`` (render + randomisation + JPEG/PNG writes).
- ``inference``: end-to-end images/s of :class:`Detector` -- letterbox, onnxruntime with
  ``intra_op_num_threads=2``, ``inter_op_num_threads=1`` and idle spinning off, decoding and NMS --
  on rendered 320x240 frames with the 320x320 model. Goal: >= 30 images/s on 2 cores.
- ``accuracy``: mAP@0.5 per class on ``--val-images`` renders of block_b (a layout the default
  model never saw), through the runtime.

Usage: ``.venv/bin/python benchmarks/bench_detector.py [--quick] [--model default] [--only render,inference]
[--json]``
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import SAMPLES, parse_args

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.site.load import load_site
from initcli.detector.synth.dataset import SynthOptions, load_placements, write_dataset
from initcli.detector.synth.render import render_view
from initcli.detector.synth.scene import Camera, Scene


def make_site(name: str, root: Path) -> Path:
    out = root / name
    if not out.exists():
        write_site(out, extract_site(SAMPLES / f"{name}.ifc"), preview=False)
    return out


def poses(site: Path, n: int, seed: int = 0) -> tuple[Scene, list[tuple[float, float, float]]]:
    placement = load_placements([site])[0]
    rng = np.random.default_rng(seed)
    cells = placement.cells[rng.integers(len(placement.cells), size=n)]
    yaws = rng.uniform(-math.pi, math.pi, n)
    return Scene.from_storey(next(iter(load_site(site).storeys.values()))), [
        (float(c[0]), float(c[1]), float(y)) for c, y in zip(cells, yaws, strict=True)
    ]


def bench_render(site: Path, frames: int) -> dict:
    out = {}
    for w, h in ((320, 240), (640, 480)):
        scene, ps = poses(site, frames)
        camera = Camera.from_fov(w, h, 90.0, z=1.0)
        render_view(scene, ps[0], camera)
        t = time.perf_counter()
        for p in ps:
            render_view(scene, p, camera)
        dt = time.perf_counter() - t
        out[f"{w}x{h}"] = {"frames": frames, "fps": round(frames / dt, 1), "ms": round(1000 * dt / frames, 2)}
    return out


def bench_synth(site: Path, images: int, root: Path) -> dict:
    res = {}
    for workers in (1, 2):
        t = time.perf_counter()
        write_dataset([site], root / f"synth{workers}", SynthOptions(images=images, seed=1, workers=workers))
        dt = time.perf_counter() - t
        res[f"workers={workers}"] = {"images": images, "images_per_s": round(images / dt, 1)}
    return res


def bench_inference(model: str, site: Path, frames: int, threads: int) -> dict:
    from initcli.detector.runtime import Detector

    det = Detector(model, conf=0.25, threads=threads)
    scene, ps = poses(site, frames, seed=1)
    camera = Camera.from_fov(320, 240, 90.0, z=1.0)
    images = [render_view(scene, p, camera).bgr for p in ps]
    for img in images[:5]:
        det.detect(img)
    t = time.perf_counter()
    n_det = 0
    for img in images:
        n_det += len(det.detect(img))
    dt = time.perf_counter() - t
    x, _ = det.prepare(images[0])
    t = time.perf_counter()
    for _ in range(frames):
        det._run(x)
    net = time.perf_counter() - t
    return {
        "model": str(det.path),
        "input": list(det.input_size),
        "threads": threads,
        "images": frames,
        "images_per_s": round(frames / dt, 1),
        "ms_end_to_end": round(1000 * dt / frames, 2),
        "ms_network_only": round(1000 * net / frames, 2),
        "detections": n_det,
    }


def bench_accuracy(model: str, site: Path, images: int, root: Path) -> dict:
    from initcli.detector.evaluate import evaluate_model

    ds = root / "val_b"
    write_dataset([site], ds, SynthOptions(images=images, seed=2, val_fraction=1.0))
    return evaluate_model(model, ds / "data.yaml").to_dict()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="default", help="ONNX model ('default' = the shipped one)")
    ap.add_argument("--only", default="render,synth,inference,accuracy")
    ap.add_argument("--frames", type=int, default=200)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--val-images", type=int, default=500)
    ap.add_argument("--json", action="store_true")
    args = parse_args(ap, quick={"frames": 10, "val_images": 20})
    only = set(args.only.split(","))
    results: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        site_a = make_site("block_a", root)
        if "render" in only:
            results["render"] = bench_render(site_a, args.frames)
        if "synth" in only:
            results["synth"] = bench_synth(site_a, args.frames, root)
        if "inference" in only:
            results["inference"] = bench_inference(args.model, site_a, args.frames, args.threads)
        if "accuracy" in only:
            site_b = make_site("block_b", root)
            results["accuracy"] = bench_accuracy(args.model, site_b, args.val_images, root)
    if args.json:
        print(json.dumps(results, indent=2))
        return
    for section, value in results.items():
        print(f"== {section}")
        print(json.dumps(value, indent=2))
    sys.stdout.flush()


if __name__ == "__main__":
    main()
