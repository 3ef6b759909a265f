"""Values derived from a map, kept per map content (initcli.core.filters.grid_cache) and the two users of
it: the likelihood field and global localisation's free cells."""

from __future__ import annotations

import numpy as np

from bimtools.site.records import FREE, OCCUPIED, OccupancyGrid
from initcli.core.filters.global_localisation import free_cell_centres
from initcli.core.filters.grid_cache import GridCache
from initcli.core.filters.particle_filter import LikelihoodField, likelihood_field


def room(size: int = 40) -> OccupancyGrid:
    cells = np.full((size, size), FREE, dtype=np.uint8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    return OccupancyGrid(cells, 0.1, (0.0, 0.0, 0.0))


def test_one_build_per_content_and_settings() -> None:
    cache: GridCache[int] = GridCache(size=2)
    builds: list[str] = []

    def build(tag: str) -> int:
        builds.append(tag)
        return len(builds)

    a = room()
    assert cache.get(a, 1.0, lambda: build("a")) == 1
    assert cache.get(room(), 1.0, lambda: build("equal map")) == 1  # same content, another object
    assert cache.get(a, 2.0, lambda: build("other setting")) == 2
    a.cells[5, 5] = OCCUPIED  # edited in place: a new map
    assert cache.get(a, 1.0, lambda: build("edited")) == 3
    assert cache.get(room(), 1.0, lambda: build("evicted")) == 4  # the oldest of 2 went
    assert builds == ["a", "other setting", "edited", "evicted"]


def test_likelihood_field_and_free_cells_are_shared_and_right() -> None:
    grid = room()
    field = likelihood_field(grid, 1.5)
    assert likelihood_field(room(), 1.5) is field
    np.testing.assert_array_equal(field.distance, LikelihoodField(grid, 1.5).distance)
    assert likelihood_field(grid, 2.0) is not field
    free = free_cell_centres(grid)
    assert free_cell_centres(room()) is free
    assert len(free) == 38 * 38 and not free.flags.writeable
    grid.cells[10, 10] = OCCUPIED
    assert len(free_cell_centres(grid)) == 38 * 38 - 1
