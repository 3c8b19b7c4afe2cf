"""Run every benchmark: ``python -m benchmarks [--quick]``."""

import argparse

from benchmarks import gallery, periodic, rhomblock, verify, wallpaper

parser = argparse.ArgumentParser(prog="python -m benchmarks", description="Run every benchmark.")
parser.add_argument("--quick", action="store_true", help="a small version, for tests")
args = parser.parse_args()
for module in (wallpaper, rhomblock, verify, periodic, gallery):
    module.run(quick=args.quick)
