"""``python -m tests.fuzz.run [--seconds S] [TARGET ...]`` (``make fuzz``): each reader's fuzz target
(:mod:`tests.fuzz.targets`) for S seconds of fresh random examples; exit 1 at the first input that
breaks the promise (shrunk by hypothesis and printed), 0 otherwise."""

from __future__ import annotations

import argparse
import sys
import time

from hypothesis import HealthCheck, given, settings

from tests.fuzz.targets import TARGETS, target


def fuzz(name: str, seconds: float, batch: int = 20) -> int:
    """Examples run on ``name`` in about ``seconds`` (batches of ``batch``, each with a new seed)."""
    chosen = target(name)
    strategy = chosen.strategy()

    @settings(max_examples=batch, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(strategy)
    def one_batch(data: bytes) -> None:
        chosen.check(data)

    examples = 0
    until = time.monotonic() + seconds
    while time.monotonic() < until:
        one_batch()
        examples += batch
    return examples


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=8.0, help="per target")
    parser.add_argument("targets", nargs="*", help=f"some of {', '.join(t.name for t in TARGETS)}")
    args = parser.parse_args(argv)
    names = args.targets or [t.name for t in TARGETS]
    started = time.monotonic()
    for name in names:
        t0 = time.monotonic()
        try:
            n = fuzz(name, args.seconds)
        except Exception as exc:  # noqa: BLE001 - the failing example is in hypothesis's report
            print(f"fuzz {name}: FAILED: {type(exc).__name__}: {exc}", file=sys.stderr)
            return 1
        print(f"fuzz {name}: {n} examples in {time.monotonic() - t0:.0f} s, all read or refused in one line")
    print(f"fuzz: {len(names)} targets in {time.monotonic() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
