"""Hostile cases: documents that would hang, exhaust memory or crash a reader; devices and pipes;
NaN and infinity in logs, bags and summaries."""

from __future__ import annotations

from pathlib import Path

from tests.hostile.harness import Case
from tests.hostile.workspace import (
    BILLION_LAUGHS,
    bag_with,
    config_plus,
    depthless_log,
    fifo,
    huge_score,
    inf_transform,
    log_lines,
    manifest,
    map_yaml,
    nan_camera_k,
    nan_depth,
    nan_detection,
    nan_odometry,
    site_copy,
    sparse,
    storey_elevation,
    summary_with,
    text,
)

BOMB = r"its aliases would expand it by \d+ nodes"
DEVICE = r"/dev/zero: is a device"
RUN = ("bim-init", "run", "--config")
MATCH = ("bim-init", "match")
DEEP = "[" * 100_000 + "]" * 100_000
DIGITS = "9" * 5000


def _eval_plus(name: str, extra: str):
    def setup(folder: Path) -> None:
        (folder / name).write_text((folder / "eval.yaml").read_text() + extra)

    return setup


def _map_text(extra: str):
    def edit(site: Path) -> None:
        path = next(site.glob("map_*.yaml"))
        path.write_text(path.read_text() + extra + "\n")

    return edit


def _pgm(content: bytes):
    def edit(site: Path) -> None:
        next(site.glob("map_*.pgm")).write_bytes(content)

    return edit


def _walls(content: str):
    def edit(site: Path) -> None:
        (site / "walls.geojson").write_text(content)

    return edit


def _features_nan(site: Path) -> None:
    lines = (site / "features.csv").read_text().splitlines()
    cells = lines[1].split(",")
    cells[2] = "nan"
    lines[1] = ",".join(cells)
    (site / "features.csv").write_text("\n".join(lines) + "\n")


def _set_map_yaml(value: object):
    def change(doc: dict) -> None:
        doc["storeys"][0]["map_yaml"] = value

    return change


YAML = [
    Case(
        "billion laughs in a site config",
        (*RUN, "bomb.yaml"),
        BOMB,
        config_plus("bomb.yaml", BILLION_LAUGHS + "\n"),
    ),
    Case(
        "billion laughs in an eval config",
        ("bim-init", "eval", "--config", "bomb.yaml"),
        BOMB,
        _eval_plus("bomb.yaml", BILLION_LAUGHS + "\n"),
    ),
    Case(
        "billion laughs in a categories file",
        ("bim-extract", "model.ifc", "--categories", "bomb.yaml", "-o", "out"),
        BOMB,
        text("bomb.yaml", BILLION_LAUGHS + "\n"),
    ),
    Case(
        "billion laughs in survey --config",
        ("bim-init", "survey", "site", "--config", "bomb.yaml", "--out", "sv"),
        BOMB,
        config_plus("bomb.yaml", BILLION_LAUGHS + "\n"),
    ),
    Case(
        "billion laughs in a map yaml",
        ("bim-init", "survey", "s2", "--out", "sv"),
        BOMB,
        site_copy("s2", _map_text(BILLION_LAUGHS)),
    ),
    Case(
        "recursive alias",
        (*RUN, "rec.yaml"),
        r"a recursive alias",
        config_plus("rec.yaml", "loop: &a [1, *a]\n"),
    ),
    Case(
        "two site: keys",
        (*RUN, "dup.yaml"),
        r"dup.yaml:3: duplicate key 'site'",
        text("dup.yaml", "site:\n  path: site\nsite:\n  path: model.ifc\n"),
    ),
    Case(
        "duplicate key in a section",
        (*RUN, "dup.yaml"),
        r"duplicate key 'fx'",
        config_plus("dup.yaml", "camera:\n  fx: 300\n  fx: 400\n"),
    ),
    Case(
        "duplicate key in an eval config",
        ("bim-init", "eval", "--config", "dup.yaml"),
        r"duplicate key 'starts'",
        _eval_plus("dup.yaml", "starts: 2\n"),
    ),
    Case(
        "duplicate key in a categories file",
        ("bim-extract", "model.ifc", "--categories", "dup.yaml", "-o", "out"),
        r"duplicate key 'version'",
        text("dup.yaml", "version: 1\nversion: 2\n"),
    ),
    Case(
        "a 5000-digit seed",
        (*RUN, "big.yaml"),
        r"an integer of 5000 digits",
        config_plus("big.yaml", f"sim:\n  seed: {DIGITS}\n"),
    ),
    Case(
        "a 5000-digit starts",
        ("bim-init", "eval", "--config", "big.yaml"),
        r"an integer of 5000 digits",
        text("big.yaml", f"sites:\n  - config: site.yaml\nstarts: {DIGITS}\n"),
    ),
    Case(
        "YAML nested 100000 deep",
        (*RUN, "deep.yaml"),
        r"nested deeper than 64 levels",
        config_plus("deep.yaml", "x: " + "[" * 100_000 + "\n"),
    ),
    Case(
        "YAML nested 100 deep",
        (*RUN, "deep.yaml"),
        r"nested deeper than 64 levels",
        config_plus("deep.yaml", "x: " + "[" * 100 + "]" * 100 + "\n"),
    ),
    Case(
        "config 70 MiB",
        (*RUN, "huge.yaml"),
        r"above the limit of 64 MiB",
        sparse("huge.yaml", 70 << 20, b"site:\n"),
    ),
]

