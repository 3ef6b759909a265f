"""Active exploration (§3.3.4): with several but fewer than m_thre hypotheses, go and look where
they disagree.

Each hypothesis in turn (the most probable first) names a target: a viewpoint in front of the
nearest BIM feature of the highest-priority category (fewest in the BIM) that it has not matched
yet and whose sighting would rule out another hypothesis. The robot follows a route there along
the BIM's corridors (doors shut: a robot cannot open one) with the modified bug algorithm
(Eq. 15-16). A target is given up when the robot got there and saw nothing new, stopped getting
closer, or ran out of time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from bimtools.site.load import Site
from bimtools.site.records import Feature
from initcli.config import SessionConfig
from initcli.core.geometry.se2 import Pose2D, rot2
from initcli.core.navigation.bug_navigation import BugParams, RouteNavigator
from initcli.core.navigation.grid_planner import PlanningGrid, with_doors_closed
from initcli.core.navigation.wall_following import ScanView, WallFollowParams
from initcli.drivers.base import SensorFrame
from initcli.match.pipeline import Hypothesis

__all__ = ["ActiveExploration", "Target", "unseen_features"]


@dataclass(frozen=True)
class Target:
    """The viewpoint chosen to validate one hypothesis."""

    viewpoint: np.ndarray  # odom frame, m
    hypothesis: Hypothesis
    route_m: float  # length of the route along the BIM's corridors

    def record(self) -> dict[str, object]:
        """What the session's ``active`` state record says about the target."""
        return {
            "target": [round(float(c), 3) for c in self.viewpoint],
            "hypothesis": self.hypothesis.rank,
            "route_m": round(self.route_m, 1),
            "matches": self.hypothesis.matches,
        }


