"""Run every benchmark: ``python -m benchmarks [--quick] [--results DIR]``.

Each module writes ``<name>.json`` (machine, versions, medians, ratios) and
``<name>.png`` into ``benchmarks/results`` (or DIR).
"""

import argparse
import time

from benchmarks import (accuracy, beyond, certify, contact_kinds, degeneracy, gallery, periodic, rhomblock, scaling,
                        stability, sweep, verify, wallpaper)
from benchmarks.common import add_arguments, use_results_folder

#: ``view`` is left out: it needs chromium and chromedriver (``python -m benchmarks.view``), and without them it
#: fails (selenium: "Binary Location Must be a String") instead of skipping.
MODULES = (wallpaper, rhomblock, verify, scaling, certify, periodic, accuracy, degeneracy, gallery, stability, sweep,
           beyond, contact_kinds)

parser = argparse.ArgumentParser(prog="python -m benchmarks", description="Run every benchmark.")
add_arguments(parser)
args = parser.parse_args()
use_results_folder(args.results)
for module in MODULES:
    start = time.perf_counter()
    module.run(quick=args.quick)
    print(f"-- {module.__name__} in {time.perf_counter() - start:.1f} s")
