"""Reading any ROS map_server / Nav2 map: the modes, negate, the thresholds, PGM P5/P2 and PNG, and
images whose header disagrees with their data (refused by name, never read sheared)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
import yaml

from bimkit.errors import InputError
from bimtools.site.occupancy_map import FREE, OCCUPIED, UNKNOWN, read_map


def pgm(cells: np.ndarray, maxval: int = 255) -> bytes:
    rows, cols = cells.shape
    dtype = np.uint8 if maxval < 256 else ">u2"
    return f"P5\n{cols} {rows}\n{maxval}\n".encode() + np.ascontiguousarray(cells, dtype=dtype).tobytes()


def write(tmp_path, image_bytes: bytes, name: str = "m.pgm", **meta):
    (tmp_path / name).write_bytes(image_bytes)
    doc = {"image": name, "resolution": 0.05, "origin": [1.0, -2.0, 0.0], **meta}
    (tmp_path / "m.yaml").write_text(yaml.safe_dump(doc))
    return tmp_path / "m.yaml"


LEVELS = np.array([[0, 50, 100, 150, 200, 205, 230, 254, 255]], dtype=np.uint8)


def test_trinary_default_thresholds(tmp_path):
    # p = (255 - v) / 255: 0 -> 1, 50 -> 0.80, 100 -> 0.61, 150 -> 0.41, 200 -> 0.22, 205 -> 0.196,
    # 230 -> 0.098, 254 -> 0.004, 255 -> 0; occupied above 0.65, free below 0.196
    grid = read_map(write(tmp_path, pgm(LEVELS)))
    o, f, u = OCCUPIED, FREE, UNKNOWN
    assert grid.cells.tolist() == [[o, o, u, u, u, u, f, f, f]]
    assert grid.origin == (1.0, -2.0, 0.0) and grid.resolution == 0.05


def test_negate_and_thresholds(tmp_path):
    grid = read_map(write(tmp_path, pgm(LEVELS), negate=1, occupied_thresh=0.5, free_thresh=0.3))
    # p = v / 255: 0, 0.2, 0.39, 0.59, 0.78, 0.80, 0.90, 0.996, 1
    o, f, u = OCCUPIED, FREE, UNKNOWN
    assert grid.cells.tolist() == [[f, f, u, o, o, o, o, o, o]]


def test_scale_mode_alpha_is_unknown_and_between_stays_unknown(tmp_path):
    bgra = np.zeros((1, 4, 4), dtype=np.uint8)
    bgra[0, :, :3] = np.array([0, 254, 128, 254])[:, None]
    bgra[0, :, 3] = [255, 255, 255, 100]  # the last pixel is see-through
    ok, data = cv2.imencode(".png", bgra)
    assert ok
    grid = read_map(write(tmp_path, data.tobytes(), name="m.png", mode="scale"))
    assert grid.cells.tolist() == [[OCCUPIED, FREE, UNKNOWN, UNKNOWN]]
    # trinary ignores the alpha channel
    grid = read_map(write(tmp_path, data.tobytes(), name="m.png", mode="trinary"))
    assert grid.cells.tolist() == [[OCCUPIED, FREE, UNKNOWN, FREE]]


def test_raw_mode_is_percent_occupancy(tmp_path):
    raw = np.array([[0, 10, 50, 90, 100, 101, 255]], dtype=np.uint8)
    grid = read_map(write(tmp_path, pgm(raw), mode="raw", negate=1))  # negate does not apply to raw
    o, f, u = OCCUPIED, FREE, UNKNOWN
    assert grid.cells.tolist() == [[f, f, u, o, o, u, u]]


def test_plain_pgm_and_16_bit(tmp_path):
    text = b"P2\n# a comment\n3 2\n100\n0 50 100\n100 100 0\n"
    grid = read_map(write(tmp_path, text))
    assert grid.cells.tolist() == [[OCCUPIED, UNKNOWN, FREE], [FREE, FREE, OCCUPIED]]
    wide = np.array([[0, 65535]], dtype=np.uint16)
    assert read_map(write(tmp_path, pgm(wide, 65535))).cells.tolist() == [[OCCUPIED, FREE]]


def test_row_zero_is_the_top(tmp_path):
    cells = np.full((4, 3), 254, dtype=np.uint8)
    cells[0, 0] = 0  # top left
    grid = read_map(write(tmp_path, pgm(cells)))
    assert grid.value_at(1.0 + 0.025, -2.0 + 4 * 0.05 - 0.025) == OCCUPIED
    assert grid.value_at(1.0 + 0.025, -2.0 + 0.025) == FREE


@pytest.mark.parametrize(
    ("image", "says"),
    [
        (b"P5\n4 3\n255\n" + bytes(13), "header disagrees with its data"),  # one byte too many
        (b"P5\n3 4\n255\n" + bytes(11), "truncated"),
        (b"P5\n2 2\n100\n" + bytes([0, 0, 0, 200]), "above the maxval 100"),
        (b"P2\n2 2\n255\n0 0 0\n", "header disagrees with its data"),
        (b"P2\n2 2\n255\n0 0 0 0 0\n", "header disagrees with its data"),
        (b"P2\n2 2\n255\n0 x 0 0\n", "expected a whole number"),
        (b"P5\n2 2\n70000\n" + bytes(8), "maxval 70000"),
        (b"P5\n0 2\n255\n", "at least 1 x 1"),
        (b"P5\n99999 99999\n255\n" + bytes(4), "over the limit"),
        (b"hello, no image", "not a map image"),
    ],
)
def test_bad_images_are_refused_by_name(tmp_path, image, says):
    with pytest.raises(InputError) as caught:
        read_map(write(tmp_path, image))
    message = str(caught.value)
    assert says in message and "m.pgm" in message and "\n" not in message


def test_png_header_must_agree(tmp_path):
    ok, data = cv2.imencode(".png", np.full((3, 5), 254, dtype=np.uint8))
    assert ok
    png = bytearray(data.tobytes())
    png[16:24] = (50000).to_bytes(4, "big") * 2  # claims 50000 x 50000 pixels
    with pytest.raises(InputError, match="over the limit"):
        read_map(write(tmp_path, bytes(png), name="m.png"))
    assert read_map(write(tmp_path, data.tobytes(), name="m.png")).cells.shape == (3, 5)


@pytest.mark.parametrize(
    ("meta", "says"),
    [
        ({"origin": [0.0, 0.0, 0.5]}, "origin yaw 0.5"),
        ({"resolution": 0}, "resolution"),
        ({"resolution": -0.05}, "resolution"),
        ({"resolution": 1e-6}, "resolution"),
        ({"resolution": float("nan")}, "resolution"),
        ({"negate": 2}, "negate"),
        ({"mode": "fancy"}, "mode"),
        ({"occupied_thresh": 1.5}, "occupied_thresh"),
        ({"occupied_thresh": 0.2, "free_thresh": 0.6}, "free_thresh 0.6 is above occupied_thresh"),
        ({"image": "absent.pgm"}, "'absent.pgm' not found"),
    ],
)
def test_bad_yaml_is_one_line(tmp_path, meta, says):
    with pytest.raises(InputError) as caught:
        read_map(write(tmp_path, pgm(LEVELS), **meta))
    assert says in str(caught.value) and "m.yaml" in str(caught.value)
