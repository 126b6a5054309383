"""The viewer page in headless Chromium: how long a shape takes to appear and a step to
redraw, by image size.

kimia99's hand scaled to 512, 1024 and 2048 px a side, through a real server with one
worker. For each: upload to drawing, the request's round trip as the page measures it,
one step of the slider, the whole sequence at once (first step to last), and the size of
the document with its sequence; medians of 3 loads, 3 jumps each.

``python -m benchmarks viewer`` (about a minute; needs Debian's chromium and
chromium-driver).
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

from testkit import DATA
from testkit.browser import MISSING, chromium, missing
from testkit.realserver import running_server

from .common import table, upscale

SIZES = (512, 1024, 2048)
STEP = (
    "const t = performance.now();"
    "document.dispatchEvent(new KeyboardEvent('keydown', {key: arguments[0]}));"
    "return performance.now() - t;"
)


def main() -> None:
    if missing():
        print(f"the viewer benchmark {MISSING}")
        return
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    hand = np.asarray(Image.open(DATA / "kimia99" / "hand-1.png")) > 0
    rows = []
    with (
        tempfile.TemporaryDirectory() as tmp,
        running_server(Path(tmp) / "server.log", workers="1", job_timeout="120") as (_, base),
        chromium() as driver,
    ):
        for size in SIZES:
            path = Path(tmp) / f"hand-{size}.png"
            Image.fromarray(upscale(hand, size).astype(np.uint8) * 255).save(path)
            shown, request, one, whole, mb = [], [], [], [], 0.0
            for _ in range(3):
                driver.get(base + "/")
                t = time.perf_counter()
                driver.find_element(By.ID, "file").send_keys(str(path))
                WebDriverWait(driver, 300, poll_frequency=0.01).until(
                    lambda d: d.find_element(By.ID, "result").is_displayed()
                )
                shown.append(time.perf_counter() - t)
                request.append(driver.execute_script("return state.elapsed") / 1000)
                mb = driver.execute_script("return state.text.length") / 1e6
                for _ in range(3):
                    whole.append(driver.execute_script(STEP, "Home"))
                    one.append(driver.execute_script(STEP, "ArrowRight"))
                    whole.append(driver.execute_script(STEP, "End"))
            rows.append(
                [
                    size,
                    statistics.median(shown),
                    statistics.median(request),
                    statistics.median(one),
                    statistics.median(whole),
                    mb,
                ]
            )
    print(
        table(
            [
                "px a side",
                "upload to drawn s",
                "request s",
                "one step ms",
                "whole sequence ms",
                "document MB",
            ],
            rows,
        )
    )
