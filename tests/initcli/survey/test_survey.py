"""The survey (initcli.survey.plan, sequences, run, summary, landmarks) on a tiny walled room:
features, occluders, the start plan, one small survey, its per-position numbers and the summary of
survey.json."""

from __future__ import annotations

import math
import time
from types import SimpleNamespace

import numpy as np
import pytest

from bimtools.site.load import StoreyModel
from bimtools.site.records import FREE, OCCUPIED, Feature, Obstacle, OccupancyGrid, WallSegment
from initcli.core.features.classes import ClassMap
from initcli.survey.landmarks import landmark_candidates, suggest_landmarks
from initcli.survey.plan import SurveyParams, cumulative_sightings, occluders_of, plan_storey, storey_features
from initcli.survey.run import StoreySurvey, survey_storey
from initcli.survey.sequences import sample_views, sequences
from initcli.survey.summary import summarise

RES = 0.1
W, H = 8.0, 5.0  # m: the room's inside


def _room(with_grid: bool = True) -> StoreyModel:
    """An 8 m x 5 m room (walls on its border), doors and a lift on its walls facing inwards."""
    rows, cols = int(H / RES) + 2, int(W / RES) + 2
    cells = np.full((rows, cols), FREE, dtype=np.uint8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    grid = OccupancyGrid(cells, RES, (-RES, -RES, 0.0))
    features = [
        Feature("d1", "Door", 1.0, 0.0, 0.0, 1.0, 1.0, 2.1),
        Feature("d2", "Door", 2.5, 0.0, 0.0, 1.0, 1.0, 2.1),
        Feature("d3", "Door", 0.0, 3.5, 1.0, 0.0, 1.0, 2.1),
        Feature("l1", "Lift", 6.0, 5.0, 0.0, -1.0, 1.2, 2.2),
        Feature("s1", "Staircase", 8.0, 1.0, -1.0, 0.0, 1.2, 2.2),
    ]
    walls = [
        WallSegment("L0", "w1", "IfcWall", 0.0, 0.0, W, 0.0, (0.0, 1.0)),
        WallSegment("L0", "w2", "IfcWall", W, 0.0, W, H, (-1.0, 0.0)),
        WallSegment("L0", "w3", "IfcWall", W, H, 0.0, H, (0.0, -1.0)),
        WallSegment("L0", "w4", "IfcWall", 0.0, H, 0.0, 0.0, (1.0, 0.0)),
    ]
    return StoreyModel("L0", 0.0, features, walls, grid=grid if with_grid else None)


PARAMS = SurveyParams(spacing=2.0, headings=2, limit_m=40.0, min_sightings=2)


def test_storey_features_are_canonical_classes() -> None:
    f = storey_features(_room())
    assert f.cls == ("door", "door", "door", "lift", "stairs")
    assert f.xy.shape == (5, 2) and f.normal[3].tolist() == [0.0, -1.0]
    assert f.height.tolist() == [2.1, 2.1, 2.1, 2.2, 2.2]
    mapped = storey_features(_room(), ClassMap({"lift": "cabin"}))
    assert mapped.cls[3] == "cabin"


def test_occluders_are_walls_unless_there_are_obstacles() -> None:
    room = _room()
    assert occluders_of(room).tolist() == [[w.x1, w.y1, w.x2, w.y2] for w in room.walls]
    square = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.0, 0.0))
    hole = ((0.2, 0.2), (0.4, 0.2), (0.4, 0.4), (0.2, 0.2))
    room.obstacles = [Obstacle("L0", "c", "IfcColumn", square, (hole,))]
    edges = occluders_of(room)
    assert edges.shape == (4 + 3, 4)  # the walls are no longer used
    assert edges[0].tolist() == [0.0, 0.0, 1.0, 0.0] and edges[4].tolist() == [0.2, 0.2, 0.4, 0.2]


def test_cumulative_counts_over_two_laps() -> None:
    vis = np.array([[1, 0], [0, 1], [1, 1]], dtype=bool)
    cum = cumulative_sightings(vis)
    assert cum.shape == (7, 2)
    assert cum[:, 0].tolist() == [0, 1, 1, 2, 3, 3, 4]
    assert cum[:, 1].tolist() == [0, 0, 1, 2, 2, 3, 4]


def test_plan_storey_samples_starts_on_the_spacing_with_every_heading() -> None:
    plan = plan_storey(_room(), PARAMS)
    assert plan.name == "L0" and len(plan.loops) >= 1
    m = len(plan.positions)
    assert 4 <= m <= math.ceil(W / 2.0) * math.ceil(H / 2.0)
    assert plan.starts.shape == (2 * m, 3)
    assert sorted(set(np.round(plan.starts[:, 2], 6))) == [0.0, round(math.pi, 6)]
    assert plan.position.tolist() == np.repeat(np.arange(m), 2).tolist()
    x, y = plan.positions.T
    clear = PARAMS.start_clearance
    assert np.all((x >= clear - RES) & (x <= W - clear + RES) & (y >= clear - RES) & (y <= H - clear + RES))
    gaps = np.hypot(*(plan.positions[:, None] - plan.positions[None]).T)
    assert gaps[~np.eye(m, dtype=bool)].min() >= 1.0  # one start per 2 m x 2 m block
    assert plan.walls.shape == (4, 6)


