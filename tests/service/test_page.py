"""The viewer page at ``/``, in a real browser against the real server.

Debian's headless Chromium and its chromedriver (apt ``chromium chromium-driver``, which
``.ci/run`` installs) drive the page with selenium: upload a dataset shape, wait for the
skeleton, walk the pruning sequence with the keyboard and the slider, and check the
drawing against the library's own skeleton of each step; then the readable problem
messages. One server and one browser for the whole module. Screenshots go to
``artefacts/page/`` (not tracked) for people to look at.
"""

from __future__ import annotations

import io
import json
import re
from collections.abc import Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

import skelprune
from service.http.schemas import PruneDocument
from skelprune.io.png import read_mask
from testkit import DATA, REPO
from testkit.browser import MISSING, chromium
from testkit.browser import missing as browser_missing
from testkit.realserver import Running, running_server

SHOTS = REPO / "artefacts" / "page"
BIRD = DATA / "kimia216" / "bird-2.png"
#: Small enough that a test image can exceed it, large enough for the large shape.
MAX_PIXELS = 1_200_000


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Running]:
    log = tmp_path_factory.mktemp("page") / "server.log"
    with running_server(log, workers="1", max_pixels=str(MAX_PIXELS)) as running:
        yield running


@pytest.fixture(scope="module")
def downloads(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("downloads")


@pytest.fixture(scope="module")
def browser(downloads: Path) -> Iterator[object]:
    if browser_missing():
        pytest.fail(f"the browser test {MISSING}")
    with chromium(downloads) as driver:
        yield driver


def _wait(driver, condition, timeout: float = 60):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout).until(condition)


def _upload(driver, base: str, path: Path) -> None:
    from selenium.webdriver.common.by import By

    driver.get(base + "/")
    driver.find_element(By.ID, "file").send_keys(str(path))


def _result(driver) -> dict[str, int]:
    """The step the page shows and what it drew, once the skeleton is there."""
    from selenium.webdriver.common.by import By

    _wait(
        driver,
        lambda d: (
            d.find_element(By.ID, "result").is_displayed()
            and d.find_element(By.ID, "step-info").get_attribute("data-step") not in (None, "")
        ),
    )
    info = driver.find_element(By.ID, "step-info")
    drawn = driver.find_elements(By.CSS_SELECTOR, "#branches .branch")
    ends = driver.find_elements(By.CSS_SELECTOR, "#nodes circle.endpoint")
    return {
        "step": int(info.get_attribute("data-step")),
        "drawn": len(drawn),
        "endpoints_drawn": len(ends),
        "branches": int(info.get_attribute("data-branches")),
        "error": int(info.get_attribute("data-error-pixels")),
        "expected_error": int(info.get_attribute("data-expected-error-pixels")),
    }


def _lost_at(comp, k: int) -> int:
    """Pixels ``S(k)`` misses as the page shows it: the chosen step with its tips cut."""
    if k == comp.chosen_step and comp.trim is not None:
        return comp.trim.lost
    return comp.sequence.lost[k]


def _answer_lost(comp) -> int:
    return _lost_at(comp, comp.chosen_step)


def _shot(driver, name: str) -> Path:
    SHOTS.mkdir(parents=True, exist_ok=True)
    path = SHOTS / name
    driver.save_screenshot(str(path))
    return path


def _press(driver, key: str, times: int = 1) -> None:
    from selenium.webdriver.common.by import By

    body = driver.find_element(By.TAG_NAME, "body")
    for _ in range(times):
        body.send_keys(key)


def test_page_and_assets_are_served_by_the_service(server: Running) -> None:
    _, base = server
    page = httpx.get(base + "/", timeout=10)
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    # no asset from anywhere else: the page works offline
    refs = re.findall(r'(?:src|href)="([^"]+)"', page.text)
    assert refs and all(r.startswith(("/", "data:")) for r in refs), refs
    for path, kind in (("/ui/app.js", "text/javascript"), ("/ui/style.css", "text/css")):
        r = httpx.get(base + path, timeout=10)
        assert r.status_code == 200 and r.headers["content-type"].startswith(kind)
        assert not re.search(r"https?://(?!www\.w3\.org)", r.text), path


