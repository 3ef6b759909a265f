"""Hostile cases: unbounded work (a Ray address that does not answer, campaigns of millions of starts),
the reported tracebacks, servers that do not speak rosbridge, a Latin-1 file name."""

from __future__ import annotations

from pathlib import Path

from tests.hostile.harness import Case
from tests.hostile.workspace import latin1_copy, text, thin_image

NO_RAY = r"--address 127\.0\.0\.1:1: no Ray cluster answers there"
SURVEY = ("bim-init", "survey", "site", "--out", "sv")
EVAL = ("bim-init", "eval", "--config", "eval.yaml", "--out", "ev", "--workers", "1")


def _site_written(folder: Path) -> None:
    assert (folder / "lat" / "site.json").is_file() and (folder / "lat" / "features.csv").is_file()


WORK = [
    Case(
        "eval --executor ray --address 127.0.0.1:1",
        (*EVAL, "--executor", "ray", "--address", "127.0.0.1:1"),
        NO_RAY,
        timeout=45,
    ),
    Case(
        "survey --executor ray --address 127.0.0.1:1",
        (*SURVEY, "--executor", "ray", "--address", "127.0.0.1:1"),
        NO_RAY,
        timeout=45,
    ),
    Case(
        "survey ray://127.0.0.1:1",
        (*SURVEY, "--executor", "ray", "--address", "ray://127.0.0.1:1"),
        r"no Ray cluster answers there",
        timeout=45,
    ),
    Case(
        "eval --address not an address",
        (*EVAL, "--executor", "ray", "--address", "no-port-here"),
        r"expected host:port",
        timeout=45,
    ),
    Case(
        "survey --address a silent TCP server",
        (*SURVEY, "--executor", "ray", "--address", "127.0.0.1:{port}"),
        r"the Ray cluster did not answer within 20 s",
        server="silent-tcp",
        timeout=60,
        slow=True,
    ),
    Case(
        "survey --spacing 0.1 --headings 360",
        (*SURVEY, "--spacing", "0.1", "--headings", "360"),
        r"starts .* more than 100000 \(hours of work\); pass --yes",
    ),
    Case(
        "eval --starts 100000",
        (*EVAL, "--starts", "100000"),
        r"400000 trials .* more than 20000 trials .* pass --yes",
    ),
    Case(
        "eval a sweep of 400 values",
        (*EVAL, "--starts", "20", "--sweep", "alpha=" + ",".join(f"{0.5 + k / 1000:g}" for k in range(400))),
        r"32000 trials .* 400 sweep values",
    ),
]

TRACEBACKS = [
    Case(
        "--sweep matching=1,2",
        (*EVAL, "--sweep", "matching=1,2"),
        r"--sweep matching: matching is a section whose settings do not all scale",
    ),
    Case("--sweep camera=2", (*EVAL, "--sweep", "camera=2"), r"do not all scale"),
    Case(
        "predict a 1x20000 image",
        ("bim-init", "detector", "predict", "default", "thin.png"),
        r"a 20000x1 image; the detector needs",
        thin_image("thin.png", 20000, 1),
    ),
    Case(
        "predict a 20000x1 image",
        ("bim-init", "detector", "predict", "default", "tall.png"),
        r"a 1x20000 image",
        thin_image("tall.png", 1, 20000),
    ),
    Case(
        "predict a 4x4 image",
        ("bim-init", "detector", "predict", "default", "tiny.png"),
        r"a 4x4 image",
        thin_image("tiny.png", 4, 4),
    ),
    Case(
        "predict an image that is text",
        ("bim-init", "detector", "predict", "default", "fake.png"),
        r"cannot read image",
        text("fake.png", "not a png"),
    ),
    Case(
        "a valid IFC named in Latin-1 bytes",
        ("bim-extract", "caf\udce9.ifc", "-o", "lat"),
        r"wrote \d+ files to lat",
        latin1_copy("model.ifc", b"caf\xe9.ifc"),
        code=0,
        check=_site_written,
    ),
]

ROSBRIDGE = [
    Case(
        "publish-pose to a plain websocket server",
        ("bim-init", "publish-pose", "summary.json", "--host", "127.0.0.1", "--port", "{port}"),
        r"is a websocket server but does not speak rosbridge",
        server="plain-ws",
    ),
    Case(
        "publish-pose to an echoing websocket server",
        ("bim-init", "publish-pose", "summary.json", "--host", "127.0.0.1", "--port", "{port}"),
        r"does not speak rosbridge",
        server="echo-ws",
    ),
    Case(
        "publish-pose to a closed port",
        ("bim-init", "publish-pose", "summary.json", "--host", "127.0.0.1", "--port", "1"),
        r"cannot reach rosbridge at ws://127\.0\.0\.1:1",
    ),
]
