"""The ``sim:`` section of the session config: the simulated robot's world, sensors and their errors,
each setting written once with its unit, range and default (:mod:`bimkit.settings`).

The simulator (:mod:`initcli.sim`) reads these records; they import nothing of it, so the config
and the simulator do not import each other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bimkit.checks import show_number
from bimkit.settings import section, setting

__all__ = [
    "REALITY_PROFILES",
    "AsBuiltParams",
    "AsBuiltSection",
    "OdometryNoiseSection",
    "PROFILE_REPLACES",
    "PersistentDetectorErrors",
    "SimDetectorSection",
    "SimOdometrySection",
    "SimSection",
]


@dataclass
class AsBuiltSection:
    """How the simulated site deviates from its design model (:mod:`initcli.sim.as_built`)."""

    missing_doors: float = setting(
        0.0, "share of doors not installed (no leaf, a free doorway, nothing to detect)", minimum=0, maximum=1
    )
    door_shift: float = setting(
        0.0, "m, sigma: doors built off their design place along the host wall", minimum=0, maximum=5
    )
    wall_offset: float = setting(
        0.0, "m, sigma: every other element built off its place", minimum=0, maximum=1
    )
    open_doors: float = setting(
        0.0,
        "share of installed doors standing open (no obstacle, still a door to the camera)",
        minimum=0,
        maximum=1,
    )
    hoarding: float = setting(
        0.0,
        "temporary walls not in the BIM per 100 m of corridor (across a corridor or in front of a room)",
        minimum=0,
        maximum=50,
    )
    extra_doors: float = setting(
        0.0, "doors on site the model lacks, per 100 m of corridor", minimum=0, maximum=50
    )
    clutter_in_corridor: float = setting(
        0.0,
        "share of the material stacks (sim.clutter) standing out in the corridor, not against a wall",
        minimum=0,
        maximum=1,
    )


@dataclass
class PersistentDetectorErrors:
    """What the simulated detector gets wrong persistently (beyond sim.miss_rate per image)."""

    persistent_phantoms: float = setting(
        0.0,
        "per 100 m of corridor: a poster or panel detected as a door every time it is in view",
        minimum=0,
        maximum=50,
    )
    never_seen: float = setting(
        0.0, "share of the real features the detector never fires on", minimum=0, maximum=1
    )


PROFILE_REPLACES = ("miss_rate", "false_positives_per_minute", "confusion_rate")  # of sim:


@dataclass
class SimDetectorSection(PersistentDetectorErrors):
    """The simulated detector's persistent errors, and the measured profile it may draw from."""

    profile: str = setting(
        "",
        "a detector profile (bim-init detector calibrate): default-real (the shipped model on real"
        " photos), default-renders (on renders) or a JSON file, relative to this file; the simulated"
        " detector then draws recall by box height, false boxes per image, class confusion and scores"
        " from it, in place of sim.miss_rate, sim.false_positives_per_minute and sim.confusion_rate"
        " (a config that sets one of those and a profile is refused); empty: those three",
    )


@dataclass
class SimOdometrySection:
    """Systematic odometry errors (on top of sim.odometry_noise's random walk)."""

    scale_error: float = setting(
        0.0, "share of distance counted too far (0.02: a 2 % wheel-radius error)", minimum=-0.5, maximum=0.5
    )
    slip: float = setting(
        0.0,
        "wheel-slip events per 100 m (odometry counts 5-30 cm and a few degrees that did not happen)",
        minimum=0,
        maximum=100,
    )


@dataclass
class OdometryNoiseSection:
    """Drift of the robot's odometry (wheels fused with the IMU, as on the paper's robot); variances
    grow with each step's motion (see initcli.sim.robot)."""

    alpha1: float = setting(0.0001, "rad^2/rad: rotation variance per radian turned", minimum=0, maximum=1)
    alpha2: float = setting(0.00001, "rad^2/m: rotation variance per metre driven", minimum=0, maximum=1)
    alpha3: float = setting(0.0004, "m^2/m: translation variance per metre driven", minimum=0, maximum=1)
    alpha4: float = setting(0.0001, "m^2/rad: translation variance per radian turned", minimum=0, maximum=1)


