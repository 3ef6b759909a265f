"""Hostile cases: outputs that are, hold or lie in an input; outputs that cannot be written."""

from __future__ import annotations

from pathlib import Path

from tests.hostile.harness import Case
from tests.hostile.workspace import link, moved, text

IS_INPUT = r"is the input"
HOLDS_INPUT = r"holds the input"
INSIDE = r"is inside the input folder"
CANNOT = r"cannot write in /proc"
DANGLING = r"symbolic link to a missing target"


def _kept(*names: str):
    def check(folder: Path) -> None:
        for name in names:
            assert (folder / name).is_file(), f"{name} was removed"

    return check


RUN = ("bim-init", "run", "--config", "site.yaml", "--quiet")
EVAL = ("bim-init", "eval", "--config", "eval.yaml", "--workers", "1")
EXTRACT = ("bim-extract", "model.ifc")

SACRED = [
    # the data-loss cases
    Case("bag2log -o the bag itself", ("bim-init", "bag2log", "rec.mcap", "-o", "rec.mcap"), IS_INPUT),
    Case(
        "bag2log -o the bag by another path",
        ("bim-init", "bag2log", "rec.mcap", "-o", "x/../rec.mcap"),
        IS_INPUT,
    ),
    Case(
        "bag2log -o a symlink to the bag",
        ("bim-init", "bag2log", "rec.mcap", "-o", "log.jsonl"),
        IS_INPUT,
        link("log.jsonl", "rec.mcap"),
    ),
    Case(
        "bag2log -o a hard link of the bag",
        ("bim-init", "bag2log", "rec.mcap", "-o", "log.jsonl"),
        IS_INPUT,
        link("log.jsonl", "rec.mcap", hard=True),
    ),
    Case(
        "extract DIR/model.ifc -o DIR --force",
        ("bim-extract", "DIR/model.ifc", "-o", "DIR", "--force"),
        HOLDS_INPUT,
        moved(("model.ifc", "DIR/model.ifc"), ("notes.txt", "DIR/notes.txt")),
    ),
    Case(
        "extract DIR/model.ifc -o DIR",
        ("bim-extract", "DIR/model.ifc", "-o", "DIR"),
        HOLDS_INPUT,
        moved(("model.ifc", "DIR/model.ifc")),
    ),
    Case("extract model.ifc -o . --force", (*EXTRACT, "-o", ".", "--force"), HOLDS_INPUT),
    Case(
        "extract DIR/sub/model.ifc -o DIR --force",
        ("bim-extract", "DIR/sub/model.ifc", "-o", "DIR", "--force"),
        HOLDS_INPUT,
        moved(("model.ifc", "DIR/sub/model.ifc")),
    ),
    Case("extract -o the model", (*EXTRACT, "-o", "model.ifc"), r"is a file, expected a folder"),
    Case(
        "extract --categories inside -o",
        (*EXTRACT, "--categories", "out/cats.yaml", "-o", "out", "--force"),
        HOLDS_INPUT,
        moved(("categories.yaml", "out/cats.yaml")),
    ),
    Case("run --record the config", (*RUN, "--out", "r", "--record", "site.yaml"), IS_INPUT),
    Case(
        "run --record the IFC",
        ("bim-init", "run", "--config", "ifc.site.yaml", "--record", "model.ifc"),
        IS_INPUT,
    ),
    Case("run --record not .mcap", (*RUN, "--out", "r", "--record", "session.txt"), r"ending in \.mcap"),
    Case("run --out the site folder", (*RUN, "--out", "site"), IS_INPUT),
    Case("run --out inside the site folder", (*RUN, "--out", "site/run1"), INSIDE),
    Case("run --out . --force", (*RUN, "--out", ".", "--force"), HOLDS_INPUT),
    Case(
        "run --out the config's folder",
        ("bim-init", "run", "--config", "cfg/site.yaml", "--out", "cfg", "--force"),
        HOLDS_INPUT,
        text("cfg/site.yaml", "site:\n  path: ../site\n"),
    ),
    Case("eval --out . --force", (*EVAL, "--out", ".", "--force"), HOLDS_INPUT),
    Case("eval --out the site folder", (*EVAL, "--out", "site", "--force"), IS_INPUT),
    Case("eval --out inside the site folder", (*EVAL, "--out", "site/ev"), INSIDE),
    Case("survey --out the site", ("bim-init", "survey", "site", "--out", "site", "--force"), IS_INPUT),
    Case("survey --out inside the site", ("bim-init", "survey", "site", "--out", "site/survey"), INSIDE),
    Case(
        "survey --out holding --config",
        ("bim-init", "survey", "site", "--config", "cfg/c.yaml", "--out", "cfg", "--force"),
        HOLDS_INPUT,
        text("cfg/c.yaml", "site:\n  path: ../site\n"),
    ),
    Case(
        "match --plot the log",
        ("bim-init", "match", "good.jsonl", "--site", "site", "--plot", "good.jsonl"),
        IS_INPUT,
    ),
    Case(
        "match --plot in the site",
        ("bim-init", "match", "good.jsonl", "--site", "site", "--plot", "site/p.png"),
        INSIDE,
    ),
    Case(
        "predict --out holding the image",
        ("bim-init", "detector", "predict", "default", "door.png", "--out", "."),
        HOLDS_INPUT,
    ),
    Case(
        "predict --out the image folder",
        ("bim-init", "detector", "predict", "default", "imgs", "--out", "imgs"),
        IS_INPUT,
    ),
    Case(
        "synth --out the site", ("bim-init", "detector", "synth", "--site", "site", "--out", "site"), IS_INPUT
    ),
    Case(
        "synth --out inside the site",
        ("bim-init", "detector", "synth", "--site", "site", "--out", "site/ds"),
        INSIDE,
    ),
    Case(
        "synth --preview the log",
        ("bim-init", "detector", "synth", "--site", "site", "--out", "ds", "--preview", "good.jsonl"),
        r"ending in \.png",
    ),
    Case(
        "train --out the data.yaml",
        ("bim-init", "detector", "train", "--data", "data/data.yaml", "--out", "data/data.yaml"),
        IS_INPUT,
    ),
    Case(
        "train --init is --out's history",
        ("bim-init", "detector", "train", "--data", "data/data.yaml", "--init", "m.csv", "--out", "m.pt"),
        IS_INPUT,
        text("m.csv", "x"),
    ),
    Case(
        "export -o the checkpoint", ("bim-init", "detector", "export", "model.pt", "-o", "model.pt"), IS_INPUT
    ),
    Case(
        "export an .onnx onto itself",
        ("bim-init", "detector", "export", "m.onnx"),
        IS_INPUT,
        text("m.onnx", "x"),
    ),
    # folders of someone else's files
    Case("run --out a folder of other files", (*RUN, "--out", "other"), r"pass --force to write into it"),
    Case(
        "extract --force onto the user's features.csv",
        (*EXTRACT, "-o", "mine", "--force"),
        r"features\.csv would be written over",
        text("mine/features.csv", "mine\n"),
    ),
    Case(
        "survey --force onto the user's map png",
        ("bim-init", "survey", "site", "--out", "mine", "--force"),
        r"survey_Level_1\.png would be written over",
        text("mine/survey_Level_1.png", "mine\n"),
    ),
    Case(
        "eval --force onto the user's fig9.png",
        (*EVAL, "--out", "mine", "--force"),
        r"fig9\.png would be written over",
        text("mine/fig9.png", "mine\n"),
    ),
    Case(
        "predict --out over the user's jpg",
        ("bim-init", "detector", "predict", "default", "door.png", "--out", "mine"),
        r"door\.jpg would be written over",
        text("mine/door.jpg", "mine\n"),
    ),
    # what --force does now: write into the folder, keep everything else
    Case(
        "extract --force into a folder of notes keeps them",
        (*EXTRACT, "-o", "other", "--force"),
        r"wrote \d+ files to other",
        code=0,
        check=_kept("other/notes.txt"),
    ),
    Case(
        "extract -o . --force keeps the folder's files",
        ("bim-extract", "../model.ifc", "-o", ".", "--force"),
        r"wrote \d+ files",
        code=0,
        check=_kept("other/notes.txt"),
        cwd="other",
    ),
]

