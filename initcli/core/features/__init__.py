"""What the camera sees, as features (§3.3.1).

- :mod:`~initcli.core.features.classes` -- detector class names <-> BIM feature categories;
- :mod:`~initcli.core.features.detection_filter` -- sightings -> confirmed features S_object (Eq. 3);
- :mod:`~initcli.core.features.visibility` -- which BIM features a camera sees from many poses at once;
- :mod:`~initcli.core.features.marker_pose` -- the robot pose from one ArUco tag (the marker baseline).
"""
