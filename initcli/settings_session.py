"""The sections of the session config (``site.yaml``), each setting written once with its unit,
range and default (:mod:`initcli.settings`); the ``sim:`` section is :mod:`initcli.settings_sim`.

The sections are the records the code reads: ``matching:`` is
:class:`initcli.match.options.MatchingSettings` (the tunables ``bim-init match`` shares) with the
session's own added, ``verification:`` is :class:`initcli.core.verification_settings.VerificationParams`
with the session's rival search added. The tuning of the session's escapes (loops, shuttling),
active exploration's targets and the fine stage are settings here too.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from initcli.core.verification_settings import VerificationParams
from initcli.match.options import D_THRE, SCORE_THRESHOLD, MatchingSettings
from initcli.settings import section, setting
from initcli.settings_sim import SimSection

__all__ = [
    "CameraPose",
    "CameraSection",
    "ConfirmSection",
    "DetectorSection",
    "ExplorationSection",
    "FineTuningSection",
    "FrontierSettings",
    "LidarSection",
    "LapSettings",
    "LimitsSection",
    "LoopSettings",
    "MatchingSection",
    "Nav2Section",
    "RivalSettings",
    "RobotSection",
    "RosbridgeSection",
    "SessionConfig",
    "ShuttleSettings",
    "SiteSection",
    "TargetSettings",
    "VerificationSection",
]


@dataclass
class SiteSection:
    path: str = setting(
        "", "an IFC file or a bim-extract output folder, relative to this file", required=True
    )
    storey: str = setting("auto", "storey name, or auto (the only storey, or every storey when matching)")


@dataclass
class RosbridgeSection:  # robot.driver: rosbridge (initcli/ros/rosbridge_driver.py)
    host: str = setting("localhost", "the rosbridge server's host name or address")
    port: int = setting(9090, "the rosbridge server's port", minimum=1, maximum=65535)
    odom_topic: str = setting("/odom", "nav_msgs/Odometry")
    scan_topic: str = setting("/scan", "sensor_msgs/LaserScan")
    detections_topic: str = setting("/detections", "vision_msgs/Detection2DArray")
    depth_topic: str = setting(
        "/camera/aligned_depth_to_color/image_raw",
        "the depth image aligned with the colour image (16UC1 mm or 32FC1 m)",
    )
    cmd_vel_topic: str = setting("/cmd_vel", "geometry_msgs/Twist")
    camera_info_topic: str = setting(
        "/camera/color/camera_info", "sensor_msgs/CameraInfo: the intrinsics (camera: is the fallback)"
    )
    tf_static_topic: str = setting(
        "/tf_static", "tf2_msgs/TFMessage: the camera mount (camera.pose is the fallback)"
    )
    base_frame: str = setting(
        "", "the robot's base frame for the camera mount (empty: the odometry's child frame)"
    )
    camera_wait: float = setting(
        3.0,
        "s: how long to wait for CameraInfo and /tf_static before the site config's camera",
        minimum=0,
        maximum=60,
    )


@dataclass
class RobotSection:
    driver: str = setting(
        "sim",
        "sim: the simulated robot (sim:); rosbridge: a live robot over rosbridge",
        enum=("sim", "rosbridge"),
    )
    radius: float = setting(0.3, "m: the robot's footprint radius", above=0, maximum=2)
    max_linear: float = setting(0.5, "m/s: top linear speed", above=0, maximum=5)
    max_angular: float = setting(1.0, "rad/s: top turn rate", above=0, maximum=10)
    drive: bool = setting(True, "rosbridge: false listens only while a person drives")
    rosbridge: RosbridgeSection = section(
        RosbridgeSection, "robot.driver rosbridge: the rosbridge server and the robot's topics"
    )


@dataclass
class CameraPose:
    x: float = setting(0.2, "m: camera in the robot base frame", minimum=-10, maximum=10)
    y: float = setting(0.0, "m: camera in the robot base frame", minimum=-10, maximum=10)
    z: float = setting(1.0, "m: camera in the robot base frame", minimum=-10, maximum=10)
    roll: float = setting(0.0, "radians", minimum=-6.2832, maximum=6.2832)
    pitch: float = setting(0.0, "radians", minimum=-6.2832, maximum=6.2832)
    yaw: float = setting(0.0, "radians", minimum=-6.2832, maximum=6.2832)


@dataclass
class CameraSection:
    # 640x480 at ~90 degrees horizontal field of view (Intel D455 colour)
    fx: float = setting(320.0, "px: focal length", above=0, maximum=100000)
    fy: float = setting(320.0, "px: focal length", above=0, maximum=100000)
    cx: float = setting(320.0, "px: principal point", minimum=0, maximum=20000)
    cy: float = setting(240.0, "px: principal point", minimum=0, maximum=20000)
    width: int = setting(640, "px: image width", above=0, maximum=8192)
    height: int = setting(480, "px: image height", above=0, maximum=8192)
    pose: CameraPose = section(CameraPose, "the camera's mount on the robot")
    depth_noise: float = setting(
        0.005, "depth sigma = depth_noise * d^2 (0.005: 2 % at 4 m, Intel D455)", minimum=0, maximum=1
    )
    range: float = setting(6.0, "m: objects are detected up to this distance", above=0, maximum=100)
    # The simulated depth camera's nearest valid reading (detector.kind onnx renders the view and
    # reads its depth): nearer pixels read nothing. Not the detection filter's matching.min_depth.
    min_range: float = setting(
        0.3,
        "m: the rendered depth camera (detector.kind onnx) reads nothing nearer than this (and nothing"
        " beyond camera.range)",
        minimum=0,
        maximum=100,
    )
    max_view_angle: float = setting(75.0, "degrees from an element's normal", above=0, maximum=90)
    depth_window: int = setting(2, "n of the (2n+1)x(2n+1) depth window", minimum=0, maximum=50)


@dataclass
class LidarSection:
    beams: int = setting(360, "beams per scan", above=0, maximum=10000)
    fov: float = setting(360.0, "degrees: field of view", above=0, maximum=360)
    max_range: float = setting(20.0, "m: the farthest range the lidar reads", minimum=1, maximum=200)
    noise: float = setting(0.02, "m: range noise standard deviation", minimum=0, maximum=5)
    dropout: float = setting(0.01, "fraction of beams returning nothing", minimum=0, maximum=1)
    log_every: int = setting(
        5,
        "control periods between the scans written to the detection log and kept for verification (2 Hz"
        " at the 10 Hz control rate)",
        minimum=1,
        maximum=1000,
    )


@dataclass
class DetectorSection:
    kind: str = setting(
        "simulated",
        "simulated: the simulator's detector; onnx: a network on the rendered view",
        enum=("simulated", "onnx"),
    )
    model: str = setting("default", "ONNX model path, or default (the model shipped in the package)")
    score_threshold: float = SCORE_THRESHOLD()
    rate: float = setting(5.0, "Hz: detector frames per second", above=0, maximum=100)
    classes: dict[str, str] = setting(
        {}, "detector class name -> feature category, for names the built-in synonyms do not know"
    )


@dataclass
class MatchingSection(MatchingSettings):
    """Every matching tunable of ``bim-init match`` (the same names, units and defaults: the fields of
    :class:`MatchingSettings`), and the session's own. The detection filter's score threshold is
    ``detector.score_threshold`` and the wall clearance of Eq. 17 ``exploration.d_thre``."""

    m_thre: int = setting(
        40, "active exploration only with fewer hypotheses than this", above=0, maximum=10000
    )
    drift_window: float = setting(
        50.0,
        "m: when no hypothesis is consistent with every confirmed feature, match again with only those"
        " confirmed in the last M metres of travel (odometry drift); 0 disables",
        minimum=0,
        maximum=100000,
    )
    redecide: float = setting(
        10.0,
        "m of travel after which hypotheses left undecided are matched and judged again (the lidar along"
        " the path may tell them apart by then)",
        above=0,
        maximum=10000,
    )


@dataclass
class LoopSettings:
    """A loop: driving a long way in a short time without leaving a small area (circling an island of
    clutter, a chicane, an open hall with no wall in reach)."""

    window: float = setting(45.0, "s of path checked for a loop", above=0, maximum=3600)
    length: float = setting(
        8.0,
        "m driven in that window (a robot arcing at 0.3 m/s on a 0.7 m radius drives 12 m) ...",
        minimum=0,
        maximum=10000,
    )
    radius: float = setting(
        2.5, "m: ... staying this close to the path's centre is a loop", above=0, maximum=1000
    )
    escape: float = setting(
        25.0,
        "s driving out of a loop (or shuttling) toward an unexplored opening or open space",
        above=0,
        maximum=3600,
    )
    open_reach: float = setting(
        8.0,
        "m along the longest free beam to the point a loop escape heads for when no opening is known ...",
        above=0,
        maximum=1000,
    )
    open_short: float = setting(
        1.0, "m: ... or this much short of what that beam hit", minimum=0, maximum=1000
    )
    blind_reach: float = setting(
        2.0,
        "m straight ahead a loop escape heads for when there is no scan to pick a beam from",
        above=0,
        maximum=1000,
    )


@dataclass
class ShuttleSettings:
    """Shuttling: back and forth over the same few metres for minutes (a dead end behind a material
    stack the followed wall leads around, targets that keep failing): follow the other wall."""

    window: float = setting(150.0, "s of path checked for shuttling", above=0, maximum=36000)
    length: float = setting(
        30.0, "m driven in that window (0.2 m/s on average with the defaults) ...", minimum=0, maximum=100000
    )
    radius: float = setting(
        8.0, "m: ... without leaving a circle this size is shuttling", above=0, maximum=10000
    )


@dataclass
class FrontierSettings:
    """The local map of what the lidar has seen, whose unexplored openings loop escapes head for."""

    scan_every: int = setting(
        10,
        "control periods between the scans written into it (1 Hz at the 10 Hz control rate) ...",
        minimum=1,
        maximum=1000,
    )
    beam_step: int = setting(2, "... each beam_step-th beam of them", minimum=1, maximum=1000)


@dataclass
class LapSettings:
    """A lap: back where the robot was after its path turned once round (a room, a hall, a corridor
    section closed at both ends) with no new feature on the way: it heads for an opening of its
    local map it can pass, and with none left it is shut in (beyond the paper)."""

    length: float = setting(6.0, "m: a lap is at least this long ...", above=0, maximum=10000)
    radius: float = setting(1.0, "m: ... back this close to where it began ...", above=0, maximum=100)
    turn: float = setting(
        315.0, "degrees: ... the path's direction turned by at least this much", above=0, maximum=3600
    )
    shut_in: bool = setting(
        True,
        "stop the session when a lap brought no new feature and the local map has no opening the robot can"
        " pass (reason: shut in, with the area explored, the features seen and what to do); false: drive"
        " on to limits.max_distance",
    )


@dataclass
class TargetSettings:
    """Active exploration's targets (paper 3.3.4, exploration.active)."""

    hypotheses: int = setting(
        5,
        "hypotheses (most probable first) whose targets active exploration validates",
        minimum=1,
        maximum=1000,
    )
    view_distance: float = setting(
        1.8,
        "m in front of a target feature where active exploration goes to look at it",
        minimum=0,
        maximum=100,
    )
    discrimination_radius: float = setting(
        1.5,
        "m: another hypothesis predicting a same-category feature this close to a target agrees with it (the"
        " target tells them not apart)",
        minimum=0,
        maximum=100,
    )
    visited_radius: float = setting(
        2.0, "m: a target this close to one visited before is skipped", minimum=0, maximum=100
    )
    planner_margin: float = setting(
        0.1, "m of clearance added to robot.radius when planning routes", minimum=0, maximum=10
    )
    travel_slack: float = setting(
        1.5,
        "the time allowed to get to a target: the route's length over robot.max_linear, times this ...",
        minimum=0,
        maximum=100,
    )
    travel_cap: float = setting(
        120.0, "s: ... at most this, on top of exploration.t_thre", minimum=0, maximum=36000
    )
    stall: float = setting(
        15.0,
        "s without getting closer to the route's next waypoint: the route is blocked",
        above=0,
        maximum=3600,
    )
    progress_step: float = setting(
        0.5, "m closer to the waypoint that counts as progress", minimum=0, maximum=100
    )
    waypoint_cost: float = setting(
        2.0, "m added to the remaining distance for each waypoint still ahead", minimum=0, maximum=100
    )
    look: float = setting(2.0, "s spent at a reached target looking for its feature", minimum=0, maximum=3600)
    max_fruitless: int = setting(
        3,
        "targets in a row without a new feature after which random exploration takes over",
        minimum=1,
        maximum=1000,
    )


