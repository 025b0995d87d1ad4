"""The HTML report in a real browser: headless Chromium from Debian's packages, driven by
selenium through Debian's chromedriver (``make test-browser`` installs both).

Each page (the demo's report, and ``odomkit report`` on a built-in log) must load with every
image decoded (``naturalWidth > 0``), no console error (the page's Content-Security-Policy
turns any attempt to fetch from the network into one), no resource fetched, and is saved as
a full-page screenshot: in the test's temporary folder, and where ``ODOMKIT_SCREENSHOT``
says (the demo's there, the others beside it as ``<stem>-<page>.png``).
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import os
import shutil
from pathlib import Path

import pytest

from odomkit.cli import main
from odomkit.data import builtin_data_path

pytestmark = pytest.mark.browser

CHROMIUM = shutil.which("chromium") or ("/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None)
DRIVER = shutil.which("chromedriver")
_MISSING = [what for what, ok in (("chromium", CHROMIUM), ("chromedriver", DRIVER),
                                  ("the selenium package", importlib.util.find_spec("selenium")))
            if not ok]
if _MISSING:
    pytest.skip(f"not installed: {', '.join(_MISSING)}; run `make test-browser` (installs Debian's "
                "chromium and chromium-driver and the 'browser' extra)", allow_module_level=True)

WIDTH = 1280
# As root Chromium needs --no-sandbox; the rest keeps it from reaching any network service.
ARGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-dev-shm-usage",
        "--hide-scrollbars", f"--window-size={WIDTH},900")


def _quiet(argv: list[str]) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(argv) == 0


@pytest.fixture(scope="module")
def pages(tmp_path_factory) -> dict[str, Path]:
    """The demo's report and the report of one built-in log with its own truth."""
    folder = tmp_path_factory.mktemp("reports")
    _quiet(["demo", "--out", str(folder / "demo")])
    log = folder / "log.html"
    _quiet(["report", str(builtin_data_path("230620202042_run-01.csv")), "--robot",
            str(builtin_data_path("optiodom_diff.toml")), "--out", str(log)])
    return {"demo": folder / "demo" / "report.html", "log": log}


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in ARGS:
        options.add_argument(arg)
    options.add_argument(f"--user-data-dir={tmp_path_factory.mktemp('chromium-profile')}")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=options, service=Service(executable_path=DRIVER))
    try:
        yield driver
    finally:
        driver.quit()


def _screenshot(driver, target: Path) -> Path:
    """The whole page: the viewport made as tall as the document first (the window's own
    frame would otherwise cut its foot)."""
    height = driver.execute_script("return document.documentElement.scrollHeight")
    driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride", {
        "width": WIDTH, "height": min(int(height), 30000), "deviceScaleFactor": 1, "mobile": False})
    target.parent.mkdir(parents=True, exist_ok=True)
    assert driver.save_screenshot(str(target))
    return target


def _keep(name: str, shot: Path) -> None:
    wanted = os.environ.get("ODOMKIT_SCREENSHOT")
    if wanted:
        path = Path(wanted)
        if name != "demo":
            path = path.with_name(f"{path.stem}-{name}{path.suffix or '.png'}")
        path.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(shot, path)


@pytest.mark.parametrize("name", ["demo", "log"])
def test_report_renders_in_chromium(browser, pages, name, tmp_path):
    page = pages[name]
    browser.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})
    browser.set_window_size(WIDTH, 900)
    browser.get(page.resolve().as_uri())
    browser.get_log("browser")  # nothing from an earlier page
    browser.refresh()
    state = browser.execute_script("""
        const imgs = [...document.images];
        return {
          ready: document.readyState,
          images: imgs.map(i => ({alt: i.alt, complete: i.complete, width: i.naturalWidth,
                                  height: i.naturalHeight, shown: i.getBoundingClientRect().width})),
          svgs: [...document.querySelectorAll('svg')].map(s => s.getBoundingClientRect().width),
          resources: performance.getEntriesByType('resource').map(r => r.name),
          title: document.title,
          sections: [...document.querySelectorAll('h2')].map(h => h.textContent),
          overflow: document.documentElement.scrollWidth - document.documentElement.clientWidth,
        };""")
    assert state["ready"] == "complete"
    assert state["images"], "the report has no figure"
    for image in state["images"]:
        assert image["complete"] and image["width"] > 0 and image["height"] > 0, image
        assert image["shown"] > 100, image  # laid out at a readable width
    assert all(width > 0 for width in state["svgs"])
    assert [r for r in state["resources"] if not r.startswith("data:")] == []
    assert state["overflow"] <= 0, "the page scrolls sideways"
    assert len(state["sections"]) >= 4
    errors = [e for e in browser.get_log("browser") if e["level"] in ("SEVERE", "ERROR")]
    assert errors == []
    shot = _screenshot(browser, tmp_path / f"report-{name}.png")
    assert shot.stat().st_size > 10_000
    _keep(name, shot)


def test_console_errors_are_seen(browser, tmp_path):
    """The check itself can fail: a page that loads an image from the network is refused by
    the report's Content-Security-Policy, and the refusal is a console error."""
    from odomkit.report import Paragraph, Section, render_report

    page = render_report("t", [Section("a", "A", (Paragraph("x"),))])
    page = page.replace("<p>x</p>", '<img src="http://127.0.0.1:9/x.png" alt="remote">')
    target = tmp_path / "bad.html"
    target.write_text(page, encoding="utf-8")
    browser.get(target.as_uri())
    width = browser.execute_script("return document.images[0].naturalWidth")
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    assert width == 0 and errors
