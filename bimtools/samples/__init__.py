"""Deterministic sample IFC4 models of the paper's three test environments, with ground truth.

- ``ntu_hallway``: university hallway, two parallel 84 m corridors joined by three 7 m links
  (189 m of 2 m corridor), 38 doors and 5 lifts, no IfcSpace.
- ``block_a``: residential floor, straight 61.3 m corridor, lift lobby in the middle;
  13 unit main gates, 3 lifts, 2 staircases; IfcSpace per room.
- ``block_b``: residential floor, L-shaped 62.8 m corridor, lift lobby at the west end;
  same element counts as block_a; IfcSpace per room.

:func:`build` returns the model and its ground truth in memory; ``python -m bimtools.samples``
writes ``<name>.ifc`` and ``<name>.truth.json``. Plans live in :mod:`bimtools.samples.layouts`,
the IFC construction (and its placement conventions) in :mod:`bimtools.samples.ifc_writer`.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import ifcopenshell

from bimtools.samples.ifc_writer import write_model
from bimtools.samples.layouts import truth_document
from bimtools.samples.plans import PLANS, plan
from bimtools.site.records import Feature

MODELS: tuple[str, ...] = tuple(PLANS)


def build(name: str) -> tuple[ifcopenshell.file, dict[str, Any]]:
    """Build sample model ``name`` in memory: the IFC file and its ground-truth document."""
    floor = plan(name)
    written = write_model(floor)
    return written.model, truth_document(floor, written.door_guids())


def ifc_text(model: ifcopenshell.file) -> str:
    """The STEP text of a model exactly as :func:`write` stores it."""
    return model.to_string()


def truth_text(truth: dict[str, Any]) -> str:
    """The JSON text of a ground-truth document exactly as :func:`write` stores it (one feature a line)."""
    lines = []
    for key, value in truth.items():
        if isinstance(value, list) and value and isinstance(value[0], dict):
            items = ",\n".join(f"  {json.dumps(v)}" for v in value)
            lines.append(f" {json.dumps(key)}: [\n{items}\n ]")
        else:
            lines.append(f" {json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(lines) + "\n}\n"


def write(name: str, out_dir: Path) -> tuple[Path, Path]:
    """Write ``<out_dir>/<name>.ifc`` and ``<out_dir>/<name>.truth.json``; return both paths."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    model, truth = build(name)
    ifc_path, truth_path = out_dir / f"{name}.ifc", out_dir / f"{name}.truth.json"
    ifc_path.write_text(ifc_text(model), encoding="utf-8", newline="\n")
    truth_path.write_text(truth_text(truth), encoding="utf-8", newline="\n")
    return ifc_path, truth_path


def truth_features(truth: dict[str, Any]) -> list[Feature]:
    """The ground-truth features of a truth document as :class:`Feature` records."""
    return [
        Feature(
            id=f["ID"],
            category=f["Category"],
            x=f["X"],
            y=f["Y"],
            norm_x=f["Norm_X"],
            norm_y=f["Norm_Y"],
            width=f["Width"],
            height=f["Height"],
            storey=f["Storey"],
            elevation=f.get("Elevation", 0.0),
            ifc_class=f["IfcClass"],
            name=f["Name"],
        )
        for f in truth["features"]
    ]


__all__ = ["MODELS", "build", "ifc_text", "truth_features", "truth_text", "write"]
