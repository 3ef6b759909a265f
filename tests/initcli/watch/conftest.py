"""The corridor world's site and recordings, written once per test session."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from initcli.io.log_writer import write_log
from tests.initcli.watch.kidnap_world import Recording, control, corridor_world, kidnap, write_world_site


class Corridor:
    def __init__(self, root: Path) -> None:
        world = corridor_world()
        rng = np.random.default_rng(49)
        self.site = write_world_site(root)
        self.kidnap: Recording = kidnap(world, rng)
        self.control: Recording = control(world, rng)
        self.kidnap_log = root / "kidnap.jsonl"
        self.control_log = root / "control.jsonl"
        write_log(self.kidnap_log, self.kidnap.records)
        write_log(self.control_log, self.control.records)


@pytest.fixture(scope="session")
def corridor(tmp_path_factory: pytest.TempPathFactory) -> Corridor:
    return Corridor(tmp_path_factory.mktemp("corridor"))