UNWRITABLE = [
    Case("extract -o /proc/x", (*EXTRACT, "-o", "/proc/bim-x"), CANNOT),
    Case("extract -o through a dangling link", (*EXTRACT, "-o", "dangling/x"), DANGLING),
    Case("extract -o a dangling link", (*EXTRACT, "-o", "dangling"), DANGLING),
    Case("extract -o through a file", (*EXTRACT, "-o", "afile/x"), r"is a file, not a folder"),
    Case("run --out /proc/x", (*RUN, "--out", "/proc/bim-x"), CANNOT),
    Case("run --out through a dangling link", (*RUN, "--out", "dangling/x"), DANGLING),
    Case("run --out a file", (*RUN, "--out", "afile"), r"is a file, expected a folder"),
    Case("run --record /proc", (*RUN, "--out", "r", "--record", "/proc/bim-x.mcap"), CANNOT),
    Case(
        "run --record through a dangling link", (*RUN, "--out", "r", "--record", "dangling/x.mcap"), DANGLING
    ),
    Case(
        "run --record /dev/null",
        (*RUN, "--out", "r", "--record", "/dev/null"),
        r"is a device, pipe or socket",
    ),
    Case("run --record a folder", (*RUN, "--out", "r", "--record", "other"), r"is a folder, expected a file"),
    Case("eval --out /proc/x", (*EVAL, "--out", "/proc/bim-x"), CANNOT),
    Case("eval --out through a dangling link", (*EVAL, "--out", "dangling/x"), DANGLING),
    Case("eval --out through a file", (*EVAL, "--out", "afile/x"), r"is a file, not a folder"),
    Case("survey --out /proc/x", ("bim-init", "survey", "site", "--out", "/proc/bim-x"), CANNOT),
    Case(
        "survey --out through a dangling link",
        ("bim-init", "survey", "site", "--out", "dangling/x"),
        DANGLING,
    ),
    Case(
        "synth --out /proc/x",
        ("bim-init", "detector", "synth", "--site", "site", "--out", "/proc/bim-x"),
        CANNOT,
    ),
    Case(
        "synth --out through a dangling link",
        ("bim-init", "detector", "synth", "--site", "site", "--out", "dangling/x"),
        DANGLING,
    ),
    Case(
        "synth --preview in /proc",
        ("bim-init", "detector", "synth", "--site", "site", "--out", "ds", "--preview", "/proc/x.png"),
        CANNOT,
    ),
    Case(
        "train --out in /proc (before training)",
        ("bim-init", "detector", "train", "--data", "data/data.yaml", "--out", "/proc/bim-x/model.pt"),
        CANNOT,
    ),
    Case(
        "train --out through a dangling link",
        ("bim-init", "detector", "train", "--data", "data/data.yaml", "--out", "dangling/model.pt"),
        DANGLING,
    ),
    Case(
        "train --out a folder",
        ("bim-init", "detector", "train", "--data", "data/data.yaml", "--out", "other"),
        r"is a folder, expected a file",
    ),
    Case("export -o /proc", ("bim-init", "detector", "export", "model.pt", "-o", "/proc/bim-x.onnx"), CANNOT),
    Case(
        "export -o not .onnx",
        ("bim-init", "detector", "export", "model.pt", "-o", "m.txt"),
        r"ending in \.onnx",
    ),
    Case(
        "predict --out /proc/x",
        ("bim-init", "detector", "predict", "default", "door.png", "--out", "/proc/bim-x"),
        CANNOT,
    ),
    Case(
        "predict --out through a dangling link",
        ("bim-init", "detector", "predict", "default", "door.png", "--out", "dangling/x"),
        DANGLING,
    ),
    Case("bag2log -o /proc", ("bim-init", "bag2log", "rec.mcap", "-o", "/proc/bim-x.jsonl"), CANNOT),
    Case(
        "bag2log -o through a dangling link",
        ("bim-init", "bag2log", "rec.mcap", "-o", "dangling/x.jsonl"),
        DANGLING,
    ),
    Case(
        "bag2log -o through a file",
        ("bim-init", "bag2log", "rec.mcap", "-o", "afile/x.jsonl"),
        r"is a file, not a folder",
    ),
    Case(
        "bag2log -o /dev/null",
        ("bim-init", "bag2log", "rec.mcap", "-o", "/dev/null"),
        r"is a device, pipe or socket",
    ),
    Case(
        "match --plot in /proc",
        ("bim-init", "match", "good.jsonl", "--site", "site", "--plot", "/proc/bim-x.png"),
        CANNOT,
    ),
    Case(
        "match --plot through a dangling link",
        ("bim-init", "match", "good.jsonl", "--site", "site", "--plot", "dangling/p.png"),
        DANGLING,
    ),
    Case(
        "match --plot out.txt",
        ("bim-init", "match", "good.jsonl", "--site", "site", "--plot", "out.txt"),
        r"ending in \.png or \.pdf",
    ),
    Case(
        "match --plot a folder",
        ("bim-init", "match", "good.jsonl", "--site", "site", "--plot", "other"),
        r"is a folder, expected a file",
    ),
]
