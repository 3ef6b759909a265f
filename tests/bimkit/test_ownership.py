"""No output names a file the tool did not write: a plot is written over only when matplotlib drew
it, a model only when this tool exported it, a profile only when it is one, a recording never; each
refusal is one line before any work, the file untouched."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib
import pytest

from bimkit.errors import InputError
from bimkit.outputs import OutputFile, check_outputs
from bimkit.ownership import drawn_by_matplotlib, json_of_format, never_written_over, starts_with_marker

matplotlib.use("Agg")


def _plot(path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig = plt.figure()
    fig.savefig(path)
    plt.close(fig)
    return path


@pytest.mark.parametrize("suffix", [".png", ".pdf", ".svg"])
def test_a_plot_of_ours_is_written_over_a_users_picture_never(tmp_path, suffix):
    ours = _plot(tmp_path / f"ours{suffix}")
    check_outputs([], [OutputFile(ours, "--plot", owned=drawn_by_matplotlib, kind="plot")])
    theirs = tmp_path / f"photo{suffix}"
    theirs.write_bytes(b"\x89PNG\r\n\x1a\n a holiday photo" if suffix == ".png" else b"%PDF-1.4 a contract")
    before = theirs.read_bytes()
    with pytest.raises(InputError, match=r"exists and is not a plot this tool wrote"):
        check_outputs([], [OutputFile(theirs, "--plot", owned=drawn_by_matplotlib, kind="plot")])
    assert theirs.read_bytes() == before


def test_models_profiles_and_recordings(tmp_path):
    model = tmp_path / "m.onnx"
    model.write_bytes(b"\x08\x07\x12\x08bim-init" + bytes(100))
    assert starts_with_marker(b"bim-init")(model)
    other = tmp_path / "other.onnx"
    other.write_bytes(b"\x08\x07\x12\x07pytorch" + bytes(100))
    assert not starts_with_marker(b"bim-init")(other)
    profile = tmp_path / "p.json"
    profile.write_text(json.dumps({"format": "bim-init.detector-profile/1"}))
    assert json_of_format("bim-init.detector-profile/1")(profile)
    assert not json_of_format("bim-init.detector-profile/1")(tmp_path / "missing.json")
    bag = tmp_path / "run.mcap"
    bag.write_bytes(b"\x89MCAP0\r\n")
    with pytest.raises(InputError, match=r"--record .*exists"):
        check_outputs(
            [], [OutputFile(bag, "--record", (".mcap",), owned=never_written_over, kind="new recording")]
        )
