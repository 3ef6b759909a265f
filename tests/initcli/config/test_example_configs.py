"""The example configs of the docs load: docs/examples/sim-site.yaml, the commented minimal
simulated site.yaml for one's own building, runs on the block_a sample it names."""

from __future__ import annotations

from pathlib import Path

from initcli.config import load_config
from tests.helpers import SAMPLES

EXAMPLES = Path(__file__).resolve().parents[3] / "docs/examples"


def test_sim_site_example_loads_as_a_simulated_session() -> None:
    path = EXAMPLES / "sim-site.yaml"
    config = load_config(path)
    assert config.robot.driver == "sim"
    assert config.site_path() == (SAMPLES / "block_a.ifc").resolve()
    assert config.sim.reality == "ideal" and config.sim.as_built.missing_doors == 0
    text = path.read_text(encoding="utf-8")
    assert "construction" in text and "sim.workers" not in text  # the realities explained
    built = load_config(path, "construction")
    assert built.sim.as_built.missing_doors > 0 and built.sim.people == config.sim.people


def test_sim_site_example_runs(tmp_path) -> None:
    """``bim-init run --config docs/examples/sim-site.yaml`` ends with a verdict (a few seconds)."""
    import json

    from typer.testing import CliRunner

    from initcli.cli.main import app

    out = tmp_path / "run"
    result = CliRunner().invoke(
        app, ["run", "--config", str(EXAMPLES / "sim-site.yaml"), "--quiet", "--out", str(out)]
    )
    assert result.exit_code in (0, 3, 4), result.output
    assert json.loads((out / "summary.json").read_text())["storey"] == "Level 1"