def test_plan_storey_needs_a_map() -> None:
    with pytest.raises(ValueError, match="occupancy map"):
        plan_storey(_room(with_grid=False), PARAMS)


def test_survey_storey_distances_are_within_the_limit_or_never() -> None:
    started = time.perf_counter()
    result, views = survey_storey(plan_storey(_room(), PARAMS), PARAMS)
    d = result.distance
    assert d.shape == (len(result.plan.starts),)
    finite = d[np.isfinite(d)]
    assert np.all((finite >= 0.0) & (finite <= PARAMS.limit_m))
    assert len(views.entries) == len(d)
    doc = summarise(result)
    assert doc["samples"] == len(d) and doc["positions"] == len(result.plan.positions)
    assert doc["never_unique_share"] == round(float(np.mean(~np.isfinite(d))), 4)
    assert np.isfinite(d).all()  # five distinct features in an asymmetric room: every start ends unique
    assert time.perf_counter() - started < 30.0


def test_sequences_are_in_confirmation_order_and_unique_distance_is_one_of_them() -> None:
    plan = plan_storey(_room(), PARAMS)
    views = sample_views(plan, PARAMS)
    seqs, dists = sequences(plan, views, PARAMS)
    result, _ = survey_storey(plan, PARAMS)
    for seq, dist, unique in zip(seqs, dists, result.distance, strict=True):
        assert len(set(seq)) == len(seq) and set(seq) <= set(range(5))
        assert np.all(np.diff(dist) >= 0.0) and np.all(dist <= PARAMS.limit_m)
        assert np.isclose(dist, unique).any()
    only = sequences(plan, views, PARAMS, which=[3, 1])
    assert only[0] == [seqs[3], seqs[1]]


def test_a_room_with_one_door_is_never_unique() -> None:
    room = _room()
    room.features = room.features[:1]
    result, _ = survey_storey(plan_storey(room, PARAMS), PARAMS)
    assert not np.isfinite(result.distance).any()
    assert summarise(result)["never_unique_share"] == 1.0


def _fake(distance: list[float], position: list[int], positions: int, headings: int) -> StoreySurvey:
    plan = SimpleNamespace(
        name="L9",
        position=np.array(position),
        positions=np.zeros((positions, 2)),
        shut_in=[],
        twin=None,
        lidar_twins=[],
        lidar_twin_start_share=0.0,
    )
    params = SurveyParams(spacing=2.0, headings=headings, limit_m=30.0)
    return StoreySurvey(plan, np.array(distance, dtype=float), params)  # type: ignore[arg-type]


def test_position_values_cap_at_the_limit_and_average_headings() -> None:
    s = _fake([4.0, math.inf, 12.0, 50.0], [0, 0, 1, 1], positions=2, headings=2)
    assert s.position_distance.tolist() == [(4.0 + 30.0) / 2, (12.0 + 30.0) / 2]
    assert s.position_never.tolist() == [0.5, 0.0]


def test_summarise_numbers() -> None:
    s = _fake([4.0, math.inf, 12.0, 8.0], [0, 0, 1, 1], positions=2, headings=2)
    doc = summarise(s)
    assert doc["storey"] == "L9" and doc["samples"] == 4 and doc["headings"] == 2
    assert doc["area_m2"] == 8.0  # 2 positions of 2 m x 2 m
    assert doc["unique_within"] == {"5m": 0.25, "10m": 0.5, "20m": 0.75}
    assert doc["median_distance_m"] == 10.0
    assert doc["mean_distance_m"] == 8.0
    assert doc["never_unique_share"] == 0.25
    assert doc["never_unique_area_m2"] == 2.0  # half the headings of one 4 m^2 position
    assert doc["self_similar"] is None


def test_summarise_all_never_has_no_median() -> None:
    doc = summarise(_fake([math.inf, math.inf], [0, 0], positions=1, headings=2))
    assert doc["median_distance_m"] is None and doc["mean_distance_m"] is None
    assert doc["never_unique_share"] == 1.0


def _two_doors() -> StoreyModel:
    room = _room()
    room.features = room.features[:2]  # d1 (1, 0) and d2 (2.5, 0) on the bottom wall
    return room


