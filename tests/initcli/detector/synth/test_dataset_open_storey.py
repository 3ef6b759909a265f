"""synth on storeys whose space is open to the outside, and on door openings left open by the section cut."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from bimkit.errors import InputError
from bimtools.site.load import StoreyModel
from bimtools.site.records import Feature, WallSegment
from initcli.detector.synth import dataset as synth
from initcli.detector.synth.dataset import (
    NoCirculation,
    SynthOptions,
    load_placements,
    placement_for,
    render_sample,
)
from initcli.detector.synth.render import render_view
from initcli.detector.synth.scene import Camera, Scene


def _walls(storey: str, pts: list[tuple[float, float, float, float]]) -> list[WallSegment]:
    return [WallSegment(storey, f"w{i}", "IfcWall", *p, (0.0, 0.0)) for i, p in enumerate(pts)]


def room_with_entrance(name: str = "closed") -> StoreyModel:
    """A 10 x 6 m room; the door in the south wall is a 1 m gap (as a section cut at 1 m leaves it)."""
    pts = [(0, 0, 4.5, 0), (5.5, 0, 10, 0), (10, 0, 10, 6), (10, 6, 0, 6), (0, 6, 0, 0)]
    door = Feature("d1", "Door", 5.0, 0.0, 0.0, 1.0, 1.0, 2.1, storey=name)
    lift = Feature("l1", "Lift", 10.0, 3.0, -1.0, 0.0, 1.2, 2.2, storey=name)
    return StoreyModel(name, 0.0, [door, lift], walls=_walls(name, pts))


def open_plaza(name: str = "open") -> StoreyModel:
    """Two walls of a corner with a door: the free space in front of it runs off to the outside."""
    pts = [(0, 0, 10, 0), (0, 0, 0, 8)]
    door = Feature("d2", "Door", 5.0, 0.0, 0.0, 1.0, 1.0, 2.1, storey=name)
    return StoreyModel(name, 0.0, [door], walls=_walls(name, pts))


def test_open_storey_raises_no_circulation():
    with pytest.raises(NoCirculation, match="open to the outside"):
        placement_for(Scene.from_storey(open_plaza(), decorate=False), "site")


def test_door_gap_is_closed_and_the_door_is_labelled():
    scene = Scene.from_storey(room_with_entrance(), decorate=False)
    pl = placement_for(scene, "site")  # without the closing segment the room leaks through the door gap
    assert len(pl.cells) > 100
    assert (pl.cells[:, 1] > 0).all()  # all cells inside the room
    view = render_view(scene, (5.0, 3.0, -np.pi / 2), Camera.from_fov(160, 120, 90.0, z=1.0))
    seen = {scene.features[v.index].id for v in view.features}
    assert "d1" in seen


def test_load_placements_skips_open_storeys_with_a_warning(monkeypatch):
    storeys = {"open": open_plaza(), "closed": room_with_entrance()}
    monkeypatch.setattr(synth, "load_site", lambda *_a, **_k: SimpleNamespace(storeys=storeys))
    warnings: list[str] = []
    placements = load_placements(["site"], warn=warnings.append)
    assert [p.scene.name for p in placements] == ["closed"]
    assert len(warnings) == 1 and "'open'" in warnings[0] and "skipped" in warnings[0]
    labelled = sum(
        len(render_sample(placements, i, SynthOptions(images=12, width=160, height=120, seed=3)).labels)
        for i in range(12)
    )
    assert labelled > 0

    monkeypatch.setattr(synth, "load_site", lambda *_a, **_k: SimpleNamespace(storeys={"open": open_plaza()}))
    with pytest.raises(InputError, match="no storey .* to render .*open to the outside"):
        load_placements(["site"])