MAPS = [
    Case(
        "map resolution 0",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"resolution: 0 must be > 0",
        site_copy("s2", map_yaml(resolution=0)),
    ),
    Case(
        "map resolution -1 (run)",
        (*RUN, "s2.yaml", "--out", "r"),
        r"resolution: -1 must be > 0",
        lambda f: (site_copy("s2", map_yaml(resolution=-1))(f), text("s2.yaml", "site:\n  path: s2\n")(f)),
    ),
    Case(
        "map resolution nan",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"resolution: nan is not a finite number",
        site_copy("s2", map_yaml(resolution=float("nan"))),
    ),
    Case(
        "map origin of two numbers",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"origin: expected \[x, y, yaw\]",
        site_copy("s2", map_yaml(origin=[0, 0])),
    ),
    Case(
        "map origin 1e300",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"origin.0: .* is above the maximum",
        site_copy("s2", map_yaml(origin=[1e300, 0, 0])),
    ),
    Case(
        "map negate 2",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"negate: expected 0 or 1",
        site_copy("s2", map_yaml(negate=2)),
    ),
    Case(
        "map free_thresh 5",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"free_thresh: 5 is above the maximum 1",
        site_copy("s2", map_yaml(free_thresh=5)),
    ),
    Case(
        "map image /dev/zero",
        ("bim-init", "survey", "s2", "--out", "sv"),
        DEVICE,
        site_copy("s2", map_yaml(image="/dev/zero")),
    ),
    Case(
        "map image a list",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"image: expected a file name",
        site_copy("s2", map_yaml(image=[1, 2])),
    ),
    Case(
        "map PGM header junk",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"PGM header",
        site_copy("s2", _pgm(b"P5\nabc 10\n255\n" + b"\0" * 10)),
    ),
    Case(
        "map PGM of 0 pixels",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"PGM of 0 x 0 pixels",
        site_copy("s2", _pgm(b"P5\n0 0\n255\n")),
    ),
    Case(
        "map PGM 10^10 digits wide",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"PGM header",
        site_copy("s2", _pgm(b"P5\n" + b"9" * 5000 + b" 1\n255\n")),
    ),
    Case(
        "manifest map_yaml outside the site",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"map_yaml: expected a file name in the site folder",
        site_copy("s2", manifest(_set_map_yaml("../../etc/passwd"))),
    ),
    Case(
        "manifest map_yaml a number",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"map_yaml: expected a file name",
        site_copy("s2", manifest(_set_map_yaml(5))),
    ),
    Case(
        "manifest storeys a string",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"storeys\.0: expected an object",
        site_copy("s2", manifest(lambda d: d.update(storeys="ab"))),
    ),
    Case(
        "manifest nested 100000 deep",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"nested deeper than 64",
        site_copy("s2", lambda s: (s / "site.json").write_text(DEEP)),
    ),
    Case(
        "walls features an object",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"features: expected a list",
        site_copy("s2", _walls('{"type": "FeatureCollection", "features": {"a": 1}}')),
    ),
    Case(
        "walls with a 5000-digit number",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"an integer of 5000 digits",
        site_copy("s2", _walls('{"type": "FeatureCollection", "x": ' + DIGITS + "}")),
    ),
    Case(
        "walls with properties a list",
        ("bim-init", "survey", "s2", "--out", "sv"),
        r"features\[0\]: malformed wall",
        site_copy(
            "s2",
            _walls(
                '{"type": "FeatureCollection", "features": '
                '[{"properties": [], "geometry": {"type": "LineString"}}]}'
            ),
        ),
    ),
    Case(
        "features.csv with nan",
        (*MATCH, "good.jsonl", "--site", "s2"),
        r"expected a finite number, got 'nan'",
        site_copy("s2", _features_nan),
    ),
]

