"""The HTML report in a real headless Chromium (the system's ``/usr/bin/chromium``, driven by Playwright).

Playwright (an optional extra, ``.[browser]``) is used rather than ``chromium --headless --dump-dom``
because it reports console messages, uncaught page errors and every request as events, and queries the
rendered DOM: the test can assert that nothing but the file itself was loaded, that no error was logged,
and what a reader sees. The screenshot is kept for CI in ``$SCENARIO_ARTIFACTS`` (default
``.ci/artifacts/``).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from urllib.parse import unquote, urljoin, urlparse

import pytest
from coverage_support import coverage

pytest_plugins = ["coverage_fixtures"]

ROOT = Path(__file__).resolve().parent.parent
CHROMIUM = os.environ.get("SCENARIO_CHROMIUM", "/usr/bin/chromium")


def _playwright():
    if os.environ.get("CI"):
        from playwright.sync_api import sync_playwright  # CI installs it (.ci/run): missing is a failure
        return sync_playwright
    sync_api = pytest.importorskip("playwright.sync_api", reason="pip install -e '.[browser]'")
    return sync_api.sync_playwright


def artifacts() -> Path:
    folder = Path(os.environ.get("SCENARIO_ARTIFACTS", ROOT / ".ci" / "artifacts"))
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def test_the_html_report_opens_offline_and_shows_grades_heat_maps_and_links(child_batch, tmp_path):
    if not os.path.exists(CHROMIUM):
        reason = f"no Chromium at {CHROMIUM} (apt-get install chromium; .ci/run does)"
        if os.environ.get("CI"):
            pytest.fail(reason)           # CI installs it: a missing browser there is a failure
        pytest.skip(reason)
    sync_playwright = _playwright()
    page_file = child_batch.root / "site" / "coverage.html"
    done = coverage("html", "results", "-o", str(page_file), cwd=child_batch.root)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"wrote {page_file} (grade 76.6 %, 12 run(s))"
    text = page_file.read_text(encoding="utf-8")
    assert "http://" not in text and "https://" not in text and "<script" not in text

    problems, requests = [], []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}")
                    if m.type in ("error", "warning") else None)
            page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
            page.on("requestfailed", lambda r: problems.append(f"request failed: {r.url}"))
            page.on("request", lambda r: requests.append(r.url))
            page.goto(page_file.as_uri(), wait_until="load")

            assert page.title() == "Scenario coverage 76.6% — results"
            assert page.inner_text("#overall .big") == "76.6%"
            assert "4 passed" in page.inner_text(".legend") and "2 error" in page.inner_text(".legend")
            grades = dict(zip(page.locator("table.overview tbody tr td:first-child").all_inner_texts(),
                              page.locator("table.overview tbody tr td:nth-child(3)").all_inner_texts(),
                              strict=False))
            assert grades["cut_in.ego_speed"] == "33.3%" and grades["input:cut_in.speed x cut_in.gap"] == "83.3%"

            # One heat map per two-way cross: 3 of varied parameters, 1 cover cross (6 x 3 cells).
            maps = page.locator("table.heat")
            assert maps.count() == 4
            cross = page.locator("#item-9 table.heat")
            assert cross.locator("tbody td").count() == 18 and cross.locator("tbody td.hole").count() == 14
            hit = cross.locator("tbody td:not(.hole)").first
            assert hit.locator(".h").inner_text() == "1" and hit.locator(".r").inner_text() == "100%"
            assert "2 error" in page.locator("#item-3 table.heat td.hole").inner_text()

            # Holes are listed, a failing run's link leads to its log in the results folder.
            assert page.locator("#item-6 .holes .hole").all_inner_texts() == [
                "[0..25)", "[75..100)", "[100..125)", "[125..150]"]
            link = page.locator("#failing a", has_text="log").first
            target = Path(unquote(urlparse(urljoin(page.url, link.get_attribute("href"))).path))
            assert target == child_batch.results / "cut_in0" / "log.txt" and target.is_file()

            shot = artifacts() / "coverage-report.png"
            page.screenshot(path=str(shot), full_page=True)
            page.screenshot(path=str(artifacts() / "coverage-report-top.png"))
        finally:
            browser.close()
    assert problems == []
    assert requests == [page_file.as_uri()]          # nothing but the page itself: no CDN, no network
    assert shot.stat().st_size > 50_000
    shutil.copy(page_file, artifacts() / "coverage-report.html")
