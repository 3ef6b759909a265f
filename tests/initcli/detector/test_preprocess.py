"""Letterbox preprocessing: fit, centre, pad with grey 114, and the boxes back to image pixels."""

from __future__ import annotations

import numpy as np
import pytest

from initcli.detector.preprocess import PAD_VALUE, Letterbox, letterbox, to_tensor_layout


def test_wide_image_is_scaled_to_fit_and_padded_top_and_bottom() -> None:
    image = np.full((240, 640, 3), 7, np.uint8)
    out, box = letterbox(image, (320, 320))
    assert out.shape == (320, 320, 3)
    assert box.scale == pytest.approx(0.5) and box.pad_x == 0.0 and box.pad_y == 100.0
    assert (out[:100] == PAD_VALUE).all() and (out[220:] == PAD_VALUE).all()
    assert (out[100:220] == 7).all()


def test_boxes_go_back_to_image_pixels() -> None:
    image = np.zeros((240, 640, 3), np.uint8)
    _, box = letterbox(image, (320, 320))
    back = box.to_image(np.array([[0.0, 100.0, 320.0, 220.0], [80.0, 110.0, 160.0, 160.0]]))
    assert back.tolist() == [[0.0, 0.0, 640.0, 240.0], [160.0, 20.0, 320.0, 120.0]]
    stretched = Letterbox(scale=0.5, pad_x=0.0, pad_y=0.0, scale_y=2.0)  # a plain resize
    assert stretched.to_image([10.0, 10.0, 20.0, 20.0]).tolist() == [[20.0, 5.0, 40.0, 10.0]]


def test_an_image_of_the_right_size_is_unchanged() -> None:
    image = np.random.default_rng(0).integers(0, 255, (320, 320, 3), dtype=np.uint8)
    out, box = letterbox(image, (320, 320))
    assert np.array_equal(out, image) and box == Letterbox(1.0, 0.0, 0.0)


def test_tensor_layout_is_nchw_scaled() -> None:
    image = np.zeros((2, 3, 3), np.uint8)
    image[1, 2] = [255, 51, 0]
    x = to_tensor_layout(image)
    assert x.shape == (1, 3, 2, 3) and x.dtype == np.float32
    assert x[0, :, 1, 2].tolist() == pytest.approx([1.0, 0.2, 0.0])
    assert x.sum() == pytest.approx(1.2)
