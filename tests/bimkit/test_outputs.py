"""bimkit.outputs: every output path checked against the inputs and the file system before any work."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from bimkit.atomic import RECORD
from bimkit.errors import InputError
from bimkit.outputs import OutputFile, OutputFolder, check_outputs


def test_a_new_or_empty_folder_or_an_earlier_runs_folder_is_fine(tmp_path: Path) -> None:
    check_outputs([], [OutputFolder(tmp_path / "new" / "deeper", "--out", ("manifest.json",))])
    empty = tmp_path / "empty"
    empty.mkdir()
    check_outputs([], [OutputFolder(empty, "--out", ("manifest.json",))])
    earlier = tmp_path / "earlier"
    earlier.mkdir()
    (earlier / "manifest.json").write_text("{}")
    (earlier / "map.pgm").write_text("x")
    check_outputs([], [OutputFolder(earlier, "--out", ("manifest.json",))])
    recorded = tmp_path / "recorded"
    recorded.mkdir()
    (recorded / "a.txt").write_text("x")
    (recorded / RECORD).write_text('{"files": ["a.txt"]}')
    check_outputs([], [OutputFolder(recorded, "--out", ("manifest.json",))])


def test_a_folder_of_other_files_needs_force_and_a_clash_is_refused_even_then(tmp_path: Path) -> None:
    other = tmp_path / "other"
    other.mkdir()
    (other / "notes.txt").write_text("mine")
    out = OutputFolder(other, "--out", ("manifest.json",), ("manifest.json", "map_*"))
    with pytest.raises(InputError, match=r"holds other files .* pass --force to write into it \(the other"):
        check_outputs([], [out])
    check_outputs([], [out], force=True)  # notes.txt will be kept
    (other / "map_L1.pgm").write_text("not the tool's")
    with pytest.raises(
        InputError, match=r"map_L1.pgm would be written over and was not written by this tool"
    ):
        check_outputs([], [out], force=True)


def test_wrong_kinds_are_refused(tmp_path: Path) -> None:
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    with pytest.raises(InputError, match=r"^--out .*file.txt: is a file, expected a folder$"):
        check_outputs([], [OutputFolder(a_file, "--out")])
    with pytest.raises(InputError, match=r"file.txt is a file, not a folder"):
        check_outputs([], [OutputFolder(a_file / "sub", "--out")], force=True)
    with pytest.raises(InputError, match="is a folder, expected a file name"):
        check_outputs([], [OutputFile(tmp_path, "--json")])
    with pytest.raises(InputError, match="is a file, not a folder"):
        check_outputs([], [OutputFile(a_file / "result.json", "--json")])
    with pytest.raises(InputError, match="is a device, pipe or socket"):
        check_outputs([], [OutputFile(Path("/dev/null"), "-o")])
    with pytest.raises(InputError, match=r"expected a file name ending in .png or .pdf"):
        check_outputs([], [OutputFile(tmp_path / "plot.txt", "--plot", (".png", ".pdf"))])
    check_outputs([], [OutputFile(tmp_path / "PLOT.PNG", "--plot", (".png", ".pdf"))])


def test_paths_that_cannot_be_written_are_refused(tmp_path: Path) -> None:
    dangling = tmp_path / "dangling"
    dangling.symlink_to(tmp_path / "missing")
    with pytest.raises(InputError, match="is a symbolic link to a missing target"):
        check_outputs([], [OutputFile(dangling, "-o")])
    with pytest.raises(InputError, match="goes through .*dangling, which is a symbolic link to a missing"):
        check_outputs([], [OutputFolder(dangling / "sub", "--out")])
    with pytest.raises(InputError, match=r"^--out /proc/bim-init-test: cannot write in /proc"):
        check_outputs([], [OutputFolder(Path("/proc/bim-init-test"), "--out")])
    if os.geteuid() != 0:  # root writes anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        with pytest.raises(InputError, match="cannot write in"):
            check_outputs([], [OutputFile(locked / "x.json", "-o")])
    assert [p.name for p in tmp_path.iterdir()] == ["dangling"] or os.geteuid() != 0  # no probe left


def test_an_output_that_is_an_input_is_refused_by_path_link_and_inode(tmp_path: Path) -> None:
    bag = tmp_path / "s.mcap"
    bag.write_bytes(b"recording")
    with pytest.raises(InputError, match=r"^-o/--out .*s.mcap: is the input .*s.mcap; choose another name"):
        check_outputs([bag], [OutputFile(bag, "-o/--out")])
    link = tmp_path / "link.jsonl"
    link.symlink_to(bag)
    with pytest.raises(InputError, match="is the input"):
        check_outputs([bag], [OutputFile(link, "-o/--out")])
    hard = tmp_path / "hard.jsonl"
    os.link(bag, hard)
    with pytest.raises(InputError, match="is the input"):
        check_outputs([bag], [OutputFile(hard, "-o/--out")])
    os.chdir(tmp_path)
    with pytest.raises(InputError, match="is the input"):
        check_outputs([Path("s.mcap")], [OutputFile(Path("./sub/../s.mcap"), "-o/--out")])
    check_outputs([bag], [OutputFile(tmp_path / "s.jsonl", "-o/--out")])


def test_a_folder_holding_an_input_or_inside_an_input_folder_is_refused(tmp_path: Path) -> None:
    folder = tmp_path / "DIR"
    folder.mkdir()
    model = folder / "model.ifc"
    model.write_text("ISO-10303-21;")
    with pytest.raises(InputError, match="holds the input .*model.ifc; choose another folder"):
        check_outputs([model], [OutputFolder(folder, "-o", ("site.json",))], force=True)
    with pytest.raises(InputError, match="holds the input"):
        check_outputs([model], [OutputFolder(tmp_path, "-o")], force=True)
    os.chdir(folder)
    with pytest.raises(InputError, match="holds the input"):
        check_outputs([Path("model.ifc")], [OutputFolder(Path("."), "-o")], force=True)
    site = tmp_path / "site"
    site.mkdir()
    with pytest.raises(InputError, match="is inside the input folder .*site"):
        check_outputs([site], [OutputFolder(site / "survey", "--out")])
    with pytest.raises(InputError, match="is inside the input folder"):
        check_outputs([site], [OutputFile(site / "plot.png", "--plot")])
    with pytest.raises(InputError, match="is the input"):
        check_outputs([site], [OutputFolder(site, "--out")])
    check_outputs([site, model], [OutputFolder(tmp_path / "elsewhere", "--out")])
