"""Executors: the local pool and Ray run the same trials to the same records (identical per trial seed)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from bimkit.errors import InputError
from initcli.config import load_config
from initcli.config.building import prepare_site
from initcli.eval.campaign import PreparedSite, plan_jobs, run_jobs
from initcli.eval.config import EvalConfig, EvalSite
from initcli.executor import LocalExecutor, make_executor, map_unordered

SAMPLES = Path(__file__).resolve().parents[2] / "sample_models"


def _square(x: int) -> int:
    return x * x


@pytest.mark.parametrize("workers", [1, 2])
def test_map_unordered_returns_every_result_with_its_index(workers):
    executor = LocalExecutor(workers)
    try:
        got = dict(map_unordered(executor, [(_square, k) for k in range(7)], window=3))
    finally:
        executor.close()
    assert got == {k: k * k for k in range(7)}


def test_unknown_executor_and_address_without_ray_are_bad_input():
    with pytest.raises(InputError):
        make_executor("slurm")
    with pytest.raises(InputError):
        make_executor("local", 1, "auto")


@pytest.fixture(scope="module")
def small_campaign(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("campaign")
    config_path = SAMPLES / "block_b.site.yaml"
    config = load_config(config_path)
    site = prepare_site(config, tmp / "block_b")
    eval_site = EvalSite(name="block_b", config=config_path, starts=2, paper="BlockB")
    eval_config = EvalConfig(sites=[eval_site], seed=1)
    jobs = plan_jobs(eval_config, [PreparedSite(eval_site, Path(site.root))], ("bim",), starts=2)
    return jobs


def _records(jobs, executor=None, workers=1):
    out = []
    run_jobs(jobs, workers, out.extend, executor)
    return sorted((dataclasses.replace(r, seconds=0.0) for r in out), key=lambda r: r.start)


def test_a_small_campaign_on_a_local_ray_instance_matches_the_local_pool(small_campaign):
    pytest.importorskip("ray")
    from initcli.executor import RayExecutor

    local = _records(small_campaign)
    ray_executor = RayExecutor(None, num_cpus=2)
    try:
        assert ray_executor.slots == 2
        on_ray = _records(small_campaign, ray_executor)
    finally:
        ray_executor.close()
    assert len(local) == 2 and [r.start for r in local] == [0, 1]
    assert on_ray == local


def test_a_ray_address_is_probed_before_ray_is_asked(monkeypatch):
    import socket
    import time

    from initcli.executor import probe_address

    closed = socket.socket()
    closed.bind(("127.0.0.1", 0))
    port = closed.getsockname()[1]
    closed.close()  # nothing listens there now
    started = time.monotonic()
    for address in (f"127.0.0.1:{port}", f"ray://127.0.0.1:{port}"):
        with pytest.raises(InputError, match=rf"--address {address}: no Ray cluster answers there"):
            probe_address(address)
    assert time.monotonic() - started < 5
    for address in ("no-port", "host:", ":6379", "host:99999", "host:port"):
        with pytest.raises(InputError, match="expected host:port, ray://host:port or auto"):
            probe_address(address)
    listening = socket.socket()
    listening.bind(("127.0.0.1", 0))
    listening.listen(1)
    try:
        probe_address(f"127.0.0.1:{listening.getsockname()[1]}")  # accepts: over to ray.init
        probe_address("auto")
    finally:
        listening.close()


def test_cancel_stops_the_workers_at_once():
    import time

    executor = LocalExecutor(2)
    handles = {executor.submit(time.sleep, 60) for _ in range(2)}
    time.sleep(1.0)
    started = time.monotonic()
    executor.close(cancel=True)
    assert time.monotonic() - started < 10
    assert all(h.done() for h in handles)
