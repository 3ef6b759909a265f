"""Detection metrics (precision, recall, mAP) on hand-made cases."""

from __future__ import annotations

import numpy as np
import pytest

from initcli.detector.metrics import MetricAccumulator, average_precision


def test_metrics_known_cases():
    gt = np.array([[0, 0, 10, 10], [20, 20, 30, 30]], float)
    acc = MetricAccumulator(2)
    acc.add(
        np.array([[0, 0, 10, 10], [20, 20, 30, 31], [40, 40, 50, 50]], float),
        np.array([0.9, 0.8, 0.3]),
        np.array([0, 0, 0]),
        gt,
        np.array([0, 0]),
    )
    m = acc.compute(["door", "lift"], conf=0.5)
    door = m.classes[0]
    assert door.ap50 == pytest.approx(1.0) and door.precision == 1.0 and door.recall == 1.0
    assert m.classes[1].ap50 is None and m.map50 == pytest.approx(1.0)
    assert average_precision(np.array([False, True]), np.array([0.9, 0.8]), 1) == pytest.approx(0.5)
    assert average_precision(np.array([], bool), np.array([]), 3) == 0.0
