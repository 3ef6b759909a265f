"""walls.geojson: round trip and the storey filter."""

from __future__ import annotations

from bimtools.site.records import Obstacle, WallSegment
from bimtools.site.walls_geojson import read_walls, write_walls


def test_walls_geojson_round_trip_and_storey_filter(tmp_path):
    walls = [
        WallSegment("L1", "w1", "IfcWall", 0, 0, 4, 0, (0.0, 1.0)),
        WallSegment("L2", "w2", "IfcWall", 1, 1, 1, 5, (-1.0, 0.0)),
    ]
    obstacles = [Obstacle("L1", "w1", "IfcWall", ((0, -0.2), (4, -0.2), (4, 0), (0, 0), (0, -0.2)))]
    path = tmp_path / "walls.geojson"
    write_walls(path, walls, obstacles)
    got_walls, got_obstacles = read_walls(path)
    assert got_walls == walls
    assert got_obstacles[0].exterior == tuple((float(x), float(y)) for x, y in obstacles[0].exterior)
    only_l2, none = read_walls(path, storey="L2")
    assert [w.element for w in only_l2] == ["w2"] and none == []