LOGS = [
    Case(
        "log line nested 100000 deep",
        (*MATCH, "deep.jsonl", "--site", "site"),
        r"deep.jsonl:\d+: JSON nested deeper than 64 levels",
        log_lines("deep.jsonl", DEEP),
    ),
    Case(
        "log with a 5000-digit integer",
        (*MATCH, "big.jsonl", "--site", "site"),
        r"big.jsonl:\d+: an integer of 5000 digits",
        log_lines("big.jsonl", '{"type": "odom", "t": ' + DIGITS + ', "x": 0, "y": 0, "yaw": 0}'),
    ),
    Case(
        "log with a 5000-digit float",
        (*MATCH, "big.jsonl", "--site", "site"),
        r"big.jsonl:\d+: field 't' must be finite",
        log_lines("big.jsonl", '{"type": "odom", "t": ' + DIGITS + '.5, "x": 0, "y": 0, "yaw": 0}'),
    ),
    Case(
        "log odom x NaN",
        (*MATCH, "nan.jsonl", "--site", "site"),
        r"nan.jsonl:\d+: field 'x' must be finite",
        log_lines("nan.jsonl", replace_first='{"type": "odom", "t": 0.0, "x": NaN, "y": 0, "yaw": 0}'),
    ),
    Case(
        "log Infinity in a state record",
        (*MATCH, "inf.jsonl", "--site", "site"),
        r"inf.jsonl:\d+: extra: inf is not a finite number",
        log_lines("inf.jsonl", '{"type": "state", "t": 1.0, "state": "x", "extra": Infinity}'),
    ),
    Case(
        "log -Infinity in hypotheses",
        (*MATCH, "inf.jsonl", "--site", "site"),
        r"hypotheses.0.pose.1: -inf is not a finite",
        log_lines(
            "inf.jsonl", '{"type": "hypotheses", "t": 1.0, "hypotheses": [{"pose": [0, -Infinity, 0]}]}'
        ),
    ),
    Case(
        "log 1e999 in a feature",
        (*MATCH, "inf.jsonl", "--site", "site"),
        r"field 'x' must be finite",
        log_lines("inf.jsonl", '{"type": "feature", "t": 1.0, "class": "door", "x": 1e999, "y": 0}'),
    ),
    Case(
        "log line of 17 MiB",
        (*MATCH, "long.jsonl", "--site", "site"),
        r"long.jsonl:\d+: a line of 17(\.0)? MiB \(at most 16 MiB\)",
        log_lines("long.jsonl", '{"type": "state", "s": "' + "x" * (17 << 20) + '"}'),
    ),
    Case(
        "log 2 GiB",
        (*MATCH, "huge.jsonl", "--site", "site"),
        r"above the limit of 1 GiB",
        sparse("huge.jsonl", 2 << 30, b'{"type": "meta"'),
    ),
    Case("log is /dev/zero", (*MATCH, "/dev/zero", "--site", "site"), DEVICE),
    Case(
        "log is a FIFO",
        (*MATCH, "pipe.jsonl", "--site", "site"),
        r"pipe.jsonl: is a pipe \(FIFO\)",
        fifo("pipe.jsonl"),
    ),
    Case("--site is /dev/zero", (*MATCH, "good.jsonl", "--site", "/dev/zero"), DEVICE),
    Case(
        "--site features.csv is a FIFO",
        (*MATCH, "good.jsonl", "--site", "f.csv"),
        r"is a pipe",
        fifo("f.csv"),
    ),
]

