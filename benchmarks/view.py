"""The 3D view: file size and load time in headless Chromium of RhomBlock hexagons up to 4,800 blocks.

Each hexagon (ring fixed) is verified (``check``) and written with
:func:`interlock.gallery.write_view`; Debian's chromium (headless, software
WebGL as on these machines) opens the file from ``file://`` five times.  The
load time is the page's own clock (``performance.now()``, from the start of
navigation) when the first frame's pixels can be read back (``readPixels``
after two animation frames: software WebGL rasterises after the script has
returned): reading the file, parsing three.js, decoding the scene, building
the instanced meshes, compiling the shaders, drawing.  The WebDriver's wall
time from the request to that moment (a new renderer process and its polling
included) is recorded beside it.  The issue's targets: under 3 s and about 20 MB for 4,800 blocks.

    python -m benchmarks.view [--quick]
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

from benchmarks.common import main, pyplot, save_chart, write_json
from interlock.blocks import random_hexagon, rhomblock_assembly
from interlock.gallery import write_view
from interlock.verify import check, contacts

#: Hexagon sides: a x b + b x c + c x a blocks (300, 1,200, 4,800).
SIZES = (10, 20, 40)
QUICK_SIZES = (4, 8)
#: Page loads per size (the median is reported).
LOADS = 5
#: The issue's targets for the 4,800-block view.
TARGET_SECONDS = 3.0
TARGET_BYTES = 20e6


def _browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    from tests.gallery.browser import CHROMIUM, DRIVER, FLAGS, first_found

    options = webdriver.ChromeOptions()
    options.binary_location = first_found(CHROMIUM)
    for flag in FLAGS:
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(first_found(DRIVER)), options=options)


def _load(driver, path: Path) -> tuple[float, float]:
    """(in-page seconds until the first frame is on screen, WebDriver wall seconds) of one load."""
    driver.get("about:blank")
    start = time.perf_counter()
    driver.get(path.resolve().as_uri())
    while not driver.execute_script("return !!(window.interlock && window.interlock.shown !== undefined)"):
        time.sleep(0.01)
    errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"]
    if errors:
        raise RuntimeError(f"the view logged errors: {errors}")
    drawn = driver.execute_script(
        "var gl = document.querySelector('.iv-stage canvas').getContext('webgl2'), pixel = new Uint8Array(4);"
        "gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); return performance.now();")
    return drawn / 1000, time.perf_counter() - start


def run(quick: bool = False) -> dict:
    rows = []
    driver = _browser()
    try:
        with tempfile.TemporaryDirectory() as folder:
            for side in (QUICK_SIZES if quick else SIZES):
                assembly = rhomblock_assembly(random_hexagon(side, side, side, seed=0), 0, frame="boundary")
                clock = time.perf_counter()
                found = contacts(assembly)
                verdict = check(assembly, contacts=found)
                verified = time.perf_counter() - clock
                clock = time.perf_counter()
                path = write_view(assembly, Path(folder) / f"hexagon-{side}.html", verdict, contacts=found)
                written = time.perf_counter() - clock
                loads = [_load(driver, path) for _ in range(LOADS)]
                row = {"blocks": len(assembly), "frame": len(verdict.frame), "verdict": str(verdict)[:80],
                       "bytes": path.stat().st_size, "write_seconds": written, "verify_seconds": verified,
                       "load_seconds": statistics.median(s for s, _ in loads),
                       "load_seconds_all": [s for s, _ in loads],
                       "webdriver_seconds": statistics.median(w for _, w in loads)}
                rows.append(row)
                print(f"{row['blocks']:5d} blocks: {row['bytes'] / 1e6:5.1f} MB, written in {written:.2f} s, "
                      f"on screen after {row['load_seconds']:.2f} s (median of {LOADS}; WebDriver "
                      f"{row['webdriver_seconds']:.2f} s)")
        version = driver.capabilities.get("browserVersion")
    finally:
        driver.quit()
    largest = rows[-1]
    payload = {"benchmark": "view", "quick": quick, "browser": f"chromium {version} headless (SwiftShader WebGL)",
               "rows": rows, "target_seconds": TARGET_SECONDS, "target_bytes": TARGET_BYTES,
               "largest_within_targets": largest["load_seconds"] < TARGET_SECONDS and largest["bytes"] < TARGET_BYTES}
    write_json("view", payload)
    _chart(rows)
    return payload


def _chart(rows):
    plt = pyplot()
    if plt is None:
        return
    fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.6))
    blocks = [r["blocks"] for r in rows]
    left.plot(blocks, [r["load_seconds"] for r in rows], "o-", label="on screen (page clock)")
    left.plot(blocks, [r["webdriver_seconds"] for r in rows], "s--", label="WebDriver wall time")
    left.axhline(TARGET_SECONDS, color="C3", lw=1, ls=":", label="target 3 s")
    left.set_xlabel("blocks")
    left.set_ylabel("seconds")
    left.set_title("load in headless Chromium")
    left.legend(fontsize=8)
    right.plot(blocks, [r["bytes"] / 1e6 for r in rows], "o-")
    right.axhline(TARGET_BYTES / 1e6, color="C3", lw=1, ls=":", label="target 20 MB")
    right.set_xlabel("blocks")
    right.set_ylabel("MB")
    right.set_title("view.html size (three.js inline: 2.2 MB)")
    right.legend(fontsize=8)
    fig.suptitle("interlock view of RhomBlock hexagons, ring fixed")
    save_chart(fig, "view")
    plt.close(fig)


if __name__ == "__main__":
    main(run, __doc__)
