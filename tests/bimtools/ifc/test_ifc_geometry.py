"""bimtools.ifc.geometry: world-coordinate triangle meshes from the geometry kernel."""

from __future__ import annotations

import numpy as np
import pytest

from bimtools.ifc.geometry import Mesh, iterate_meshes
from bimtools.ifc.model import open_model
from tests.helpers import SAMPLES


@pytest.fixture(scope="module")
def block_a():
    return open_model(SAMPLES / "block_a.ifc")


def test_mesh_z_extent() -> None:
    mesh = Mesh("g", np.array([[0.0, 0, -1.0], [1, 0, 2.5], [0, 1, 0.0]]), np.array([[0, 1, 2]]))
    assert (mesh.zmin, mesh.zmax) == (-1.0, 2.5)


def test_iterate_meshes_of_doors_in_world_coordinates(block_a) -> None:
    doors = block_a.by_type("IfcDoor")[:3]
    calls: list[tuple[int, int]] = []
    meshes = iterate_meshes(
        block_a, doors, progress=lambda done, total: calls.append((done, total)), threads=1
    )
    assert set(meshes) == {d.GlobalId for d in doors}
    assert calls and calls[-1] == (3, 3)
    for door in doors:
        mesh = meshes[door.GlobalId]
        assert mesh.verts.shape[1] == 3 and mesh.faces.shape[1] == 3
        assert mesh.faces.max() < len(mesh.verts)
        # the sample's doors stand on the floor and are as tall as the model says
        assert mesh.zmin == pytest.approx(0.0, abs=1e-6)
        assert mesh.zmax == pytest.approx(door.OverallHeight, abs=1e-6)
        width = np.ptp(mesh.verts[:, :2], axis=0).max()
        assert width == pytest.approx(door.OverallWidth, abs=1e-6)


def test_iterate_meshes_of_nothing_and_of_bodiless_elements(block_a) -> None:
    assert iterate_meshes(block_a, []) == {}
    storeys = block_a.by_type("IfcBuildingStorey")
    assert iterate_meshes(block_a, storeys, threads=1) == {}
