"""features.csv (Table 1): round trips, a hand-written table, errors that name the line."""

from __future__ import annotations

from pathlib import Path

import pytest

from bimkit.errors import InputError
from bimtools.site.features_csv import format_features, read_features, write_features
from bimtools.site.records import TABLE1_COLUMNS, Feature

FEATURES = [
    Feature("62938", "Door", -6.38, -4.14, 1.0, 0.0, 1.05, 2.30, "L1", 0.0, "IfcDoor", "Door, 1"),
    Feature("96688", "Lift", -5.07, 0.0, 0.0, -1.0, 1.10, 2.12, "L1", 0.0, "IfcTransportElement", "Lift A"),
    Feature("94617", "Stairs", -3.39, 58.41, -1.0, 0.0, 1.19, 1.86, "L2", 3.2, "IfcStair", 'Stair "B"'),
]


def test_features_csv_round_trip(tmp_path):
    path = tmp_path / "features.csv"
    write_features(path, FEATURES)
    assert path.read_text().splitlines()[0].split(",")[:8] == list(TABLE1_COLUMNS)
    assert read_features(path) == FEATURES


def test_hand_written_table1_is_enough(tmp_path):
    path = tmp_path / "table1.csv"
    path.write_text("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n62938,Door,-6.38,-4.14,2,0,1.05,2.30\n")
    (feature,) = read_features(path)
    assert feature.id == "62938" and feature.storey == "" and feature.norm_x == 1.0


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("ID,Category,X,Y\n1,Door,0,0\n", "missing column(s) Norm_X"),
        (
            "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,abc,0,1,0,1,2\n",
            ":2: column X: expected a number",
        ),
        (
            "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,0,0,1,0,1,2\n2,Door,0,0,0,0,1,2\n",
            ":3: Norm_X, Norm_Y is the zero",
        ),
        ("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n,Door,0,0,1,0,1,2\n", ":2: column ID is empty"),
        (
            "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,0,0,1,0,1000000,2\n",
            ":2: column Width is 1e.06 m; no door",
        ),
        ("ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,0,0,1,0,1,-2\n", ":2: column Height is -2 m"),
        (
            "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n7,Door,0,0,1,0,1,2\n8,Lift,5,0,1,0,1,2\n7,Door,9,0,1,0,1,2\n",
            ":4: ID 7 on storey '' is on line 2 already",
        ),
    ],
)
def test_features_csv_errors_name_the_line(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        read_features(path)


def test_format_features_has_no_negative_zero():
    text = format_features([Feature("a", "Door", 0, 0, -1e-17, -1.0, 1, 2)])
    assert "-0.000000" not in text


def test_a_stray_carriage_return_is_one_line_of_error(tmp_path: Path) -> None:
    """Found by the fuzz test: a bare CR inside a field made the csv module raise its own error."""
    path = tmp_path / "features.csv"
    path.write_bytes(b"ID,Category,X,Y,Norm_X,Norm_Y,Width,Height\n1,Door,0,0,1,0\r\x01,1,2\n")
    with pytest.raises(InputError, match=r"features\.csv:\d+: "):
        read_features(path)


def test_one_element_on_two_storeys_is_two_rows(tmp_path: Path) -> None:
    """A lift has a feature per storey it serves, all with its GlobalId: not a duplicate."""
    path = tmp_path / "features.csv"
    head = "ID,Category,X,Y,Norm_X,Norm_Y,Width,Height,Storey,Elevation,IfcClass,Name\n"
    path.write_text(
        head + "L1,Lift,0,0,1,0,1,2,Level 1,0,IfcTransportElement,lift\n"
        "L1,Lift,0,0,1,0,1,2,Level 2,3,IfcTransportElement,lift\n"
    )
    assert [f.storey for f in read_features(path)] == ["Level 1", "Level 2"]