def test_landmark_candidates_lie_on_walls_facing_in_and_off_the_features() -> None:
    plan = plan_storey(_two_doors(), PARAMS)
    cand = landmark_candidates(plan, PARAMS)
    assert len(cand) >= 4
    for x, y, nx, ny in cand:
        on = [w for w in plan.walls if abs((w[2] - w[0]) * (y - w[1]) - (w[3] - w[1]) * (x - w[0])) < 1e-9]
        assert on and (nx, ny) == tuple(on[0][4:6])
        assert np.hypot(*(plan.features.xy - [x, y]).T).min() >= 1.0
    assert [2.0, 0.0] not in cand[:, :2].tolist()  # 0.5 m from d2
    few = landmark_candidates(plan, SurveyParams(spacing=2.0, headings=2, landmark_candidates=2))
    assert len(few) == 2


def test_suggested_landmarks_make_an_ambiguous_room_unique() -> None:
    result, views = survey_storey(plan_storey(_two_doors(), PARAMS), PARAMS)
    assert not np.isfinite(result.distance).any()
    landmarks, after = suggest_landmarks(result, views, 2)
    assert [lm.cls for lm in landmarks] == ["landmark_1", "landmark_2"]
    assert len(after.plan.features) == 4 and after.plan.features.cls[2:] == ("landmark_1", "landmark_2")
    assert landmarks[-1].mean_distance_m < PARAMS.limit_m
    assert landmarks[-1].mean_distance_m <= landmarks[0].mean_distance_m
    assert np.isfinite(after.distance).sum() > 0
    assert landmarks[-1].mean_distance_m == pytest.approx(np.minimum(after.distance, PARAMS.limit_m).mean())


def _corridor_and_room() -> StoreyModel:
    """A 10 m x 2 m corridor (y 0-2) and a 4 m x 3 m room above it (y 2.2-5.2), joined by a 0.8 m
    door opening that the map leaves free; the 1 m door faces the corridor, as do two lifts."""
    rows, cols = int(5.4 / RES) + 2, int(10.0 / RES) + 2
    cells = np.full((rows, cols), OCCUPIED, dtype=np.uint8)
    cells[1 : int(2.0 / RES) + 1, 1:-1] = FREE  # the corridor
    cells[int(2.2 / RES) + 1 : int(5.2 / RES) + 1, int(3.0 / RES) + 1 : int(7.0 / RES) + 1] = FREE  # the room
    cells[int(2.0 / RES) : int(2.3 / RES) + 1, int(4.6 / RES) + 1 : int(5.4 / RES) + 1] = FREE  # the opening
    grid = OccupancyGrid(np.flipud(cells).copy(), RES, (-RES, -RES, 0.0))  # row 0 is the map's top
    features = [
        Feature("d1", "Door", 5.0, 2.0, 0.0, -1.0, 1.0, 2.1, ifc_class="IfcDoor"),
        Feature("l1", "Lift", 2.0, 0.0, 0.0, 1.0, 1.2, 2.2),
        Feature("l2", "Lift", 8.0, 0.0, 0.0, 1.0, 1.2, 2.2),
    ]
    return StoreyModel("L0", 0.0, features, [], grid=grid)


def test_starts_stay_out_of_a_room_behind_a_door_the_map_leaves_open() -> None:
    """The simulated world closes every door leaf: a session neither starts nor drives in the
    room, so the survey does not either, though the map's opening joins it to the corridor."""
    plan = plan_storey(_corridor_and_room(), SurveyParams(spacing=0.5, headings=1))
    assert len(plan.positions) > 10
    assert plan.positions[:, 1].max() < 2.0  # all in the corridor
    assert not plan.circulation.label[plan.circulation.grid.world_to_cell(5.0, 3.5)]  # the room's middle


def test_the_lidar_model_places_no_start_on_a_self_similar_storey() -> None:
    """The survey's lidar model (the session's registration along the loop) gives a distance per
    start; none is finite on a self-similar storey, where the session ends at once; with the
    registration off there is no lidar model at all."""
    import dataclasses
    import math as m

    from initcli.core.lidar.symmetry import Turn
    from initcli.survey.run import lidar_along

    plan = plan_storey(_room(), PARAMS)
    views = sample_views(plan, PARAMS)
    lidar = lidar_along(plan, views, PARAMS)
    assert lidar is not None and len(lidar) == len(plan.starts)
    assert len(plan.lidar_placed) == 1  # the loops registered once per settings ...
    again = lidar_along(plan, views, PARAMS)
    assert again is not None and np.array_equal(again, lidar)  # ... and read again
    twin = dataclasses.replace(plan, twin=Turn(m.pi, (W / 2, H / 2), 0.1))
    never = lidar_along(twin, views, PARAMS)
    assert never is not None and not np.isfinite(never).any()
    off = dataclasses.replace(PARAMS, registration=dataclasses.replace(PARAMS.registration, enabled=False))
    assert lidar_along(plan, views, off) is None