DEVICES = [
    Case("run --config /dev/zero", (*RUN, "/dev/zero"), DEVICE),
    Case("run --config a FIFO", (*RUN, "pipe.yaml"), r"is a pipe", fifo("pipe.yaml")),
    Case(
        "run site.path /dev/zero",
        (*RUN, "z.yaml", "--out", "r"),
        DEVICE,
        text("z.yaml", "site:\n  path: /dev/zero\n"),
    ),
    Case("eval --config /dev/zero", ("bim-init", "eval", "--config", "/dev/zero"), DEVICE),
    Case(
        "eval site config /dev/zero",
        ("bim-init", "eval", "--config", "z.yaml"),
        r"sites.0.config",
        text("z.yaml", "sites:\n  - config: /dev/zero\n"),
    ),
    Case("survey SITE /dev/zero", ("bim-init", "survey", "/dev/zero", "--out", "sv"), DEVICE),
    Case(
        "survey --config /dev/zero",
        ("bim-init", "survey", "site", "--config", "/dev/zero", "--out", "sv"),
        DEVICE,
    ),
    Case("extract /dev/zero", ("bim-extract", "/dev/zero", "-o", "out"), DEVICE),
    Case("extract a FIFO", ("bim-extract", "m.ifc", "-o", "out"), r"is a pipe", fifo("m.ifc")),
    Case(
        "extract a 3 GiB IFC",
        ("bim-extract", "big.ifc", "-o", "out"),
        r"above the limit of 2 GiB",
        sparse("big.ifc", 3 << 30, b"ISO-10303-21;\n"),
    ),
    Case(
        "--categories /dev/zero",
        ("bim-extract", "model.ifc", "--categories", "/dev/zero", "-o", "out"),
        DEVICE,
    ),
    Case("publish-pose /dev/zero", ("bim-init", "publish-pose", "/dev/zero", "--dry-run"), DEVICE),
    Case("bag2log /dev/zero", ("bim-init", "bag2log", "/dev/zero", "-o", "x.jsonl"), DEVICE),
    Case(
        "bag2log a FIFO .mcap",
        ("bim-init", "bag2log", "p.mcap", "-o", "x.jsonl"),
        r"is a pipe",
        fifo("p.mcap"),
    ),
    Case("predict an image /dev/zero", ("bim-init", "detector", "predict", "default", "/dev/zero"), DEVICE),
    Case("predict a model /dev/zero", ("bim-init", "detector", "predict", "/dev/zero", "door.png"), DEVICE),
    Case("export /dev/zero", ("bim-init", "detector", "export", "/dev/zero", "-o", "m.onnx"), DEVICE),
    Case(
        "detector eval --data /dev/zero",
        ("bim-init", "detector", "eval", "default", "--data", "/dev/zero"),
        r"/dev/zero",
    ),
]

