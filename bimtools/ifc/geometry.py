"""Triangle meshes of selected elements in world coordinates (metres), from the geometry kernel.

One ``ifcopenshell.geom.iterator`` pass, filtered to the elements we need, on all cores.
Openings are subtracted from their host walls by the kernel.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import ifcopenshell
import ifcopenshell.geom
import numpy as np

__all__ = ["Mesh", "ProgressCallback", "geometry_settings", "iterate_meshes"]

ProgressCallback = Callable[[int, int], None]


@dataclass(frozen=True)
class Mesh:
    """A triangulated element: ``verts`` (n, 3) metres in the world frame, ``faces`` (m, 3)."""

    guid: str
    verts: np.ndarray
    faces: np.ndarray

    @property
    def zmin(self) -> float:
        return float(self.verts[:, 2].min())

    @property
    def zmax(self) -> float:
        return float(self.verts[:, 2].max())


def geometry_settings() -> ifcopenshell.geom.settings:
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    return settings


def iterate_meshes(
    model: ifcopenshell.file,
    elements: Iterable[ifcopenshell.entity_instance],
    progress: ProgressCallback | None = None,
    threads: int | None = None,
) -> dict[str, Mesh]:
    """Meshes of ``elements`` keyed by GlobalId; elements without a body are left out."""
    elements = list(elements)
    meshes: dict[str, Mesh] = {}
    if not elements:
        return meshes
    total = len(elements)
    iterator = ifcopenshell.geom.iterator(
        geometry_settings(), model, threads or multiprocessing.cpu_count(), include=elements
    )
    try:
        if iterator.initialize():
            while True:
                shape = iterator.get()
                geometry = shape.geometry
                verts = np.asarray(geometry.verts, dtype=float).reshape(-1, 3)
                faces = np.asarray(geometry.faces, dtype=np.int64).reshape(-1, 3)
                if len(verts) and len(faces):
                    meshes[shape.guid] = Mesh(shape.guid, verts, faces)
                if progress is not None:
                    progress(len(meshes), total)
                if not iterator.next():
                    break
    finally:
        del iterator
    return meshes
