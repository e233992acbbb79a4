"""Make the pictures of the documentation again, from the examples, with the real commands.

``search-braking.png`` (docs/search.md) is the ``Search`` section of the HTML report of a real search on
``examples/search/brake_gap.osc``: ``scenario_search`` runs it (seeded, so the same rounds each time),
``scenario_coverage html`` writes the page, and headless Chromium (Playwright, the ``browser`` extra; the
browser at ``$SCENARIO_CHROMIUM``, default ``/usr/bin/chromium``) shoots the section as the HTML test of
the search report does. Run from anywhere, with the project's environment::

    .venv/bin/python docs/images/make_pictures.py            # writes docs/images/search-braking.png
    .venv/bin/python docs/images/make_pictures.py -o /tmp    # somewhere else
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
IMAGES = Path(__file__).resolve().parent

#: The search shown in docs/search.md: its example, and the command line the page describes.
SEARCH_EXAMPLE = ROOT / "examples" / "search" / "brake_gap.osc"
SEARCH_ARGS = ("--goal", "boundary", "--budget", "48", "--round", "8", "-j", "2", "--seed", "7")

#: The page's width in the browser (as the HTML tests open it).
PAGE_WIDTH = 1280

#: Where the system's Chromium is (the HTML tests read the same variable).
CHROMIUM = os.environ.get("SCENARIO_CHROMIUM", "/usr/bin/chromium")


def _command(name: str, *args: str, cwd: Path) -> None:
    """Run one of our console scripts (the one beside this Python), its output shown; stop on failure."""
    done = subprocess.run([str(Path(sys.executable).parent / name), *args], cwd=cwd, check=False)
    if done.returncode != 0:
        raise SystemExit(f"{name} {' '.join(args)} exited {done.returncode}")


def screenshot(page_file: Path, selector: str, picture: Path) -> None:
    """Shoot the element ``selector`` of ``page_file`` in headless Chromium into ``picture``."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": PAGE_WIDTH, "height": 900})
            page.goto(page_file.as_uri(), wait_until="load")
            page.locator(selector).screenshot(path=str(picture))
        finally:
            browser.close()


def search_picture(out: Path) -> Path:
    """``search-braking.png``: the report's Search section of the seeded search on the braking example."""
    picture = out / "search-braking.png"
    with tempfile.TemporaryDirectory(prefix="search-picture-") as work:
        folder = Path(work)
        _command("scenario_search", str(SEARCH_EXAMPLE), *SEARCH_ARGS, "-o", "search", cwd=folder)
        _command("scenario_coverage", "html", "search", "-o", "search.html", cwd=folder)
        screenshot(folder / "search.html", "#search", picture)
    return picture


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--out", type=Path, default=IMAGES, help="folder for the pictures (default: here)")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    print(f"wrote {search_picture(out)}")


if __name__ == "__main__":
    main()