@dataclass
class ExplorationSection:
    wall_side: str = setting("left", "the wall random exploration follows", enum=("left", "right"))
    wall_distance: float = setting(0.7, "m kept to the followed wall", above=0, maximum=10)
    front_clearance: float = setting(
        0.2,
        "m beyond robot.radius: an obstacle this close ahead stops the wall follower, which turns in place"
        " away from the wall",
        minimum=0,
        maximum=10,
    )
    d_thre: float = D_THRE()
    t_thre: float = setting(
        25.0, "s without a new feature during active exploration -> recovery", above=0, maximum=3600
    )
    active: bool = setting(
        False,
        "BIM-based active exploration (paper 3.3.4) with several but fewer than matching.m_thre hypotheses,"
        " and toward a claim's credible rivals; false: wall following until one hypothesis is left (in the"
        " site as built wall following initialised more sessions)",
    )
    max_route: float = setting(
        0.0,
        "m: active exploration takes no target farther along the corridors than this; 0: any",
        minimum=0,
        maximum=10000,
    )
    recovery: bool = setting(
        True,
        "active exploration that finds nothing within t_thre turns in place to widen the view (paper 3.3.4);"
        " false: on to the next target",
    )
    initial_look: bool = setting(
        True, "turn once on the spot before exploring: features behind the robot cost no distance"
    )
    look_every: float = setting(
        10.0,
        "m of travel without a new feature while following a wall with open space (3 m or more) on the"
        " other side -> turn once on the spot again; 0: never",
        minimum=0,
        maximum=1000,
    )
    cross_after: int = setting(
        6,
        "looks on an open floor (look_every) since the last new feature after which the robot drives across"
        " the floor on the open side (to a wall 2 m wide or more that the lidar sees up to 16.5 m away,"
        " along a way 1.6 m wide, stopping 1.5 m short) and follows the wall found there; 0: never",
        minimum=0,
        maximum=1000,
    )
    turn: float = setting(
        360.0,
        "degrees turned in place by a look (the initial one, one on an open floor) and by the recovery"
        " rotation",
        above=0,
        maximum=3600,
    )
    turn_rate: float = setting(
        0.6, "share of robot.max_angular the robot turns in place at (looks, recovery)", above=0, maximum=1
    )
    loops: LoopSettings = section(LoopSettings, "driving out of a loop (beyond the paper)")
    shuttles: ShuttleSettings = section(
        ShuttleSettings, "following the other wall when shuttling (beyond the paper)"
    )
    frontier: FrontierSettings = section(
        FrontierSettings, "the local map of unexplored openings that loop escapes head for"
    )
    laps: LapSettings = section(LapSettings, "laps round a room or hall without a new feature: shut in?")
    targets: TargetSettings = section(TargetSettings, "active exploration's targets (exploration.active)")