@dataclass
class AsBuiltParams(PersistentDetectorErrors, AsBuiltSection):
    """Every deviation of the simulated world from the design (sim.as_built and sim.detector's
    persistent errors; all 0: the design), as :func:`initcli.sim.as_built.derive_as_built` takes them."""


# Named realities (sim.reality): values for the keys above that the config does not set itself.
REALITY_PROFILES: dict[str, dict[str, dict[str, float]]] = {
    "ideal": {},
    "construction": {
        "as_built": {
            "missing_doors": 0.2,
            "door_shift": 0.3,
            "wall_offset": 0.05,
            "open_doors": 0.3,
            "hoarding": 1.0,
            "extra_doors": 0.5,
            "clutter_in_corridor": 0.5,
        },
        "detector": {"persistent_phantoms": 1.0, "never_seen": 0.1},
        "odometry": {"scale_error": 0.02, "slip": 1.0},
    },
}


def _profiles() -> str:
    """The named profiles' values, as the description of sim.reality lists them."""
    return "; ".join(
        f"{name}: "
        + ", ".join(f"{k} {show_number(v)}" for values in sections.values() for k, v in values.items())
        for name, sections in REALITY_PROFILES.items()
        if sections
    )


START_SCHEMA: dict[str, Any] = {
    "oneOf": [
        {"const": "random"},
        {
            "type": "array",
            "minItems": 3,
            "maxItems": 3,
            "items": {"type": "number", "minimum": -1000000, "maximum": 1000000},
        },
    ]
}


@dataclass
class SimSection:
    """The simulated robot (robot.driver sim): where it starts, the building it drives in, what the
    site and its sensors get wrong."""

    start: Any = setting(
        "random",
        '"random" or [x, y, yaw_degrees] in the BIM frame (m, m, degrees; each within +-1000000); a'
        " start outside the building or inside a wall is refused",
        schema=START_SCHEMA,
    )
    refuse_enclosed: bool = setting(
        True,
        "a given start in a space closed off from where the features face (closed doors, hoardings, gaps"
        " narrower than the robot) is refused at 0 m, as the simulator knows; false: the session runs from"
        " there and finds out itself, as a live robot must (exploration.laps: shut in)",
    )
    world: str = setting(
        "",
        "the building the simulated robot drives in, senses and detects features in (an IFC file or a"
        " bim-extract OUTDIR, relative to this file); empty: site.path, the BIM it matches against",
    )
    reality: str = setting(
        "ideal",
        "a named profile: values for the sim.as_built, sim.detector and sim.odometry keys this file"
        f" leaves unset ({_profiles()})",
        enum=tuple(REALITY_PROFILES),
    )
    as_built: AsBuiltSection = section(
        AsBuiltSection, "the site as built, derived from the design model with the session's seed"
    )
    detector: SimDetectorSection = section(
        SimDetectorSection, "persistent detector errors and a measured detector profile"
    )
    odometry: SimOdometrySection = section(SimOdometrySection, "systematic odometry errors")
    odometry_noise: OdometryNoiseSection = section(
        OdometryNoiseSection, "the odometry's random walk: variances that grow with each step's motion"
    )
    clutter: float = setting(0.05, "material stacks per metre of corridor wall", minimum=0, maximum=10)
    people: int = setting(
        2,
        "people walking about the corridors, moving obstacles the lidar and the camera see (named"
        " sim.workers before; that name is still read, with a warning)",
        minimum=0,
        maximum=1000,
    )
    miss_rate: float = setting(
        0.1, "chance a visible feature is not detected in an image", minimum=0, maximum=1
    )
    false_positives_per_minute: float = setting(
        1.0,
        "false detections per minute of images: a random class at a random place, not persistent",
        minimum=0,
        maximum=1000,
    )
    confusion_rate: float = setting(0.02, "chance a detection gets another class", minimum=0, maximum=1)
    phantoms: int = setting(
        0, "persistent door-like things that are not in the BIM (posters, openings)", minimum=0, maximum=1000
    )
    seed: int = setting(1, "random seed", minimum=0, maximum=4294967295)
    kidnap: float = setting(
        0.0,
        "m of travel after which the robot is carried to a random free place, its wheels unaware (the"
        " watch method of bim-init eval: its localiser stand-in keeps tracking the old place); 0: never",
        minimum=0,
        maximum=100000,
    )