@pytest.mark.parametrize(
    "query", ["sequence=true&coarse=dce", "sequence=true", "sequence=true&method=dce", ""]
)
def test_the_sequence_opt_in_is_in_the_schema(server: Running, query: str) -> None:
    _, base = server
    r = httpx.post(
        f"{base}/v1/prune?{query}",
        content=BIRD.read_bytes(),
        headers={"Content-Type": "image/png"},
        timeout=60,
    )
    assert r.status_code == 200
    doc = PruneDocument.model_validate(r.json())  # strict: no extra keys, right types
    seq = doc.components[0].sequence
    assert (seq is None) == (query == "")
    if seq is not None:
        assert seq.start == ("coarse" if "coarse=dce" in query else "medial_axis")
        assert bool(seq.coarse_removed) == (seq.start == "coarse")


def test_a_shape_and_its_pruning_sequence(server: Running, browser, downloads: Path) -> None:
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    _, base = server
    comp = skelprune.prune(read_mask(BIRD)).components[0]
    seq = comp.sequence
    n = len(seq.removed)
    assert n >= 3  # a sequence worth walking

    _upload(browser, base, BIRD)
    shown = _result(browser)
    # the answer first: what the library answers, drawn branch by branch
    assert shown["step"] == comp.chosen_step
    assert shown["drawn"] == shown["branches"] == comp.skeleton.n_branches
    assert shown["endpoints_drawn"] == comp.skeleton.n_endpoints
    assert shown["error"] == shown["expected_error"] == _answer_lost(comp)
    # a radius on hover: that of the endpoint under the pointer
    tip = browser.find_element(By.CSS_SELECTOR, "#nodes circle.endpoint")
    ActionChains(browser).move_to_element(tip).perform()
    hover = browser.find_element(By.ID, "hover").text
    radii = {f"{r:.3f}" for r in np.sqrt(comp.skeleton.r2)}
    assert (m := re.search(r"radius (\d+\.\d{3})", hover)) and m.group(1) in radii, hover
    assert "margin" in hover
    _shot(browser, "bird-answer.png")

    # the three downloads
    for button in browser.find_elements(By.CSS_SELECTOR, "[data-download]"):
        button.click()
    names = ("bird-2.json", "bird-2.geojson", "bird-2.overlay.png")
    _wait(browser, lambda d: all((downloads / n).is_file() for n in names), 30)
    assert "sequence" in json.loads((downloads / "bird-2.json").read_text())["components"][0]
    assert json.loads((downloads / "bird-2.geojson").read_text())["type"] == "FeatureCollection"
    # the overlay is scaled for reading: a whole multiple of the mask, >= 512 px long
    (w, h), (mw, mh) = Image.open(downloads / "bird-2.overlay.png").size, Image.open(BIRD).size
    assert w % mw == 0 and w // mw == h // mh and h % mh == 0 and max(w, h) >= 512

    # to the medial axis end (step 0) and back with the keyboard, then the slider
    _press(browser, Keys.HOME)
    for k in (0, 1, 2):
        if k:
            _press(browser, Keys.ARROW_RIGHT)
        shown = _result(browser)
        truth = seq.skeleton_at(k)
        assert shown["step"] == k
        assert shown["drawn"] == shown["branches"] == truth.n_branches, k
        assert shown["endpoints_drawn"] == truth.n_endpoints, k
        assert shown["error"] == shown["expected_error"] == _lost_at(comp, k), k
    _press(browser, Keys.HOME)
    assert "margin" not in browser.find_element(By.ID, "hover").text  # not the old step's
    _shot(browser, "bird-step0.png")
    slider = browser.find_element(By.ID, "step")
    slider.send_keys(Keys.END)  # the range input's own keys
    shown = _result(browser)
    assert shown["step"] == n
    assert shown["drawn"] == seq.skeleton_at(n).n_branches
    assert shown["error"] == _lost_at(comp, n)
    _shot(browser, "bird-last.png")

    # the coarse stage on request: the controls re-run the request, and the medial-axis
    # pixels it pruned are drawn on request
    from selenium.webdriver.support.ui import Select

    Select(browser.find_element(By.ID, "coarse")).select_by_visible_text("dce")
    coarse = skelprune.prune(read_mask(BIRD), coarse="dce").components[0]
    _wait(
        browser,
        lambda d: (
            _result(d)["step"] == coarse.chosen_step
            and "coarse" in d.find_element(By.ID, "sequence-note").text
        ),
    )
    assert _result(browser)["drawn"] == coarse.skeleton.n_branches
    assert not browser.find_elements(By.CSS_SELECTOR, "#medial rect")
    browser.find_element(By.ID, "show-medial").click()
    assert browser.find_elements(By.CSS_SELECTOR, "#medial rect")
    _shot(browser, "bird-coarse-dce.png")


