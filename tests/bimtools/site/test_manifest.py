"""site.json (the site manifest): round trip."""

from __future__ import annotations

from bimtools.site.manifest import SiteManifest, format_manifest, read_manifest
from bimtools.site.records import StoreyInfo


def test_manifest_round_trip(tmp_path):
    manifest = SiteManifest(
        "a.ifc",
        "00" * 32,
        "IFC4",
        "Tool",
        "METRE",
        1.0,
        1.0,
        0.05,
        [StoreyInfo("L1", 0.0, {"Door": 3}, "map_L1.yaml", "preview_L1.png")],
        ["features.csv"],
        "0.1.0",
    )
    (tmp_path / "site.json").write_text(format_manifest(manifest))
    assert read_manifest(tmp_path / "site.json") == manifest


def test_a_format_this_version_does_not_read_is_one_line(tmp_path):
    """site.json of a format version that does not exist (yet) is refused, not read as today's."""
    import json

    import pytest

    from bimkit.errors import InputError

    manifest = SiteManifest("a.ifc", "00" * 32, "IFC4", "Tool", "METRE", 1.0, 1.0, 0.05, [], [], "0.1.0")
    doc = json.loads(format_manifest(manifest))
    doc["format"] = "bim-init.site/9"
    (tmp_path / "site.json").write_text(json.dumps(doc))
    with pytest.raises(InputError, match="format 'bim-init.site/9' is not one this bim-init reads"):
        read_manifest(tmp_path / "site.json")
