"""Debian's headless Chromium driven by selenium, for the viewer page's test and benchmark.

Only the ``chromium`` and ``chromedriver`` already installed (apt ``chromium``,
``chromium-driver``) are used: selenium is given the driver's path, so its manager never
downloads one. Each browser gets a fresh profile, deleted afterwards.
"""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

__all__ = ["FLAGS", "MISSING", "chromium", "missing"]

#: What Chromium needs to run headless as root, and nothing reaching the network.
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--window-size=1400,1250",
)
MISSING = (
    "needs Debian's chromium and chromedriver: apt-get install -y chromium "
    "chromium-driver (.ci/run installs them)"
)


def missing() -> bool:
    """Whether the browser or its driver is not installed."""
    return shutil.which("chromium") is None or shutil.which("chromedriver") is None


@contextmanager
def chromium(downloads: Path | None = None) -> Iterator[Any]:
    """A selenium ``webdriver.Chrome`` on the installed Chromium, quit on leaving."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(shutil.which("chromium"))
    for flag in FLAGS:
        options.add_argument(flag)
    with tempfile.TemporaryDirectory(prefix="skelprune-chromium-") as profile:
        options.add_argument(f"--user-data-dir={profile}")
        driver = webdriver.Chrome(
            options=options, service=Service(executable_path=shutil.which("chromedriver"))
        )
        driver.set_page_load_timeout(30)
        if downloads is not None:
            driver.execute_cdp_cmd(
                "Browser.setDownloadBehavior", {"behavior": "allow", "downloadPath": str(downloads)}
            )
        try:
            yield driver
        finally:
            driver.quit()
