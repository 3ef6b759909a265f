"""Loading a site from a folder and from a bare features.csv."""

from __future__ import annotations

import math

import pytest

from bimkit.errors import InputError
from bimtools.site.features_csv import write_features
from bimtools.site.load import load_site
from bimtools.site.records import Feature

FEATURES = [
    Feature("62938", "Door", -6.38, -4.14, 1.0, 0.0, 1.05, 2.30, "L1", 0.0, "IfcDoor", "Door, 1"),
    Feature("96688", "Lift", -5.07, 0.0, 0.0, -1.0, 1.10, 2.12, "L1", 0.0, "IfcTransportElement", "Lift A"),
    Feature("94617", "Stairs", -3.39, 58.41, -1.0, 0.0, 1.19, 1.86, "L2", 3.2, "IfcStair", 'Stair "B"'),
]


def test_load_site_from_folder_and_from_csv(tmp_path):
    write_features(tmp_path / "features.csv", FEATURES)
    site = load_site(tmp_path)
    assert sorted(site.storeys) == ["L1", "L2"]
    assert [f.id for f in site.storey("L1").features] == ["62938", "96688"]
    with pytest.raises(InputError, match="valid storeys: 'L1', 'L2'"):
        site.storey("L9")
    assert math.isclose(load_site(tmp_path / "features.csv").storeys["L2"].features[0].y, 58.41)
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="no features.csv"):
        load_site(tmp_path / "empty")


def test_a_site_copied_without_the_map_its_manifest_names_is_refused(tmp_path):
    """site.json names each storey's map; a folder that lacks one (copied in part) is refused by
    name, not loaded as a storey without a map (a survey of it was "successful" and empty)."""
    from pathlib import Path

    from bimtools.extract.from_map import extract_map_site, write_map_site
    from bimtools.site.load import load_site as load
    from tests.bimtools.extract.test_from_map import corridor_cells, write_map_files

    yaml_path = write_map_files(tmp_path / "maps", corridor_cells())
    site = tmp_path / "site"
    write_map_site(site, extract_map_site(yaml_path), preview=False)
    assert load(site).storeys["corridor"].grid is not None
    for name in ("map_corridor.yaml", "map_corridor.pgm"):
        assert (site / name).exists()
    (site / "map_corridor.yaml").unlink()
    with pytest.raises(InputError, match=r"site\.json: storey 'corridor' names the map map_corridor\.yaml"):
        load(Path(site))
    assert load(site, with_maps=False).storeys["corridor"].grid is None  # asked without maps: fine
