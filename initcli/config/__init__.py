"""The settings of bim-init, one package with one public door: this module.

Every tunable is written once, as a typed dataclass field with its one default, unit and range
(:mod:`bimkit.settings`); everything else is derived from those fields.

- :mod:`~initcli.config.session` -- the sections of ``site.yaml`` (:class:`SessionConfig`);
- :mod:`~initcli.config.sim` -- the ``sim:`` section and the named reality profiles;
- :mod:`~initcli.config.exploration` -- the ``exploration:`` section;
- :mod:`~initcli.config.matching` -- the matching options ``bim-init match`` and ``matching:`` share;
- :mod:`~initcli.config.load` -- reading, validating and merging ``site.yaml``;
- :mod:`~initcli.config.checks` -- checks across fields, after the schema's;
- :mod:`~initcli.config.schema` -- the JSON Schema generated from the records
  (``python -m initcli.config --write``);
- :mod:`~initcli.config.runtime` -- the config turned into what the algorithms take;
- :mod:`~initcli.config.building` -- the site model and storeys a config names.

The records of :mod:`initcli.core` that are sections of ``site.yaml`` (``registration:``,
``verification:``) live beside their algorithms and are composed here.
"""

from __future__ import annotations

from initcli.config.load import (
    check_resources,
    config_to_dict,
    load_config,
    parse_config,
    read_yaml,
    with_reality,
)
from initcli.config.runtime import (
    as_built_params,
    camera_of,
    followed_side,
    match_options,
    start_pose_degrees,
    turn_in_place_speed,
    wall_follow_params,
)
from initcli.config.schema import SCHEMA_PATH, site_config_schema
from initcli.config.session import (
    CameraPose,
    CameraSection,
    ConfirmSection,
    DetectorSection,
    ExplorationSection,
    FineTuningSection,
    LidarSection,
    LimitsSection,
    MatchingSection,
    Nav2Section,
    RobotSection,
    RosbridgeSection,
    SessionConfig,
    SiteSection,
    VerificationSection,
)
from initcli.config.sim import (
    REALITY_PROFILES,
    AsBuiltSection,
    OdometryNoiseSection,
    SimDetectorSection,
    SimOdometrySection,
    SimSection,
)

__all__ = [
    "REALITY_PROFILES",
    "SCHEMA_PATH",
    "AsBuiltSection",
    "CameraPose",
    "CameraSection",
    "ConfirmSection",
    "DetectorSection",
    "ExplorationSection",
    "FineTuningSection",
    "LidarSection",
    "LimitsSection",
    "MatchingSection",
    "Nav2Section",
    "OdometryNoiseSection",
    "RobotSection",
    "RosbridgeSection",
    "SessionConfig",
    "SimDetectorSection",
    "SimOdometrySection",
    "SimSection",
    "SiteSection",
    "VerificationSection",
    "as_built_params",
    "camera_of",
    "check_resources",
    "config_to_dict",
    "followed_side",
    "load_config",
    "match_options",
    "parse_config",
    "read_yaml",
    "site_config_schema",
    "start_pose_degrees",
    "turn_in_place_speed",
    "wall_follow_params",
    "with_reality",
]
