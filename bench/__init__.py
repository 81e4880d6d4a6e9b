"""Benchmarks: `make bench` (or `python -m bench`). They print figures; nothing is asserted."""
