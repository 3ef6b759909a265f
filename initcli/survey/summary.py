"""The per-storey numbers of ``survey.json``: the distance to a unique match, the shut-in rooms, the
lidar twins and a self-similar storey."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from initcli.survey.run import StoreySurvey

__all__ = ["UNIQUE_WITHIN", "summarise"]

UNIQUE_WITHIN = (5.0, 10.0, 20.0)  # m: the shares of survey.json


def summarise(result: StoreySurvey) -> dict[str, object]:
    """The per-storey numbers of ``survey.json``."""
    d = result.distance
    n = len(d)
    cell = result.params.spacing**2
    finite = d[np.isfinite(d)]
    median = float(np.median(d)) if n else math.inf
    twin = result.plan.twin
    lidar = result.lidar_distance
    return {
        "storey": result.plan.name,
        "samples": n,
        "positions": len(result.plan.positions),
        "headings": result.params.headings,
        "area_m2": round(len(result.plan.positions) * cell, 2),
        "unique_within": {
            f"{int(r)}m": round(float(np.mean(d <= r)) if n else 0.0, 4) for r in UNIQUE_WITHIN
        },
        "median_distance_m": round(median, 2) if math.isfinite(median) else None,
        "mean_distance_m": round(float(finite.mean()), 2) if len(finite) else None,
        "never_unique_share": round(float(np.mean(~np.isfinite(d))) if n else 0.0, 4),
        "never_unique_area_m2": round(float(result.position_never.sum() * cell), 2),
        # the share the session's lidar registration places within the limit (null: registration off)
        "lidar_placed_share": None
        if lidar is None
        else round(float(np.mean(np.isfinite(lidar))) if n else 0.0, 4),
        # rooms closed off by their doors: a robot there is shut in (cannot initialise from here)
        "shut_in_area_m2": round(sum(r.area_m2 for r in result.plan.shut_in), 1),
        "shut_in_rooms": [{"x": r.x, "y": r.y, "area_m2": r.area_m2} for r in result.plan.shut_in],
        # spaces a lidar alone cannot place, doors shut: with the camera off a start there fails
        "lidar_twins": [dataclasses.asdict(t) for t in result.plan.lidar_twins],
        "lidar_twin_area_m2": round(sum(t.area_m2 for t in result.plan.lidar_twins), 1),
        "lidar_twin_start_share": round(result.plan.lidar_twin_start_share, 4),
        "lidar_twin_tolerance_m": round(result.params.scan_tolerance, 3),
        # the storey is itself turned: every start has a twin (a session fails at once there)
        "self_similar": None
        if twin is None
        else {
            "turn_deg": round(twin.degrees, 1),
            "x": round(twin.centre[0], 3),
            "y": round(twin.centre[1], 3),
            "tolerance_m": round(twin.tolerance, 3),
        },
    }
