"""initcli.sim.scenario: the simulated world's corridors, starts and material stacks."""

from __future__ import annotations

import numpy as np

from bimtools.site.records import FREE, Feature
from initcli.config import load_config
from initcli.config.building import choose_storey, prepare_site
from initcli.sim.build import build_sim
from initcli.storey.circulation import Circulation
from tests.helpers import SAMPLES


def test_lidar_landmarks_move_no_start_and_no_stack(tmp_path) -> None:
    """A site extracted with lidar landmarks simulates the same world as without them: the corridors
    are the region the camera's features face (a room's corners face the room), so a start and the
    material stacks of a seed do not depend on the landmark rows."""
    config = load_config(SAMPLES / "block_b.site.yaml")
    site = prepare_site(config, tmp_path)
    storey, _ = choose_storey(config, site)
    model = site.storeys[storey]
    before = build_sim(config, site, storey, 7)
    circulation = Circulation.of(model)
    grid = model.grid
    assert grid is not None
    rows, cols = np.nonzero((grid.cells == FREE) & ~circulation.label)
    x, y = grid.cell_centre(rows, cols)
    # more corners facing free space off the corridors than the storey has doors, lifts and stairs
    pick = np.linspace(0, len(x) - 1, 4 * len(model.features)).astype(int)
    model.features += [
        Feature(f"c{i}", "ConcaveCorner", float(x[k]), float(y[k]), 1.0, 0.0, 0.5, 0.0, storey)
        for i, k in enumerate(pick)
    ]
    assert np.array_equal(Circulation.of(model).label, circulation.label)
    after = build_sim(config, site, storey, 7)
    assert after.start == before.start
    assert len(after.world.clutter) == len(before.world.clutter) > 0
    assert np.array_equal(after.world.static, before.world.static)
