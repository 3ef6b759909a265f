"""The storey's geometry that the simulator and the survey share (no robot, no session).

- :mod:`~initcli.storey.outlines` -- outlines as segments: :func:`~initcli.storey.outlines.polygon_edges`,
  :func:`~initcli.storey.outlines.closed_ring`, :func:`~initcli.storey.outlines.box_edges`,
  :func:`~initcli.storey.outlines.box_ring`;
- :mod:`~initcli.storey.doors` -- closed door leaves across the design's door openings:
  :func:`~initcli.storey.doors.door_ids`, :func:`~initcli.storey.doors.door_leaf`,
  :func:`~initcli.storey.doors.closed_doors` (``LEAF_CLASS``, ``LEAF_THICKNESS``, ``DoorFeature``);
- :mod:`~initcli.storey.circulation` -- the circulation area of the storey map:
  :class:`~initcli.storey.circulation.Circulation`, and
  :class:`~initcli.storey.circulation.NoFreeSpace` for a map without free space.
"""
