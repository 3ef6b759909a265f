"""initcli.cli.survey: survey_params from a session config."""

from __future__ import annotations

from initcli.cli.survey import survey_params
from initcli.config import followed_side, load_config
from tests.helpers import SAMPLES


def test_survey_params_come_from_the_config() -> None:
    config = load_config(SAMPLES / "block_a.site.yaml")
    params = survey_params(config, spacing=1.5, headings=4)
    assert (params.spacing, params.headings) == (1.5, 4)
    assert params.limit_m == config.limits.max_distance
    assert params.min_sightings == config.matching.min_sightings
    assert params.side == followed_side(config)
    assert params.camera.max_range == config.camera.range
    assert params.matching.alpha == config.matching.alpha
    assert params.matching.max_outliers == config.matching.max_outliers