@dataclass
class FineTuningSection:
    enabled: bool = setting(
        True, "fine-tune the coarse pose with the particle filter of Eq. 18 while following the wall"
    )
    particles: int = setting(
        2000, "particles of the fine-tuning filter (memory: particles x beams)", above=0, maximum=200000
    )
    covariance: float = setting(0.01, "m^2: x and y variance must fall below this", above=0, maximum=100)
    yaw_covariance: float = setting(0.0012, "rad^2: yaw variance must fall below this", above=0, maximum=10)
    distance: float = setting(6.0, "m followed along the wall at most", minimum=0, maximum=1000)
    min_travel: float = setting(
        1.0, "m followed before the covariance may count as converged", minimum=0, maximum=1000
    )
    seed_sigma_xy: float = setting(0.5, "m: spread of the seeded particles", minimum=0, maximum=100)
    seed_sigma_yaw: float = setting(10.0, "degrees: spread of the seeded particles", minimum=0, maximum=180)
    landmarks: int = setting(
        4, "matched features (the latest) that weight the filter's seed", minimum=1, maximum=1000
    )
    landmark_sigma: float = setting(
        0.3,
        "m: how far a matched feature may land from its BIM feature (the seed's weights)",
        above=0,
        maximum=100,
    )
    update_min_d: float = setting(
        0.25, "m of travel before a filter update (AMCL update_min_d)", minimum=0, maximum=100
    )
    update_min_a: float = setting(
        0.2, "rad turned before a filter update (AMCL update_min_a)", minimum=0, maximum=6.2832
    )
    lost_likelihood: float = setting(
        0.12,
        "per-beam likelihood (geometric mean, best particle) below which an update counts as lost ...",
        minimum=0,
        maximum=1,
    )
    lost_updates: int = setting(
        5, "... and this many lost updates in a row: the filter is lost", minimum=1, maximum=10000
    )
    drifted_distance: float = setting(
        1.0,
        "m: a filter that settled farther than this from the rectified pose carried by odometry ...",
        minimum=0,
        maximum=1000,
    )
    drifted_turn: float = setting(20.0, "degrees: ... or turned more than this ...", minimum=0, maximum=180)
    keep_rectified_margin: float = setting(
        0.1,
        "... and whose scan fit (share of beams) the carried pose beats by this much has drifted: the"
        " carried pose is kept",
        minimum=0,
        maximum=1,
    )
    reseed_sigma_xy: float = setting(
        2.0,
        "m: the spread of the second, wider try when the filter settled where the scan fits badly"
        " (verification.min_fine_scan_fit)",
        minimum=0,
        maximum=100,
    )
    tries: int = setting(
        2,
        "final-pose checks a session may fail: after a failed one (filter lost, pose failed verification)"
        " it explores on and claims again",
        minimum=1,
        maximum=100,
    )


