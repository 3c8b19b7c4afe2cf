"""Benchmarks: scripts that write JSON results and PNG charts to ``benchmarks/results``."""
