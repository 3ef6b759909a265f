"""Values derived from an occupancy map, built once per map in a process.

An evaluation runs many sessions and baselines on one site in each worker process; each builds
the same likelihood field (a distance transform) and the same list of free cells from the same BIM
map. :class:`GridCache` keeps the last few by the map's content (:meth:`OccupancyGrid.content_key`),
so a map edited in place, or an equal map loaded again, is never served a stale value.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

from bimtools.site.records import OccupancyGrid

__all__ = ["GRID_CACHE_SIZE", "GridCache"]

T = TypeVar("T")

GRID_CACHE_SIZE = 4  # maps (with their settings) whose values a cache keeps


class GridCache(Generic[T]):
    """The values of one derivation, per map content and settings, least recently used dropped."""

    def __init__(self, size: int = GRID_CACHE_SIZE) -> None:
        self.size = size
        self._items: OrderedDict[tuple[object, ...], T] = OrderedDict()

    def get(self, grid: OccupancyGrid, settings: Hashable, build: Callable[[], T]) -> T:
        """The value for ``grid`` with ``settings``; ``build()`` makes it the first time."""
        key = (grid.content_key(), settings)
        if key in self._items:
            self._items.move_to_end(key)
            return self._items[key]
        value = build()
        self._items[key] = value
        while len(self._items) > self.size:
            self._items.popitem(last=False)
        return value
