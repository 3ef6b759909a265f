"""The as-built world derived from a design model (initcli.sim.as_built)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bimtools.extract.output import write_site
from bimtools.extract.pipeline import extract_site
from bimtools.site.load import StoreyModel, load_site
from initcli.sim.as_built import (
    AsBuiltParams,
    corridor_length,
    derive_as_built,
    is_exterior,
    stand_out,
)
from initcli.sim.synthetic_log import sim_features_from_bim
from initcli.storey.circulation import Circulation
from initcli.storey.doors import LEAF_CLASS

SAMPLES = Path(__file__).resolve().parents[3] / "sample_models"


@pytest.fixture(scope="module")
def block_a(tmp_path_factory: pytest.TempPathFactory) -> StoreyModel:
    out = tmp_path_factory.mktemp("block_a") / "site"
    write_site(out, extract_site(SAMPLES / "block_a.ifc"), preview=False)
    site = load_site(out)
    return max(site.storeys.values(), key=lambda s: len(s.features))


@pytest.fixture(scope="module")
def ntu_hallway(tmp_path_factory: pytest.TempPathFactory) -> StoreyModel:
    out = tmp_path_factory.mktemp("ntu") / "site"
    write_site(out, extract_site(SAMPLES / "ntu_hallway.ifc"), preview=False)
    return next(iter(load_site(out).storeys.values()))


def derive(model: StoreyModel, seed: int = 1, leaves: bool = False, **params: float):
    doors = frozenset(f.id for f in model.features if f.ifc_class == "IfcDoor") if leaves else frozenset()
    return derive_as_built(
        model.obstacles,
        model.walls,
        sim_features_from_bim(model.features),
        Circulation.of(model),
        AsBuiltParams(**params),
        np.random.default_rng(seed),
        doors,
    )


def door_ids(model: StoreyModel) -> set[str]:
    return {f.id for f in model.features if f.category == "Door"}


def test_ideal_world_is_the_design(block_a: StoreyModel) -> None:
    world = derive(block_a)
    assert world.obstacles == block_a.obstacles
    assert [f.id for f in world.features] == [f.id for f in block_a.features]


def test_missing_doors_leave_free_doorways_and_nothing_to_detect(block_a: StoreyModel) -> None:
    doors = door_ids(block_a)
    world = derive(block_a, leaves=True, missing_doors=1.0)
    assert not doors & {f.id for f in world.features}
    assert not doors & {o.element for o in world.obstacles}
    assert world.changes["missing_doors"] == len(doors)
    assert {f.id for f in world.features} == {f.id for f in block_a.features} - doors


def test_open_doors_are_no_obstacle_but_still_detected(block_a: StoreyModel) -> None:
    doors = door_ids(block_a)
    world = derive(block_a, open_doors=1.0)
    assert doors <= {f.id for f in world.features}
    assert not doors & {o.element for o in world.obstacles}


def test_shifted_doors_move_along_their_wall_with_their_leaf(block_a: StoreyModel) -> None:
    world = derive(block_a, door_shift=0.3)
    design = {f.id: f for f in block_a.features}
    moves = []
    for f in world.features:
        if f.id not in door_ids(block_a):
            continue
        d = np.array([f.x - design[f.id].x, f.y - design[f.id].y])
        normal = np.array([design[f.id].norm_x, design[f.id].norm_y])
        assert abs(float(d @ normal)) < 1e-9  # along the wall, never into the room
        moves.append(float(np.hypot(*d)))
        leaf = [o for o in world.obstacles if o.element == f.id]
        old = [o for o in block_a.obstacles if o.element == f.id]
        for a, b in zip(leaf, old, strict=True):
            shift = np.asarray(a.exterior) - np.asarray(b.exterior)
            assert np.allclose(shift, d)
    assert 0.1 < float(np.mean(moves)) < 0.5  # sigma 0.3 m: mean |shift| about 0.24 m


def test_a_closed_door_built_off_its_place_leaves_no_gap_at_the_design_opening(block_a: StoreyModel) -> None:
    """The leaf moves with the door, the wall's opening stays where the design has it: it is closed
    there too, or a leaf 0.6 m off would leave a gap out of the room (or the building) beside it."""
    world = derive(block_a, leaves=True, door_shift=0.6)
    design = {f.id: f for f in block_a.features}
    built = {f.id: f for f in world.features}
    checked = 0
    for door_id in door_ids(block_a) & set(built):
        f, d = built[door_id], design[door_id]
        if float(np.hypot(f.x - d.x, f.y - d.y)) < 0.3:
            continue
        leaves = [
            np.asarray(o.exterior)
            for o in world.obstacles
            if o.element == door_id and o.ifc_class == LEAF_CLASS
        ]
        centres = [ring.mean(axis=0) for ring in leaves]
        for x, y in ((f.x, f.y), (d.x, d.y)):  # a leaf across the built opening and the design one
            assert any(float(np.hypot(c[0] - x, c[1] - y)) < 0.1 for c in centres), (door_id, x, y)
        checked += 1
    assert checked >= 3


def test_hoardings_phantoms_and_extra_doors_are_added(block_a: StoreyModel) -> None:
    length = corridor_length(Circulation.of(block_a))
    assert length > 30.0
    world = derive(block_a, hoarding=10.0, extra_doors=10.0, persistent_phantoms=10.0)
    assert world.changes["hoardings"] >= 1
    assert len(world.hoardings) == world.changes["hoardings"]
    assert sum(o.ifc_class == "Hoarding" for o in world.obstacles) == len(world.hoardings)
    extra = [f for f in world.features if f.id.startswith("extra-")]
    phantoms = [f for f in world.features if f.id.startswith("phantom-persistent")]
    assert extra and phantoms
    assert all(f.cls == "door" for f in extra + phantoms)
    pts = np.array([[f.x, f.y] for f in world.features])
    d = np.hypot(pts[:, None, 0] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1])
    np.fill_diagonal(d, np.inf)
    added = [i for i, f in enumerate(world.features) if f.id.startswith(("extra-", "phantom"))]
    assert all(d[i].min() >= 1.5 - 1e-9 for i in added)  # never on top of another door


def test_never_seen_hides_features_from_the_detector_only(block_a: StoreyModel) -> None:
    world = derive(block_a, never_seen=1.0)
    assert world.features == []
    assert world.obstacles == block_a.obstacles


def test_same_seed_same_world(block_a: StoreyModel) -> None:
    a = derive(block_a, 7, missing_doors=0.3, door_shift=0.2, wall_offset=0.05, hoarding=2.0)
    b = derive(block_a, 7, missing_doors=0.3, door_shift=0.2, wall_offset=0.05, hoarding=2.0)
    c = derive(block_a, 8, missing_doors=0.3, door_shift=0.2, wall_offset=0.05, hoarding=2.0)
    assert a.obstacles == b.obstacles and a.features == b.features
    assert a.obstacles != c.obstacles


def test_closed_doors_cut_rooms_off_the_circulation_area(block_a: StoreyModel) -> None:
    leaves = [o for o in block_a.obstacles if o.ifc_class == "IfcDoor"]
    assert leaves
    open_plan = Circulation.of(block_a)
    closed = Circulation.of(block_a, closed=leaves)
    assert closed.label.sum() <= open_plan.label.sum()
    # Every cell of the closed-door region is free in the open one; the corridor stays.
    assert not (closed.label & ~open_plan.label).any()
    assert closed.label.sum() > 0.5 * open_plan.label.sum() or closed.label.sum() > 1000
    corridor = closed.cells(0.5)[0]
    assert closed.region_at(*corridor) > 0


def test_every_installed_closed_door_gets_a_leaf_across_its_opening(block_a: StoreyModel) -> None:
    doors = {f.id: f for f in block_a.features if f.ifc_class == "IfcDoor"}
    world = derive(block_a, leaves=True)
    leaves = {o.element: o for o in world.obstacles if o.ifc_class == LEAF_CLASS}
    assert set(leaves) == set(doors)
    for fid, leaf in leaves.items():
        ring = np.asarray(leaf.exterior)
        f = doors[fid]
        along = np.array([-f.norm_y, f.norm_x])
        extent = (ring - [f.x, f.y]) @ along
        assert abs(extent.max() - extent.min() - max(f.width, 0.6)) < 1e-6  # spans the opening
        depth = (ring - [f.x, f.y]) @ np.array([f.norm_x, f.norm_y])
        assert depth.max() <= 0.0  # behind the face, never in the corridor
    assert not any(o.ifc_class == LEAF_CLASS for o in derive(block_a, leaves=True, open_doors=1.0).obstacles)
    assert not any(
        o.ifc_class == LEAF_CLASS for o in derive(block_a, leaves=True, missing_doors=1.0).obstacles
    )


def test_the_envelope_stays_closed(ntu_hallway: StoreyModel) -> None:
    """Exterior doors are never left open; a missing one is boarded up (an obstacle, no feature)."""
    model = ntu_hallway
    circulation = Circulation.of(model)
    features = sim_features_from_bim(model.features)
    exterior = {f.id for f in features if f.cls == "door" and is_exterior(f, circulation)}
    interior = door_ids(model) - exterior
    assert exterior and interior  # the corridor ends in doors to the outside; the rest lead inside
    world = derive(model, leaves=True, missing_doors=1.0)
    boards = {o.element for o in world.obstacles if o.ifc_class == LEAF_CLASS}
    assert boards == exterior and not exterior & {f.id for f in world.features}
    world = derive(model, leaves=True, open_doors=1.0)
    leaves = {o.element for o in world.obstacles if o.ifc_class == LEAF_CLASS}
    assert leaves == exterior  # every inside door stands open, the outside ones are shut
    assert door_ids(model) <= {f.id for f in world.features}


def test_a_stack_standing_out_leaves_a_passage() -> None:
    walls = np.array([[0.0, 0.0, 10.0, 0.0], [0.0, 1.6, 10.0, 1.6], [0.0, 3.2, 10.0, 3.2]])
    narrow = np.array([[2.0, 0.0], [3.2, 0.0], [3.2, 0.6], [2.0, 0.6], [2.0, 0.0]])  # 1.6 m corridor
    out = stand_out([narrow], 1.0, np.random.default_rng(0), walls[:2])
    assert np.array_equal(out[0], narrow)  # 0.6 + 0.6 out would leave 0.4 m: it stays at its wall
    wide = stand_out([narrow], 1.0, np.random.default_rng(0), walls[[0, 2]])  # 3.2 m corridor
    assert np.allclose(wide[0] - narrow, [0.0, 0.6])
    free = stand_out([narrow], 1.0, np.random.default_rng(0))  # no world given: always out
    assert np.allclose(free[0] - narrow, [0.0, 0.6])


def test_a_gap_narrower_than_the_robot_splits_the_circulation(block_a: StoreyModel) -> None:
    open_plan = Circulation.of(block_a)
    free = open_plan.cells(0.9)
    x0, y0 = free[np.argmin(np.abs(free[:, 0] - 15.0) + np.abs(free[:, 1] - 11.0))]
    # The corridor's walls either side of (x0, y0): a stack across it leaves a 0.4 m gap.
    ys = [y for y in np.arange(y0 - 3, y0 + 3, 0.05) if open_plan.contains(x0, y)]
    low, high = min(ys), max(ys)
    box = np.array([[x0, low - 0.2], [x0 + 0.6, low - 0.2], [x0 + 0.6, high - 0.4], [x0, high - 0.4]])
    west, east = (x0 - 3.0, y0), (x0 + 3.6, y0)
    loose = Circulation.of(block_a, boxes=[box])
    assert loose.region_at(*west) == loose.region_at(*east) > 0  # a point can slip through
    tight = Circulation.of(block_a, boxes=[box], footprint=0.35)
    assert tight.region_at(*west) > 0 and tight.region_at(*east) > 0
    assert tight.region_at(*west) != tight.region_at(*east)  # a 0.7 m robot cannot
    assert tight.clearance[tight.grid.world_to_cell(*west)] == pytest.approx(
        loose.clearance[loose.grid.world_to_cell(*west)]
    )  # clearance stays the distance to the nearest obstacle