def test_several_components(server: Running, browser, tmp_path: Path) -> None:
    """Each component walks its own sequence; the others stay at their answer."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select

    bird = read_mask(BIRD)
    hand = read_mask(DATA / "kimia99" / "hand-1.png")
    h = max(bird.shape[0], hand.shape[0])
    both = np.zeros((h, bird.shape[1] + hand.shape[1] + 10), bool)
    both[: bird.shape[0], : bird.shape[1]] = bird
    both[: hand.shape[0], bird.shape[1] + 10 :] = hand
    path = tmp_path / "two.png"
    Image.fromarray(both.astype(np.uint8) * 255).save(path)
    comps = skelprune.prune(both).components
    assert len(comps) == 2
    _, base = server
    _upload(browser, base, path)
    shown = _result(browser)
    assert shown["drawn"] == sum(c.skeleton.n_branches for c in comps)
    assert shown["error"] == _answer_lost(comps[0])
    Select(browser.find_element(By.ID, "component")).select_by_index(1)
    _press(browser, Keys.HOME)
    shown = _result(browser)
    assert shown["step"] == 0
    assert shown["drawn"] == comps[0].skeleton.n_branches + comps[1].sequence.start.n_branches
    assert shown["error"] == shown["expected_error"] == _lost_at(comps[1], 0)
    _shot(browser, "two-components.png")


def test_a_large_shape(server: Running, browser, tmp_path: Path) -> None:
    mask = read_mask(DATA / "kimia99" / "hand-1.png")
    big = np.kron(mask, np.ones((7, 7), bool))  # about 900 px a side
    path = tmp_path / "hand-x7.png"
    Image.fromarray(big.astype(np.uint8) * 255).save(path)
    comp = skelprune.prune(big).components[0]
    _, base = server
    _upload(browser, base, path)
    shown = _result(browser)
    assert shown["drawn"] == comp.skeleton.n_branches
    assert shown["error"] == shown["expected_error"] == _answer_lost(comp)
    _shot(browser, "hand-x7-answer.png")


def test_a_geojson_polygon(server: Running, browser, tmp_path: Path) -> None:
    """A polygon in map coordinates (y northwards), with a hole: drawn in its raster."""
    from selenium.webdriver.common.by import By

    x0, y0 = 530000.0, 4100000.0
    outer = [
        [x0, y0],
        [x0 + 900, y0],
        [x0 + 900, y0 + 300],
        [x0 + 560, y0 + 300],
        [x0 + 560, y0 + 700],
        [x0 + 340, y0 + 700],
        [x0 + 340, y0 + 300],
        [x0, y0 + 300],
        [x0, y0],
    ]
    hole = [
        [x0 + 400, y0 + 100],
        [x0 + 500, y0 + 100],
        [x0 + 500, y0 + 200],
        [x0 + 400, y0 + 200],
        [x0 + 400, y0 + 100],
    ]
    polygon = {"type": "Polygon", "coordinates": [outer, hole]}
    path = tmp_path / "tee.geojson"
    path.write_text(json.dumps(polygon))
    _, base = server
    doc = httpx.post(
        base + "/v1/prune?sequence=true",
        content=path.read_bytes(),
        headers={"Content-Type": "application/geo+json"},
        timeout=60,
    ).json()
    comp = doc["components"][0]
    _upload(browser, base, path)
    shown = _result(browser)
    assert shown["step"] == comp["chosen_step"]
    assert shown["drawn"] == len(comp["skeleton"]["branches"])
    assert shown["endpoints_drawn"] == len(comp["skeleton"]["endpoints"])
    assert shown["error"] == shown["expected_error"] == round(comp["rer"] * comp["area"])
    # the raster is drawn north up: the stem of the T (larger y) at the top
    svg = browser.find_element(By.ID, "view")
    ends = [
        e.location["y"] - svg.location["y"]
        for e in browser.find_elements(By.CSS_SELECTOR, "#nodes circle.endpoint")
    ]
    assert min(ends) < 0.25 * svg.size["height"] < max(ends)
    assert not browser.find_element(By.ID, "warnings").is_displayed()  # the raster holds it
    _shot(browser, "tee-geojson.png")
    # an islet no raster within the pixel budget can hold: the page says so, and why
    islet = [[x0 + 2e4, y0], [x0 + 2e4 + 1e-3, y0], [x0 + 2e4, y0 + 1e-3], [x0 + 2e4, y0]]
    far = {"type": "MultiPolygon", "coordinates": [[outer, hole], [islet]]}
    path = tmp_path / "islet.geojson"
    path.write_text(json.dumps(far))
    _upload(browser, base, path)
    _result(browser)
    box = browser.find_element(By.ID, "warnings")
    assert box.is_displayed()
    assert "of 2 is smaller than the pixel" in box.text and "none of the sizes tried" in box.text
    _shot(browser, "islet-warning.png")


def _ring_and_dot() -> np.ndarray:
    yy, xx = np.mgrid[:90, :140]
    d2 = (yy - 45) ** 2 + (xx - 45) ** 2
    ring = (d2 < 40**2) & (d2 >= 25**2)  # a loop and no end branch: nothing to prune
    dot = (np.abs(yy - 45) <= 1) & (np.abs(xx - 120) <= 1)  # 3 x 3: one point
    return ((ring | dot) * 255).astype(np.uint8)


def test_shapes_with_nothing_to_prune(server: Running, browser, tmp_path: Path) -> None:
    from selenium.webdriver.common.by import By

    image = _ring_and_dot()
    path = tmp_path / "ring.png"
    path.write_bytes(_png(image))
    comps = skelprune.prune(image > 0).components
    assert [len(c.sequence.removed) for c in comps] == [0, 0]
    _, base = server
    _upload(browser, base, path)
    shown = _result(browser)
    assert shown["step"] == 0
    assert shown["drawn"] == sum(c.skeleton.n_branches for c in comps)
    assert shown["error"] == shown["expected_error"] == _lost_at(comps[0], 0)
    assert browser.find_elements(By.CSS_SELECTOR, "#nodes circle.loop")
    severe = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert not severe, severe  # no script error
    _shot(browser, "ring-and-dot.png")


def _png(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    Image.fromarray(array).save(buf, format="PNG")
    return buf.getvalue()


@pytest.mark.parametrize(
    ("name", "image", "words"),
    [
        ("empty.png", np.zeros((40, 60), np.uint8), ("Empty mask (422)", "no foreground")),
        (
            "huge.png",
            np.pad(np.full((10, 10), 255, np.uint8), ((0, 1190), (0, 1190))),
            ("Image too large (413)", str(MAX_PIXELS)),
        ),
    ],
)
def test_problems_are_readable_messages(
    server: Running, browser, tmp_path: Path, name: str, image: np.ndarray, words: tuple[str, ...]
) -> None:
    from selenium.webdriver.common.by import By

    path = tmp_path / name
    path.write_bytes(_png(image))
    _, base = server
    _upload(browser, base, path)
    box = _wait(browser, lambda d: (e := d.find_element(By.ID, "problem")).is_displayed() and e)
    for w in words:
        assert w in box.text, box.text
    assert not browser.find_element(By.ID, "result").is_displayed()
    _shot(browser, f"problem-{Path(name).stem}.png")