BAGS = [
    Case(
        "bag with all-NaN depth: a warning, not silence",
        ("bim-init", "bag2log", "z.mcap", "-o", "x.jsonl"),
        r"warning: none of the \d+ detections has a depth",
        bag_with("z.mcap", nan_depth),
        code=0,
    ),
    Case(
        "bag CameraInfo K NaN",
        ("bim-init", "bag2log", "k.mcap", "-o", "x.jsonl"),
        r"camera_info: the CameraInfo K matrix holds nan",
        bag_with("k.mcap", nan_camera_k),
    ),
    Case(
        "bag odometry NaN",
        ("bim-init", "bag2log", "o.mcap", "-o", "x.jsonl"),
        r"/odom: an Odometry pose holds nan",
        bag_with("o.mcap", nan_odometry),
    ),
    Case(
        "bag transform inf",
        ("bim-init", "bag2log", "t.mcap", "-o", "x.jsonl"),
        r"/tf_static: the transform to .* holds inf",
        bag_with("t.mcap", inf_transform),
    ),
    Case(
        "bag Detection2D NaN",
        ("bim-init", "bag2log", "d.mcap", "-o", "x.jsonl"),
        r"/detections: a Detection2D .* holds nan",
        bag_with("d.mcap", nan_detection),
    ),
    Case(
        "bag Detection2D score 1e9",
        ("bim-init", "bag2log", "s.mcap", "-o", "x.jsonl"),
        r"/detections: a Detection2D score of 1e\+09 is outside \[0, 1\]",
        bag_with("s.mcap", huge_score),
    ),
    Case(
        "match on a bag with all-NaN depth",
        (*MATCH, "z.mcap", "--site", "site"),
        r"z.mcap: none of the \d+ detections has a depth",
        bag_with("z.mcap", nan_depth),
    ),
    Case(
        "match on a log without any depth",
        (*MATCH, "nodepth.jsonl", "--site", "site"),
        r"nodepth.jsonl: none of the 140 detections has a depth \(every 'depth' is null\)",
        depthless_log("nodepth.jsonl"),
    ),
    Case(
        "match on a bag with NaN K",
        (*MATCH, "k.mcap", "--site", "site"),
        r"CameraInfo K matrix holds nan",
        bag_with("k.mcap", nan_camera_k),
    ),
]

SUMMARIES = [
    Case(
        'summary success "false"',
        ("bim-init", "publish-pose", "summary.json", "--port", "1"),
        r"success: expected true or false, got \"false\"",
        summary_with(success="false"),
    ),
    Case(
        "summary negative variance",
        ("bim-init", "publish-pose", "summary.json", "--dry-run"),
        r"covariance.1.1: -0.5 is a negative variance",
        summary_with(covariance=[[0.1, 0, 0], [0, -0.5, 0], [0, 0, 0.1]]),
    ),
    Case(
        "summary covariance not symmetric",
        ("bim-init", "publish-pose", "summary.json", "--dry-run"),
        r"not a covariance",
        summary_with(covariance=[[0.1, 3, 0], [0, 0.1, 0], [0, 0, 0.1]]),
    ),
    Case(
        "summary success without pose",
        ("bim-init", "publish-pose", "summary.json", "--dry-run"),
        r"summary.json: pose",
        summary_with(pose=None),
    ),
    Case(
        "summary pose x text",
        ("bim-init", "publish-pose", "summary.json", "--dry-run"),
        r"pose.x: expected a number",
        summary_with(pose={"x": "4", "y": 1.0, "yaw_deg": 0}),
    ),
    Case(
        "summary covariance 2x2",
        ("bim-init", "publish-pose", "summary.json", "--dry-run"),
        r"covariance",
        summary_with(covariance=[[0.1, 0], [0, 0.1]]),
    ),
    Case(
        "summary NaN",
        ("bim-init", "publish-pose", "s.json", "--dry-run"),
        r"s.json: covariance.0.0: nan is not a finite",
        text(
            "s.json",
            '{"success": true, "pose": {"x": 1, "y": 2, "yaw_deg": 0}, '
            '"covariance": [[NaN, 0, 0], [0, 1, 0], [0, 0, 1]]}',
        ),
    ),
    Case(
        "summary nested 100000 deep",
        ("bim-init", "publish-pose", "s.json", "--dry-run"),
        r"nested deeper than 64",
        text("s.json", DEEP),
    ),
    Case(
        "summary 5000-digit duration",
        ("bim-init", "publish-pose", "s.json", "--dry-run"),
        r"an integer of 5000 digits",
        text("s.json", '{"success": true, "duration_s": ' + DIGITS + "}"),
    ),
]

