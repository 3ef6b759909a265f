"""The occupancy map (PGM + YAML): round trip, world lookup, a truncated PGM."""

from __future__ import annotations

import numpy as np
import pytest

from bimkit.errors import InputError
from bimtools.site.occupancy_map import FREE, OCCUPIED, UNKNOWN, OccupancyGrid, read_map, write_map


def test_map_round_trip_and_world_lookup(tmp_path):
    cells = np.full((40, 60), UNKNOWN, dtype=np.uint8)
    cells[10:30, 10:50] = FREE
    cells[10, 10:50] = OCCUPIED
    grid = OccupancyGrid(cells, 0.05, (-1.5, 2.0, 0.0))
    write_map(tmp_path / "map_L1.yaml", grid)
    back = read_map(tmp_path / "map_L1.yaml")
    assert np.array_equal(back.cells, cells) and back.origin == (-1.5, 2.0, 0.0) and back.resolution == 0.05
    # row 0 is the top: the lower-left pixel is at the origin.
    assert back.value_at(-1.5 + 0.025, 2.0 + 0.025) == UNKNOWN
    x, y = back.cell_centre(20, 30)
    assert back.value_at(float(x), float(y)) == FREE
    x, y = back.cell_centre(10, 30)
    assert back.value_at(float(x), float(y)) == OCCUPIED
    state = back.occupancy()
    assert state[10, 30] == 1 and state[20, 30] == 0 and state[0, 0] == -1


def test_truncated_pgm_is_reported(tmp_path):
    grid = OccupancyGrid(np.full((10, 10), FREE, dtype=np.uint8), 0.1, (0.0, 0.0, 0.0))
    write_map(tmp_path / "m.yaml", grid)
    data = (tmp_path / "m.pgm").read_bytes()
    (tmp_path / "m.pgm").write_bytes(data[:-5])
    with pytest.raises(InputError, match="truncated"):
        read_map(tmp_path / "m.yaml")


@pytest.mark.parametrize(
    ("name", "says"), [("missing.pgm", "not found"), ("9" * 5000 + ".pgm", "(5004 characters)")]
)
def test_an_image_name_that_names_no_file_is_one_line(tmp_path, name, says):
    """A name too long for the file system (found by the fuzz test: ``Path.exists`` raises on it)
    is refused like a missing file, in one short line."""
    yaml_path = tmp_path / "map.yaml"
    yaml_path.write_text(f"image: {name}\nresolution: 0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(InputError) as caught:
        read_map(yaml_path)
    assert says in str(caught.value) and len(str(caught.value)) < 250
