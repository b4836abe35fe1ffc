"""Benchmarks of nlbeam (not tests): `python -m benchmarks` regenerates BENCHMARKS.md."""
