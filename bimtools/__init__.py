"""bimtools: IFC (BIM) model in, per-storey site model out (the ``bim-extract`` command).

Data flows IFC -> :mod:`bimtools.ifc` (model access) -> :mod:`bimtools.extract`
(features, wall sections, occupancy) -> :mod:`bimtools.site` (typed records and their
file formats). :mod:`bimtools.extract.preview` draws a storey, :mod:`bimtools.cli` is the command face and
:mod:`bimtools.samples` writes the sample models. What both commands share (errors, input checks,
atomic outputs, the JSON Schemas) is in :mod:`bimkit`; the robot-side pipeline lives in
:mod:`initcli`.
"""

__version__ = "0.1.0"
