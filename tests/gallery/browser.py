"""A headless Chromium for the viewer's tests (Debian's chromium and chromium-driver, driven by Selenium)."""

from __future__ import annotations

import base64
import io
import json
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

#: Where Debian puts the browser and its driver (``apt-get install chromium chromium-driver``; ``.ci/run`` does).
CHROMIUM = ("chromium", "chromium-browser", "google-chrome")
DRIVER = ("chromedriver",)
#: Software WebGL: the machines that run the tests have no GPU.
FLAGS = ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--use-angle=swiftshader",
         "--enable-unsafe-swiftshader", "--window-size=1200,900", "--disable-gpu-sandbox")
#: Polls of a page's state (window.interlock.ready, a mounted view) before a test gives up; each 0.1 s.
POLLS = 3000


def first_found(names) -> str | None:
    return next((found for found in map(shutil.which, names) if found), None)


def launch():
    """A Selenium driver on headless Chromium that records console messages and network requests.

    Skips the test when the browser is genuinely missing here, but fails under CI (``CI=true``), where
    ``.ci/run`` installs it: a green CI run has run these tests.
    """
    try:
        from selenium import webdriver
        from selenium.webdriver.chrome.service import Service
    except ImportError:
        _missing("selenium is not installed (pip install -e '.[test]')")
    browser, driver = first_found(CHROMIUM), first_found(DRIVER)
    if browser is None or driver is None:
        _missing("Debian's chromium and chromium-driver are not installed (apt-get install chromium chromium-driver)")
    options = webdriver.ChromeOptions()
    options.binary_location = browser
    for flag in FLAGS:
        options.add_argument(flag)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL", "performance": "ALL"})
    return webdriver.Chrome(service=Service(driver), options=options)


def _missing(reason: str):
    if os.environ.get("CI", "").lower() == "true":
        pytest.fail(f"{reason}; .ci/run installs it, so under CI this is a failure, not a skip")
    pytest.skip(reason)


class Page:
    """A page opened from ``file://``: its console, its requests, its canvas."""

    def __init__(self, driver, path: Path):
        self.driver = driver
        self.path = Path(path).resolve()
        driver.get_log("browser")  # drop what earlier pages logged
        driver.get_log("performance")
        self.url = self.path.as_uri()
        self.started = time.perf_counter()
        driver.get(self.url)
        self.wait("return !!(window.interlock && window.interlock.ready)")
        self.seconds = time.perf_counter() - self.started
        self._requests, self._console = [], []

    def js(self, script: str, *args):
        return self.driver.execute_script(script, *args)

    def wait(self, script: str, *args):
        for _ in range(POLLS):
            value = self.js(script, *args)
            if value:
                return value
            time.sleep(0.1)
        raise AssertionError(f"the page never satisfied {script!r}; console: {self.console()}")

    def console(self) -> list[dict]:
        self._console += self.driver.get_log("browser")
        return list(self._console)

    def errors(self) -> list[str]:
        return [entry["message"] for entry in self.console() if entry["level"] == "SEVERE"] + \
            list(self.js("return window.interlock ? window.interlock.errors : []") or [])

    def requests(self) -> list[str]:
        """Every URL the page asked for (the DevTools protocol's ``Network.requestWillBeSent``)."""
        for entry in self.driver.get_log("performance"):
            message = json.loads(entry["message"])["message"]
            if message["method"] == "Network.requestWillBeSent":
                self._requests.append(message["params"]["request"]["url"])
        return list(self._requests)

    def outside(self) -> list[str]:
        """The requests that leave the page's own folder: anything but ``file://`` below it and ``data:``."""
        folder = self.path.parent.as_uri()
        return [url for url in self.requests() if not (url.startswith(folder + "/") or url.startswith("data:"))]

    def pixels(self, element) -> np.ndarray:
        """An element's pixels as drawn (a screenshot of it), (h, w, 3) uint8."""
        from PIL import Image

        picture = Image.open(io.BytesIO(base64.b64decode(element.screenshot_as_base64))).convert("RGB")
        return np.asarray(picture)

    def screenshot(self, path: Path) -> Path:
        self.driver.save_screenshot(str(path))
        return path


def varied(pixels: np.ndarray) -> bool:
    """Not blank: many colours and a spread of brightness (a cleared canvas has one colour)."""
    flat = pixels.reshape(-1, 3)
    colours = len(np.unique(flat[:: max(len(flat) // 20000, 1)], axis=0))
    return colours > 50 and float(flat.std()) > 10.0
