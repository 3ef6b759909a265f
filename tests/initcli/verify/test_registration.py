"""What a registration claim records (summary.json's coarse verification, ``bim-init match``'s
report): the beams through walls only where they ruled out places alike."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np

from bimkit.schemas import schema_path
from bimtools.site.load import Site, StoreyModel
from bimtools.site.records import Feature
from initcli.core.features.classes import ClassMap
from initcli.core.filters.particle_filter import LikelihoodField
from initcli.core.geometry.se2 import Pose2D
from initcli.core.lidar.registration import RegistrationMap, register
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.lidar.scan_fit import BeamEnds
from initcli.verify.registration import (
    DECIDED_BY_REGISTRATION,
    SubmapRegistration,
    door_openings,
    registration_record,
)
from tests.helpers import walls_grid
from tests.initcli.core.lidar.test_registration import FLOOR, HALF_TURN, RES, drive, grid_of, line, thick_wall


def _found(walls, path):
    grid = grid_of(walls)
    ends = BeamEnds.of(drive(walls, path, Pose2D(3.0, -7.0, 1.0)))
    return register(ends, [RegistrationMap("L1", grid, LikelihoodField(grid))], RegistrationParams(), 0.25)


def _schema() -> dict:
    schema = json.loads(schema_path("match_result.schema.json").read_text())["properties"]["registration"]
    return {**schema, "type": "object"}


def test_a_claim_that_ruled_out_places_alike_records_their_beams_through_walls() -> None:
    found = _found(HALF_TURN, line(2.0, 1.2, 28.0, 1.2))
    assert found.unique and found.best is not None and found.contested
    record = registration_record(found.best, found, blind=True).as_dict()
    jsonschema.validate(record, _schema())
    assert record["decided_by"] == DECIDED_BY_REGISTRATION and record["negative_evidence"] is False
    assert record["registration_through"] == [round(s, 4) for s in found.through]
    assert record["registration_through"][1] > record["registration_through"][0]
    assert record["registration_doors_open"] is False  # the map as drawn ruled them out


def test_a_claim_unique_by_its_fit_records_no_beams_through_walls() -> None:
    found = _found(FLOOR, line(8.0, 2.5, 8.0, 6.0) + line(8.0, 6.0, 18.0, 6.0))
    assert found.unique and found.best is not None and not found.contested
    record = registration_record(found.best, found, blind=False).as_dict()
    jsonschema.validate(record, _schema())
    assert "registration_through" not in record and record["negative_evidence"] is True


def test_the_doors_opened_in_the_map_are_the_model_s_doors_and_lift_doors() -> None:
    def feature(category: str, ifc_class: str, x: float) -> Feature:
        return Feature(f"{category}{x}", category, x, 1.0, 0.0, -1.0, 0.9, 2.1, "L1", 0.0, ifc_class)

    rows = [
        feature("Door", "IfcDoor", 1.0),
        feature("Lift", "IfcDoor", 2.0),  # a lift's landing door
        feature("Stairs", "IfcStair", 3.0),
        feature("Doors", "", 4.0),  # a feature table with no IfcClass column (the paper's Table 1)
        feature("ConcaveCorner", "", 5.0),
        feature("Door", "IfcDoorStandardCase", 6.0),
        feature("Lifts", "", 7.0),
    ]
    doors = door_openings(rows, ClassMap())
    assert doors[:, 0].tolist() == [1.0, 2.0, 4.0, 6.0, 7.0]
    assert doors[0].tolist() == [1.0, 1.0, 0.0, -1.0, 0.9]
    assert door_openings([], ClassMap()).shape == (0, 5)


def test_the_storey_s_maps_place_the_submap_with_the_doors_shut_and_cross_walls_with_them_open() -> None:
    """A model whose section leaves its doorway free (a door in the middle of a 0.3 m wall): the
    submap is placed on the map with the door shut (a beam ending on its leaf fits), the first
    wall-crossing test reads the map as drawn and the second the map with the door open."""
    grid = walls_grid(thick_wall([(4.5, 5.5)]), RES)
    door = Feature("d1", "Door", 5.0, 2.55, 0.0, -1.0, 1.0, 2.1, "L1", 0.0, "IfcDoor")
    site = Site(Path("site"), {"L1": StoreyModel("L1", 0.0, [door], grid=grid)})
    [m] = SubmapRegistration(RegistrationParams(), site, None, 0.25).maps()

    def d(f: LikelihoodField, x: float, y: float) -> float:  # m to the nearest wall
        return float(f.lookup(np.array([x]), np.array([y]))[0])

    assert d(m.fit, 5.0, 2.55) == 0.0 and d(m.field_, 5.0, 2.55) > 0.3  # on the leaf
    assert abs(d(m.fit, 5.0, 2.2) - 0.2) < 0.01 < 0.5 < d(m.field_, 5.0, 2.2)  # 0.2 m before the shut face
    assert d(m.through, 4.4, 2.4) > 0.0 and d(m.field_, 4.4, 2.4) == 0.0  # the jamb opened
    bare = Site(Path("site"), {"L1": StoreyModel("L1", 0.0, [], grid=grid)})
    [plain] = SubmapRegistration(RegistrationParams(), bare, None, 0.25).maps()
    assert plain.fit is plain.field_ is plain.through  # no doors: one map
