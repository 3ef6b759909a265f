"""The render scene of a storey: a storey without walls is refused."""

from __future__ import annotations

import pytest

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from initcli.detector.synth.scene import Scene


def test_scene_needs_walls():
    with pytest.raises(InputError, match="no walls"):
        Scene.from_storey(StoreyModel("L1", 0.0, []))
