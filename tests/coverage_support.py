"""Helpers of the coverage tests: run our commands as subprocesses."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

BIN = Path(sys.executable).parent


def run(*args: str, cwd: Path, timeout: float = 300, check: bool = True) -> subprocess.CompletedProcess:
    """Run one of our commands (or any program); stdout and stderr kept apart."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    done = subprocess.run(list(args), cwd=cwd, capture_output=True, text=True, timeout=timeout, env=env)
    if check and done.returncode not in (0, 1):
        raise AssertionError(f"{' '.join(args)} exited {done.returncode}:\n{done.stdout}\n{done.stderr}")
    return done


def coverage(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return run(str(BIN / "scenario_coverage"), *args, cwd=cwd, check=False)


CHROMIUM = os.environ.get("SCENARIO_CHROMIUM", "/usr/bin/chromium")


@contextlib.contextmanager
def chromium_page(page_file: Path, width: int = 1280) -> Iterator[tuple[Any, list[str], list[str]]]:
    """``page_file`` open in the system's headless Chromium (Playwright): yields the page, the console errors,
    warnings and page errors seen, and the URLs requested. Without Chromium or Playwright the test is
    skipped, except in CI (``$CI``), where it fails: CI installs both."""
    import pytest

    if not os.path.exists(CHROMIUM):
        if os.environ.get("CI"):
            pytest.fail(f"no Chromium at {CHROMIUM} (.ci/run installs it)")
        pytest.skip(f"no Chromium at {CHROMIUM}: apt-get install chromium")
    if os.environ.get("CI"):
        from playwright.sync_api import sync_playwright
    else:
        sync_playwright = pytest.importorskip("playwright.sync_api", reason="pip install -e '.[browser]'").sync_playwright
    problems: list[str] = []
    requests: list[str] = []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": width, "height": 900})
            page.on("console", lambda m: problems.append(m.text) if m.type in ("error", "warning") else None)
            page.on("pageerror", lambda e: problems.append(str(e)))
            page.on("request", lambda r: requests.append(r.url))
            page.goto(page_file.as_uri(), wait_until="load")
            yield page, problems, requests
        finally:
            browser.close()