MODELS = [
    Case(
        "extract a storey elevation of 1e9",
        ("bim-extract", "far.ifc", "-o", "out"),
        r"far.ifc: storey 'Level 1' has an elevation of 1e\+09 m, beyond \+-10 km",
        storey_elevation("far.ifc", 1e9),
    ),
    Case(
        "extract --section-height 10 on a 3 m storey",
        ("bim-extract", "model.ifc", "--section-height", "10", "-o", "out"),
        r"--section-height 10 m cuts no wall on any storey \(the lowest storey is 3.00 m high\)",
    ),
]

DATASETS = [
    Case(
        "train on labels all outside the image",
        ("bim-init", "detector", "train", "--data", "data/data.yaml", "--out", "m.pt"),
        r"data/data.yaml: the train split's 1 image\(s\) hold 0 usable boxes \(1 label\(s\) were dropped: "
        r"1 outside the image",
        text("data/labels/train/a.txt", "0 1.5 0.5 0.2 0.2\n"),
    ),
]

CONFIGS = [  # issue 29: values a robot cannot have, settings that contradict one another
    Case(
        "robot.radius 5",
        (*RUN, "c.yaml"),
        r"c.yaml: robot.radius: 5 is above the maximum 2",
        config_plus("c.yaml", "robot:\n  radius: 5\n"),
    ),
    Case(
        "min_depth above max_depth",
        (*RUN, "c.yaml"),
        r"c.yaml: matching.min_depth \(9 m\) must be below matching.max_depth \(3 m\)",
        config_plus("c.yaml", "matching:\n  min_depth: 9\n  max_depth: 3\n"),
    ),
    Case(
        "principal point outside the image",
        (*RUN, "c.yaml"),
        r"c.yaml: camera.cx \(900 px\) lies outside the image \(camera.width 640 px\)",
        config_plus("c.yaml", "camera:\n  cx: 900\n"),
    ),
    Case(
        "verification p_right above p_wrong",
        (*RUN, "c.yaml"),
        r"c.yaml: verification.p_right \(0.9\) is above verification.p_wrong \(0.1\)",
        config_plus("c.yaml", "verification:\n  p_right: 0.9\n  p_wrong: 0.1\n"),
    ),
    Case(
        "a 1 cm lidar range",
        (*RUN, "c.yaml"),
        r"c.yaml: lidar.max_range: 0.01 is below the minimum 1",
        config_plus("c.yaml", "lidar:\n  max_range: 0.01\n"),
    ),
    Case(
        "a detector profile and a flat miss rate",
        (*RUN, "c.yaml"),
        r"c.yaml: sim.detector.profile replaces sim.miss_rate: set the profile or the flat rate, not both",
        config_plus("c.yaml", "sim:\n  miss_rate: 0.1\n  detector:\n    profile: default-real\n"),
    ),
    Case(
        "a detector profile that is not there",
        (*RUN, "c.yaml"),
        r"c.yaml: sim.detector.profile: .*nothere.json: no such detector profile",
        config_plus("c.yaml", "sim:\n  detector:\n    profile: nothere.json\n"),
    ),
]
