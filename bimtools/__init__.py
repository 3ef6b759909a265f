"""bimtools: IFC (BIM) model in, per-storey site model out.

Data flows IFC -> :mod:`bimtools.ifc` (model access) -> :mod:`bimtools.extract`
(features, wall sections, occupancy) -> :mod:`bimtools.site` (typed records and their
file formats). The robot-side pipeline lives in :mod:`initcli`.
"""

__version__ = "0.1.0"
