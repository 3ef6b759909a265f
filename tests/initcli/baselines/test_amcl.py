"""The ``amcl`` baseline (§4.3): AMCL global localisation while following the wall on a sample site."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from initcli.baselines.amcl import AmclTracePoint, run_amcl
from initcli.baselines.outcome import LocalisationOutcome
from initcli.config import SessionConfig, load_config
from initcli.config.building import choose_storey, prepare_site
from initcli.core.filters.global_localisation import GlobalLocalisationParams
from initcli.sim.build import build_sim
from tests.helpers import SAMPLES


@pytest.fixture(scope="module")
def block_a(tmp_path_factory: pytest.TempPathFactory):
    config = load_config(SAMPLES / "block_a.site.yaml")
    site = prepare_site(config, tmp_path_factory.mktemp("amcl"))
    storey, _ = choose_storey(config, site)
    return config, site, storey


def with_limits(config: SessionConfig, max_distance: float, covariance: float | None = None) -> SessionConfig:
    config = dataclasses.replace(config, limits=dataclasses.replace(config.limits, max_distance=max_distance))
    if covariance is not None:
        config = dataclasses.replace(
            config, fine_tuning=dataclasses.replace(config.fine_tuning, covariance=covariance)
        )
    return config


def test_outcome_fields_are_consistent(block_a) -> None:
    config, site, storey = block_a
    config = with_limits(config, 20.0)
    trace: list[AmclTracePoint] = []
    outcome = run_amcl(
        config, site, build_sim(config, site, storey, 11), np.random.default_rng(11), trace=trace
    )
    assert isinstance(outcome, LocalisationOutcome)
    assert outcome.method == "amcl" and outcome.features == 0
    assert outcome.truth is not None
    assert (outcome.pose is not None) == outcome.localised
    assert 0.0 < outcome.distance_m and 0.0 < outcome.duration_s and 0.0 < outcome.wall_seconds
    # From this start (seed 11) AMCL converges after about 1 m of wall following, well inside the
    # 20 m limit: the claim comes at the first check after 1 m (as in fine tuning) and only once
    # the particle cloud is tighter than the fine-tuning threshold.
    assert outcome.localised and outcome.pose is not None
    assert 1.0 <= outcome.distance_m < 20.0
    assert trace[-1].variance_xy < config.fine_tuning.covariance
    assert outcome.pose.distance_to(outcome.truth) < 0.5
    params = GlobalLocalisationParams()
    assert trace and all(params.min_particles <= p.particles <= params.particles for p in trace)
    assert [p.t for p in trace] == sorted(p.t for p in trace)


def test_gives_up_at_the_distance_limit(block_a) -> None:
    config, site, storey = block_a
    config = with_limits(config, 4.0, covariance=-1.0)  # a threshold nothing can meet
    outcome = run_amcl(
        config,
        site,
        build_sim(config, site, storey, 3),
        np.random.default_rng(3),
        GlobalLocalisationParams(particles=1000, kld=False),
    )
    assert not outcome.localised and outcome.pose is None
    assert outcome.truth is not None
    assert 4.0 < outcome.distance_m < 4.2
    assert "4 m" in outcome.reason


def test_claims_the_converged_pose_with_its_truth(block_a) -> None:
    """Seed 11 starts where block_a's walls are distinctive: AMCL converges near the true pose."""
    config, site, storey = block_a
    outcome = run_amcl(
        with_limits(config, 20.0), site, build_sim(config, site, storey, 11), np.random.default_rng(11)
    )
    assert outcome.localised and outcome.pose is not None and outcome.truth is not None
    assert outcome.pose.distance_to(outcome.truth) < 0.5