@dataclass
class ConfirmSection:  # nav2.confirm (initcli/ros/delivery.py)
    timeout: float = setting(
        10.0,
        "s: how long to wait for AMCL's pose to agree with ours (0: do not wait)",
        minimum=0,
        maximum=600,
    )
    tolerance_m: float = setting(
        0.3, "m: AMCL's pose within this of ours counts as taken", above=0, maximum=10
    )
    tolerance_deg: float = setting(5.0, "degrees: AMCL's heading within this of ours", above=0, maximum=180)
    amcl_topic: str = setting("/amcl_pose", "geometry_msgs/PoseWithCovarianceStamped: AMCL's estimate")
    republish_period: float = setting(
        2.0, "s: /initialpose is sent again this often until confirmed", above=0, maximum=600
    )


@dataclass
class Nav2Section:  # robot.driver rosbridge: how the pose reaches Nav2 (initcli/ros/delivery.py)
    advertise_delay: float = setting(
        0.5,
        "s: wait after advertising /initialpose when rosbridge cannot say (rosapi) that the topic is up",
        minimum=0,
        maximum=60,
    )
    set_initial_pose_service: str = setting(
        "/set_initial_pose", "nav2_msgs/SetInitialPose: AMCL's service, called when rosbridge offers it"
    )
    confirm: ConfirmSection = section(ConfirmSection, "confirmation on AMCL's pose topic")