class ActiveExploration:
    """The hypotheses to validate, the targets visited, and the route being followed."""

    def __init__(self, config: SessionConfig, site: Site, follow: WallFollowParams) -> None:
        self.site = site
        self.follow = follow
        self.settings = config.exploration.targets
        self.t_thre = config.exploration.t_thre  # s to find something at a target
        self.max_linear = config.robot.max_linear  # m/s
        self.robot_radius = config.robot.radius  # m
        self.max_route = config.exploration.max_route or math.inf  # m along the corridors
        self.plan: list[Hypothesis] = []  # hypotheses whose targets are still to visit
        self.plan_all: list[Hypothesis] = []  # every hypothesis of the last match step
        self.visited: list[np.ndarray] = []  # odom viewpoints planned so far
        self.navigator: RouteNavigator | None = None
        self._planners: dict[str, PlanningGrid | None] = {}
        self.target_budget = self.t_thre  # s allowed for the current target
        self.target_started = 0.0  # s
        self.target_reached_t: float | None = None  # s
        self.progress: tuple[float, float] = (0.0, math.inf)  # (s, m) of the last progress
        self.fruitless = 0  # active-exploration targets in a row that brought no new feature

    @property
    def exhausted(self) -> bool:
        """Have ``targets.max_fruitless`` targets in a row brought nothing new?"""
        return self.fruitless >= self.settings.max_fruitless

    def validate(self, hypotheses: list[Hypothesis]) -> None:
        """Validate the most probable hypotheses first, then the next ones (§3.3.3)."""
        self.plan = list(hypotheses[: self.settings.hypotheses])
        self.plan_all = list(hypotheses)

    def _planner(self, storey: str) -> PlanningGrid | None:
        if storey not in self._planners:
            model = self.site.storeys[storey]
            grid = model.grid
            if grid is not None:  # routes run along the corridors: doors stay shut
                doors = [
                    (f.x, f.y, f.norm_x, f.norm_y, f.width)
                    for f in model.features
                    if f.ifc_class == "IfcDoor"
                ]
                grid = with_doors_closed(grid, np.array(doors).reshape(-1, 5))
            self._planners[storey] = (
                PlanningGrid.of(grid, self.robot_radius + self.settings.planner_margin)
                if grid is not None
                else None
            )
        return self._planners[storey]

    def _target(self, hypothesis: Hypothesis, odom: Pose2D) -> tuple[list[np.ndarray], float] | None:
        """A route (odom waypoints) to a viewpoint in front of the BIM feature of the highest-priority
        category (fewest in the BIM) that ``hypothesis`` has not matched yet, nearest along the
        BIM's corridors, not visited before; and its length."""
        features = self.site.storeys[hypothesis.storey].camera_features
        counts: dict[str, int] = {}
        for f in features:
            counts[f.category] = counts.get(f.category, 0) + 1
        matched = {m for m in hypothesis.matches if m is not None}
        here = hypothesis.transform * odom
        planner = self._planner(hypothesis.storey)
        if planner is None:
            return None
        dist, pred, start = planner.distances_from(here.x, here.y)
        for category in sorted(counts, key=lambda c: (counts[c], c)):
            best: tuple[float, int, np.ndarray] | None = None
            for f in features:
                if f.category != category or f.id in matched:
                    continue
                d = self.settings.view_distance
                view_bim = np.array([f.x + d * f.norm_x, f.y + d * f.norm_y])
                view = hypothesis.transform.apply_inverse(view_bim)
                if any(math.hypot(*(view - v)) <= self.settings.visited_radius for v in self.visited):
                    continue
                if not self._discriminates(hypothesis, f):
                    continue
                node = planner.node_at(*view_bim)
                if node >= 0 and math.isfinite(dist[node]) and (best is None or dist[node] < best[0]):
                    best = (float(dist[node]), node, view)
            if best is not None and best[0] <= self.max_route:
                self.visited.append(best[2])
                route = planner.path(pred, start, best[1])
                return [hypothesis.transform.apply_inverse(p) for p in route], best[0]
        return None

    def _discriminates(self, hypothesis: Hypothesis, feature: Feature) -> bool:
        """Would seeing ``feature`` where ``hypothesis`` puts it rule out some other hypothesis?

        Not when every other hypothesis also has a feature of that category there (a symmetric
        layout): the robot would see something either way and learn nothing.
        """
        others = [h for h in self.plan_all if h is not hypothesis]
        if not others:
            return True
        where = hypothesis.transform.apply_inverse(np.array([feature.x, feature.y]))  # odom frame
        for other in others:
            p = other.transform.apply(where)
            same = [
                g
                for g in self.site.storeys[other.storey].camera_features
                if g.category == feature.category
                and math.hypot(g.x - p[0], g.y - p[1]) < self.settings.discrimination_radius
            ]
            if not same:
                return True
        return False

    def next_target(self, frame: SensorFrame) -> Target | None:
        """Start toward the next hypothesis' target; None when none is left.

        Targets of the remaining hypotheses are planned together and the nearest (along the BIM's
        corridors) is validated first: a wrong hypothesis whose target is close is cheap to refute,
        and the true one is confirmed as soon as its target feature is seen.
        """
        options = []
        for hypothesis in self.plan:
            planned = self._target(hypothesis, frame.odom)
            if planned is not None:
                options.append((planned[1], hypothesis.rank, hypothesis, planned[0]))
        del self.visited[len(self.visited) - len(options) :]  # _target marked them; only the chosen one is
        if not options:
            self.plan = []
            return None
        length, _, hypothesis, route = min(options, key=lambda o: (o[0], o[1]))
        self.plan = [h for h in self.plan if h is not hypothesis]
        self.visited.append(route[-1])
        self.navigator = RouteNavigator(route, BugParams(follow=self.follow))
        # t_thre to find something, plus the time to get there (capped: under a wrong hypothesis the
        # route may run into walls).
        t = self.settings
        self.target_budget = self.t_thre + min(t.travel_slack * length / self.max_linear, t.travel_cap)
        self.target_started = frame.t
        self.target_reached_t = None
        self.progress = (frame.t, math.inf)
        return Target(route[-1], hypothesis, length)

    def drive(self, frame: SensorFrame, scan: ScanView | None) -> tuple[float, float]:
        """The command toward the target; ``scan`` None: stand still (held up, or no scan)."""
        assert self.navigator is not None
        if scan is None:
            v, w, arrived = 0.0, 0.0, False
        else:
            v, w, arrived = self.navigator.step(frame.odom, scan)
        if arrived and self.target_reached_t is None:
            self.target_reached_t = frame.t
        return v, w

    def give_up(self, frame: SensorFrame, last_feature_t: float) -> str | None:
        """Why the current target is given up (counted as fruitless), or None to keep going."""
        since = max(last_feature_t, self.target_started)
        reached = self.target_reached_t
        reached_and_looked = reached is not None and frame.t - reached > self.settings.look
        stalled = self.target_reached_t is None and self._stalled(frame)
        if not (reached_and_looked or stalled or frame.t - since > self.target_budget):
            return None
        self.fruitless += 1
        if reached_and_looked:
            return "target reached, nothing new"
        if stalled:
            return "no progress toward the target"
        return "time budget passed"

    def _stalled(self, frame: SensorFrame) -> bool:
        """No progress toward the route's current waypoint for ``targets.stall`` seconds."""
        assert self.navigator is not None
        if not self.navigator.waypoints:
            return False
        remaining = math.hypot(
            *(self.navigator.waypoints[0] - frame.odom.xy)
        ) + self.settings.waypoint_cost * len(self.navigator.waypoints)
        since, best = self.progress
        if remaining < best - self.settings.progress_step:
            self.progress = (frame.t, remaining)
            return False
        return frame.t - since > self.settings.stall


def unseen_features(
    site: Site, hypotheses: list[Hypothesis], odom: Pose2D
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The camera features each hypothesis has not matched yet, in the robot's frame at ``odom``:
    points (N x 2), normals (N x 2) and the index of the hypothesis each belongs to (N,), for
    :func:`initcli.core.navigation.feature_walls.toward_feature_wall`."""
    points, normals, owner = [], [], []
    for k, hypothesis in enumerate(hypotheses):
        matched = {m for m in hypothesis.matches if m is not None}
        robot = hypothesis.transform * odom  # the robot in the BIM frame under this hypothesis
        for f in site.storeys[hypothesis.storey].camera_features:
            if f.id in matched:
                continue
            points.append(robot.apply_inverse(np.array([f.x, f.y])))
            normals.append(rot2(robot.yaw).T @ np.array([f.norm_x, f.norm_y]))
            owner.append(k)
    return (
        np.array(points, dtype=float).reshape(-1, 2),
        np.array(normals, dtype=float).reshape(-1, 2),
        np.array(owner, dtype=int),
    )
