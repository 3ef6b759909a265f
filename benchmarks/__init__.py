"""Benchmark scripts (``bench_*.py``, run as ``python benchmarks/bench_NAME.py [--quick]``) and the
helpers they share with the tests (``_oracle``, ``_recordings``). Not part of the installed package."""
