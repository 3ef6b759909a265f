"""The sections of the session config (``site.yaml``), each setting written once with its unit,
range and default (:mod:`bimkit.settings`); the ``sim:`` section is :mod:`initcli.config.sim`.

The sections are the records the code reads: ``matching:`` is
:class:`initcli.config.matching.MatchingSettings` (the tunables ``bim-init match`` shares) with the
session's own added, ``verification:`` is :class:`initcli.core.verify.params.VerificationParams`
with the session's rival search added. The tuning of the session's escapes (loops, shuttling),
active exploration's targets are :mod:`initcli.config.exploration`; the fine stage's are here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bimkit.settings import section, setting
from initcli.config.exploration import ExplorationSection
from initcli.config.matching import SCORE_THRESHOLD, MatchingSettings
from initcli.config.sim import SimSection
from initcli.config.watch import AMCL_POSE_TOPIC, WatchSection
from initcli.core.lidar.registration_params import RegistrationParams
from initcli.core.verify.params import VerificationParams

__all__ = [
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
    "RivalSettings",
    "RobotSection",
    "RosbridgeSection",
    "SessionConfig",
    "SiteSection",
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
        "/tf_static",
        "tf2_msgs/TFMessage: the camera mount (camera.pose is the fallback) and the laser's mount (the"
        " LaserScan's frame_id resolved to the base frame)",
    )
    base_frame: str = setting(
        "", "the robot's base frame for the camera and laser mounts (empty: the odometry's child frame)"
    )
    camera_wait: float = setting(
        3.0,
        "s: how long to wait for CameraInfo and /tf_static before the site config's camera (and for the"
        " laser's mount before the scans are taken as from the base origin)",
        minimum=0,
        maximum=60,
    )
    camera: str = setting(
        "auto",
        "absent: the robot has no camera, the session runs on the lidar alone (no detections or depth"
        " subscribed); present: it has one (the site config's camera: where no CameraInfo comes); auto:"
        " absent when rosapi lists no publisher of detections_topic, with one warning (without rosapi:"
        " present)",
        enum=("auto", "present", "absent"),
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
    profile: str = setting(
        "",
        "a lidar profile measured on real laser logs (benchmarks/measure_lidar_profile.py): real-logs"
        " (the one shipped in the package) or a JSON file, relative to this file; the simulator then"
        " takes lidar.noise, lidar.dropout and sim.clutter (material stacks, for the beams that end off"
        " the BIM's walls) from it (a config that sets one of those and a profile is refused); empty:"
        " those three",
    )
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
    covariance_floor_m: float = setting(
        0.05,
        "m: the least standard deviation of x and y sent with the pose (what a map of such cells can"
        " place); the disagreement with the carried coarse claim is added too",
        minimum=0,
        maximum=10,
    )
    covariance_floor_deg: float = setting(
        0.5, "degrees: the least standard deviation of the yaw sent with the pose", minimum=0, maximum=90
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
    amcl_topic: str = setting(AMCL_POSE_TOPIC, "geometry_msgs/PoseWithCovarianceStamped: AMCL's estimate")
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
    registration: RegistrationParams = section(
        RegistrationParams,
        "the lidar submap registered over the BIM map when no camera claim exists (beyond the paper)",
    )
    watch: WatchSection = section(
        WatchSection, "bim-init watch: the localiser's pose checked against the model, and re-initialised"
    )
    source: Path | None = None  # the YAML file (not a setting)

    def site_path(self) -> Path:
        base = self.source.parent if self.source else Path.cwd()
        return (base / self.site.path).resolve()