@dataclass
class LimitsSection:
    max_distance: float = setting(
        150.0, "m driven without a unique match -> failure (paper \u00a74.3)", above=0, maximum=100000
    )
    max_time: float = setting(1200.0, "s of session time", above=0, maximum=86400)


@dataclass
class RivalSettings:
    """The session's search for a claim's rivals (beyond the paper)."""

    # Doors built off their place can push the true place past Eq. 8's distance tolerance while a
    # turned place of a nearly symmetric lobby fits within it (ntu_hallway, doors shifted sigma
    # 0.6 m: a 177-degree-off claim on 5 features).
    alpha_factor: float = setting(
        1.5,
        "a claim must stay unique with matching.alpha this many times wider too ...",
        minimum=1,
        maximum=10,
    )
    wide_inliers: int = setting(
        6,
        "... when it has this many matched features or fewer, was picked by the lidar along the path or"
        " comes soon after a doubted claim (more features: alpha as it is)",
        minimum=0,
        maximum=10000,
    )
    doubt_window: float = setting(
        10.0,
        "m of travel after a claim held back by credible rivals in which claims get the wide search",
        minimum=0,
        maximum=100000,
    )
    search_factor: float = setting(
        2.0,
        "a rival's scan fit may shift it this many times farther than a claim's"
        " (verification.scan_search_xy)",
        minimum=0,
        maximum=100,
    )
    checked: int = setting(
        8,
        "rivals of a claim verified one by one; more count as credible without a check ...",
        minimum=0,
        maximum=10000,
    )
    compared: int = setting(
        64,
        "... unless the claim outranks them all, compared one by one (the likeliest first) up to this many",
        minimum=0,
        maximum=10000,
    )


