"""Typed records of an evaluation: one trial, the rule that scores it, one table row."""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["DEFAULT_METHODS", "FailureRule", "METHODS", "MethodSummary", "TrialKey", "TrialRecord"]

DEFAULT_METHODS = ("bim", "bim+pf", "amcl", "markers")  # what an evaluation runs unless told
# ... and the watch (bim-init watch beside a localiser, kidnapped after sim.kidnap m): asked for by name
METHODS = (*DEFAULT_METHODS, "watch")


@dataclass(frozen=True)
class FailureRule:
    """The paper's failure rule (§4.3) plus the threshold of a confident wrong result.

    A trial fails when the method moved more than ``max_distance_m`` without a result, or its
    result is more than ``max_error_m`` from the truth. A *confident wrong* result is one the
    method claimed (converged, decoded, unique match) that lies more than ``wrong_error_m`` from
    the truth, or facing more than ``wrong_error_deg`` away from the true heading: the wrong
    corridor, the wrong door or the wrong way round, counted whether or not it also fails.
    """

    max_distance_m: float = 150.0
    max_error_m: float = 5.0
    wrong_error_m: float = 2.0
    wrong_error_deg: float = 30.0


@dataclass(frozen=True)
class TrialKey:
    """What identifies a trial across runs (for ``--resume``)."""

    site: str
    start: int
    method: str
    sweep_key: str = ""
    sweep_value: str = ""


@dataclass
class TrialRecord:
    """One row of ``results.jsonl``."""

    site: str
    start: int
    method: str
    success: bool
    reason: str
    features: int
    distance_m: float
    error_translation_m: float | None
    error_rotation_deg: float | None
    confident_wrong: bool
    seconds: float
    localised: bool = False
    seed: int = 0
    start_pose: list[float] = field(default_factory=list)  # x, y, yaw (deg), BIM frame
    pose: list[float] | None = None
    truth: list[float] | None = None
    sweep_key: str = ""
    sweep_value: str = ""
    # The simulator refused the start (its space closed off from the corridors, known at 0 m; a
    # storey with no free space): counted apart, neither a success nor a failure.
    refused: bool = False
    # The claimed pose's consistency with its own covariance (what Nav2 is sent): the normalised
    # estimation error squared over (x, y, yaw), and the covariance's largest position sigma (m)
    nees: float | None = None
    sigma_m: float | None = None
    # The watch method (initcli.watch.sim_trial): the travel at the kidnap (None: none), from it to
    # the first lost and the first recovery, the m driven with the localiser right and the lost
    # events there, and whether the recovery was wrong (by the rule's confident-wrong bounds)
    kidnap_m: float | None = None
    lost_after_m: float | None = None
    recovered_after_m: float | None = None
    control_m: float = 0.0
    false_alarms: int = 0
    wrong_recovery: bool = False

    @property
    def key(self) -> TrialKey:
        return TrialKey(self.site, self.start, self.method, self.sweep_key, self.sweep_value)


@dataclass
class MethodSummary:
    """One row of ``table.csv``: a method on a site (at one sweep value), over its trials.

    Means of distance, features and errors are over successful trials only, as in the paper;
    medians and 95th percentiles likewise. ``success_rate`` is over the accepted trials (``trials``
    less ``refused``: starts the simulator refused).
    """

    site: str
    method: str
    trials: int
    successes: int
    success_rate: float  # percent
    confident_wrong: int
    features_mean: float | None
    distance_mean_m: float | None
    distance_median_m: float | None
    distance_p95_m: float | None
    error_translation_mean_m: float | None
    error_translation_median_m: float | None
    error_translation_p95_m: float | None
    error_rotation_mean_deg: float | None
    error_rotation_median_deg: float | None
    error_rotation_p95_deg: float | None
    seconds_mean: float | None
    sweep_key: str = ""
    sweep_value: str = ""
    refused: int = 0  # trials whose start the simulator refused (not in success_rate)
