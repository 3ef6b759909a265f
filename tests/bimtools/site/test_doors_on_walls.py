"""A site whose doors stand away from its walls is refused: another building's features.csv beside
this one's walls.geojson (a door stands in a wall); a door or two off the walls passes."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from bimkit.errors import InputError
from bimtools.site.load import load_site


def _shifted(site_a: Path, tmp_path: Path, doors: int | None, dx: float) -> Path:
    """A copy of the site with the first ``doors`` doors (None: all) moved ``dx`` m in x."""
    site = tmp_path / "site"
    shutil.copytree(site_a, site)
    path = site / "features.csv"
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    moved = 0
    for row in rows:
        if row["Category"] == "Door" and (doors is None or moved < doors):
            row["X"] = f"{float(row['X']) + dx:.4f}"
            moved += 1
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return site


def test_the_extracted_site_loads(site_a):
    assert load_site(site_a).storeys


def test_another_buildings_doors_are_refused_by_name(site_a, tmp_path):
    site = _shifted(site_a, tmp_path, None, 40.0)
    with pytest.raises(
        InputError, match=r"features\.csv: \d+ of the \d+ doors of storey .* lie more than 1 m"
    ):
        load_site(site)


def test_a_door_or_two_off_the_walls_pass(site_a, tmp_path):
    site = _shifted(site_a, tmp_path, 1, 40.0)
    assert load_site(site).storeys