@dataclass
class VerificationSection(VerificationParams):
    """Checks of a unique match before it is claimed (:class:`VerificationParams`), the session's
    rival search, and the final pose's agreement with the claim."""

    rivals: RivalSettings = section(RivalSettings, "the session's search for a claim's rivals")
    agree_distance: float = setting(
        2.0,
        "m: a fine-tuned pose farther than this from the coarse pose carried by odometry fails"
        " verification ...",
        minimum=0,
        maximum=1000,
    )
    agree_turn: float = setting(
        30.0, "degrees: ... as does one turned more than this", minimum=0, maximum=180
    )


@dataclass
class SessionConfig:
    site: SiteSection = section(SiteSection, required=True)
    robot: RobotSection = section(RobotSection)
    camera: CameraSection = section(CameraSection)
    lidar: LidarSection = section(LidarSection)
    detector: DetectorSection = section(DetectorSection)
    matching: MatchingSection = section(MatchingSection)
    exploration: ExplorationSection = section(ExplorationSection)
    fine_tuning: FineTuningSection = section(FineTuningSection)
    limits: LimitsSection = section(LimitsSection)
    nav2: Nav2Section = section(Nav2Section, "robot.driver rosbridge: delivering the pose to Nav2")
    sim: SimSection = section(SimSection)
    verification: VerificationSection = section(
        VerificationSection,
        "checks of a unique match before it is claimed: negative evidence and the lidar's fit (beyond"
        " the paper)",
    )
    source: Path | None = None  # the YAML file (not a setting)

    def site_path(self) -> Path:
        base = self.source.parent if self.source else Path.cwd()
        return (base / self.site.path).resolve()
