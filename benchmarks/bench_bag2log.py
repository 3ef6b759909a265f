"""Benchmark of ``bim-init bag2log`` (a benchmark, not a timed test): messages/s and images/s.

Two synthetic recordings written with rosbags' MCAP writer (``benchmarks/_recordings.py``, the
tests' recordings too): the robot's own detections (``vision_msgs/Detection2DArray`` + aligned
32FC1 depth, 20 Hz odometry, 5 Hz scans), and raw 640x480 colour images run through the bundled
ONNX detector (2 threads).

Usage: ``.venv/bin/python benchmarks/bench_bag2log.py [--quick] [--seconds 60] [--image-seconds 20]``
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _common import parse_args
from _recordings import make_recording, write

from initcli.ros.bag_reader import bag_to_records


def bench(kind: str, seconds: float, tmp: Path) -> None:
    rec = make_recording(perception=kind, duration=seconds)
    bag = write(tmp, rec, "mcap", name=kind)
    started = time.perf_counter()
    _, stats = bag_to_records(bag)
    wall = time.perf_counter() - started
    size = bag.stat().st_size / 1e6
    print(
        f"{kind:10s} {seconds:5.0f} s recorded, {size:6.1f} MB, {stats.messages:6d} messages, "
        f"{stats.images:4d} images: {wall:6.2f} s -> {stats.messages / wall:8.0f} messages/s, "
        f"{stats.images / wall:6.1f} images/s"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="length of the detections recording")
    parser.add_argument("--image-seconds", type=float, default=20.0, help="length of the image recording")
    args = parse_args(parser, quick={"seconds": 10.0, "image_seconds": 4.0})
    with tempfile.TemporaryDirectory() as tmp:
        bench("detections", args.seconds, Path(tmp))
        bench("image", args.image_seconds, Path(tmp))


if __name__ == "__main__":
    main()
