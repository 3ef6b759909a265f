"""Output-layout inference from the tensor shape, and class-aware NMS."""

from __future__ import annotations

import numpy as np

from initcli.detector.layouts import infer_layout, nms


def test_layout_inference_rules():
    assert infer_layout((1, 84, 8400), 80) == ("yolov8", 80)
    assert infer_layout((1, 7, 1600), None) == ("yolov8", 3)
    assert infer_layout((1, 300, 6), 80) == ("nms", 80)
    assert infer_layout((1, 25200, 85), 80) == ("yolov5", 80)
    assert infer_layout((1, 8400, 84), 80) == ("yolov8t", 80)


def test_class_aware_nms():
    boxes = np.array([[0, 0, 10, 10], [1, 1, 11, 11], [0, 0, 10, 10], [50, 50, 60, 60]], np.float32)
    scores = np.array([0.9, 0.8, 0.7, 0.6], np.float32)
    classes = np.array([0, 0, 1, 0])
    assert nms(boxes, scores, classes, 0.5).tolist() == [0, 2, 3]
