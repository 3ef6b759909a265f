"""initcli.cli.survey: survey_params from a session config."""

from __future__ import annotations

from initcli.cli.survey import as_built_outliers, survey_params
from initcli.config import SessionConfig, followed_side, load_config
from initcli.config.load import parse_config
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


def test_as_built_doors_the_model_lacks_allow_the_matching_one_outlier_more() -> None:
    def config(**sections: object) -> SessionConfig:
        return parse_config({"site": {"path": "site"}, **sections})

    assert as_built_outliers(config()) == 0
    assert as_built_outliers(config(sim={"reality": "construction"})) == 1
    assert as_built_outliers(config(sim={"as_built": {"extra_doors": 0.5}})) == 1
    assert as_built_outliers(config(sim={"detector": {"persistent_phantoms": 2.0}})) == 1
    assert as_built_outliers(config(sim={"as_built": {"wall_offset": 0.05}})) == 0
    built = config(sim={"reality": "construction"}, matching={"max_outliers": 2})
    assert survey_params(built, spacing=1.0, headings=4).matching.max_outliers == 3
