"""Every section of every coverage renderer, on one results folder that has them all, as CI sees it.

The results are made by the real commands: a braking scenario (two ranges drawn by a Latin hypercube,
an enum, a list of hold times of which one runs into the batch's ``--timeout``) varied into 12 variants
and run by ``scenario_batch_execution``. They hold passed and failed runs, timeouts, a ``record()``
item, ``cover()`` items with ignored samples and a failing region, crosses drawn as grids and a scatter,
holes, and a plan's warning. The plain report (a pipe, and ``-o FILE``) is compared whole with a golden
text, section by section first so a difference names its section; the JSON report likewise; the
terminal (TTY) report must show the same sections; the HTML report is read in headless Chromium.

The results live in a folder of fixed length under ``/tmp`` (its random part replaced by ``X`` in the
comparison), so the paths in the failing-runs table keep the table's column widths. Set
``SCENARIO_UPDATE_GOLDEN=1`` to rewrite the golden files after a deliberate change, and read the diff.
"""

from __future__ import annotations

import json
import os
import pty
import re
import shutil
import subprocess
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from coverage_support import BIN, chromium_page, coverage, run

GOLDEN = Path(__file__).resolve().parent / "golden"
UPDATE = os.environ.get("SCENARIO_UPDATE_GOLDEN") == "1"
PREFIX = "scov-golden-"

#: The parameters both braking scenarios vary: two ranges a sampler draws from, and an enum.
BRAKING_PARAMETERS = """\
import osc.helpers

enum road_kind: [dry, wet, icy]

scenario {name}:
    speed: speed with:
        keep(it in [20kph..120kph])
    reaction: time with:
        keep(it in [0.5s..2.5s])
    road: road_kind with:
        keep(it in [road_kind!dry, road_kind!wet, road_kind!icy])
"""

BRAKE = ("# A braking test: the driver must react within 2 s; a hold of 60 s runs into the batch's timeout.\n"
         + BRAKING_PARAMETERS.format(name="brake") + """\
    hold: time with:
        keep(it in [10ms, 20ms, 30ms, 60s])
    cover(road)
    cover(speed, unit: kph, range: [0..150], every: 25, ignore: speed > 110kph)
    cover(speed_x_road, items: [speed, road])
    record(reaction_time, expression: reaction, unit: s, event: finish, text: "reaction time of the driver")
    do serial:
        wait elapsed(hold)
        compare(reaction, "<=", 2.0s)
""")

PLAN = """\
items:
  brake.road:
    at_least: 2
  brake.no_such_item:
    weight: 2
"""


@pytest.fixture(scope="module")
def braking() -> Iterator[Path]:
    """12 variants of the braking test run with ``--timeout 3`` (3 of them hold 60 s)."""
    root = Path(tempfile.mkdtemp(prefix=PREFIX, dir="/tmp"))
    try:
        (root / "brake.osc").write_text(BRAKE, encoding="utf-8")
        (root / "plan.yaml").write_text(PLAN, encoding="utf-8")
        run(str(BIN / "scenario_variation"), "brake.osc", "--strategy", "lhs", "--samples", "12", "--seed", "7",
            "-o", "out", cwd=root)
        done = run(str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results", "-j", "2", "--timeout", "3",
                   cwd=root)
        assert done.returncode == 1 and "12 job(s): 7 passed, 2 failed, 3 timeout" in done.stdout, done.stdout
        yield root
    finally:
        shutil.rmtree(root, ignore_errors=True)


def normalised(text: str, root: Path) -> str:
    """``text`` with the results' folder spelled the same on every machine (same length: columns stay)."""
    return text.replace(str(root), "/tmp/" + PREFIX + "X" * (len(root.name) - len(PREFIX)))


def sections(text: str) -> list[str]:
    """The report's blocks, split at blank lines (the summary, the items table, each item, records, …)."""
    return [block for block in text.split("\n\n") if block.strip()]


def compare_with_golden(actual: str, name: str) -> None:
    path = GOLDEN / name
    if UPDATE:
        path.parent.mkdir(exist_ok=True)
        path.write_text(actual, encoding="utf-8")
    expected = path.read_text(encoding="utf-8")
    got, want = sections(actual), sections(expected)
    for index, (mine, golden) in enumerate(zip(got, want, strict=False)):
        title = golden.splitlines()[0]
        assert mine == golden, f"section {index + 1} ({title!r}) differs from {path}"
    assert len(got) == len(want), f"{len(got)} sections, the golden text {path} has {len(want)}"
    assert actual == expected


def test_the_plain_report_in_a_pipe_is_the_golden_text(braking):
    done = coverage("report", "results", "--plan", "plan.yaml", cwd=braking)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    text = normalised(done.stdout, braking)
    compare_with_golden(text, "brake_report.txt")
    heads = [block.splitlines()[0] for block in sections(text)]
    # Every section is there, in order: summary, items, 10 varied parameters and crosses, 3 cover items,
    # the record item, the failing runs (failed and timed out, with their values).
    assert heads[0].startswith("Scenario coverage of results: 12 run(s) (7 passed, 2 failed, 3 error)")
    assert heads[1] == "Items" and heads[-2] == "Record items" and heads[-1] == "Failing runs (5)"
    assert "warning: the plan names 'brake.no_such_item', which matches no item" in text
    assert "ignore: speed > 110kph" in text and "1 failed" in text          # a failing region of the cross
    assert "speed ↓  road →" in text and "12 run(s); speed ↓  reaction →" in text
    assert "[20 kph..25 kph)" in text and "10ms" in text
    assert re.search(r"brake7 +error +speed=33.05kph, reaction=2.452s, road=road_kind!icy, hold=60s +"
                     r"timed out after 3 s", text)


def test_the_report_written_to_a_file_is_the_one_printed_in_a_pipe(braking):
    printed = coverage("report", "results", "--plan", "plan.yaml", cwd=braking).stdout
    done = coverage("report", "results", "--plan", "plan.yaml", "-o", "report.txt", cwd=braking)
    assert done.returncode == 0 and done.stdout == ""
    assert (braking / "report.txt").read_text(encoding="utf-8") == printed


def test_the_store_reports_the_same_items_as_the_folder(braking):
    folder = sections(coverage("report", "results", "--plan", "plan.yaml", cwd=braking).stdout)
    done = coverage("report", "results", "--store", f"sqlite:///{braking}/.scenario_store.db", "--plan", "plan.yaml",
                    cwd=braking)
    assert done.returncode == 0, done.stderr
    store = sections(done.stdout)
    assert store[0].startswith("Scenario coverage of batch 1 in sqlite:///")
    assert store[0].split("\n", 1)[1] == folder[0].split("\n", 1)[1]     # the same grade, holes and warning
    assert store[1:] == folder[1:]          # every item, the records and the failing runs, cell for cell


def test_the_terminal_report_shows_the_same_sections(braking):
    """On a terminal (a pseudo-terminal here) the report is drawn with colours and boxes: same sections."""
    leader, follower = pty.openpty()
    env = dict(os.environ, COLUMNS="220", LINES="50", TERM="xterm-256color")
    env.pop("NO_COLOR", None)
    process = subprocess.Popen([str(BIN / "scenario_coverage"), "report", "results", "--plan", "plan.yaml"],
                               cwd=braking, stdin=follower, stdout=follower, stderr=follower, env=env)
    os.close(follower)
    chunks = []
    while True:
        try:
            chunk = os.read(leader, 65536)
        except OSError:
            break
        if not chunk:
            break
        chunks.append(chunk)
    assert process.wait(timeout=120) == 0
    os.close(leader)
    raw = b"".join(chunks).decode("utf-8", "replace")
    assert "\x1b[" in raw                                   # colours: it knew it was a terminal
    text = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", raw)
    for title in ("Scenario coverage of results: 12 run(s)", "Items", "input:brake.speed  grade 80.0 %",
                  "speed ↓  reaction →", "speed ↓  road →", "brake.speed_x_road", "Record items",
                  "Failing runs (5)", "timed out after 3 s", "1 failed"):
        assert title in text, title


def test_the_json_report_is_the_golden_document(braking):
    done = coverage("json", "results", "--plan", "plan.yaml", cwd=braking)
    assert done.returncode == 0, done.stderr
    document = json.loads(normalised(done.stdout, braking))
    text = json.dumps(document, indent=1, ensure_ascii=False, sort_keys=True) + "\n"
    compare_with_golden(text, "brake_report.json")
    items = {item["name"]: item for item in document["items"]}
    cross = items["input:brake.speed x brake.reaction"]
    assert cross["weight"] == 0 and len(cross["points"]) == 12
    assert {p["verdict"] for p in cross["points"]} == {"passed", "failed", "error"}
    assert items["brake.speed_x_road"]["not_sampled"] == ["[50..75) × wet", "[100..125) × dry"]
    assert items["input:brake.hold"]["holes"] == ["60s"]
    first = document["failing_runs"][0]["values"]            # exact, as the variant's assignment has them
    assert first["brake.road"] == "road_kind!dry" and first["brake.hold"] == "10ms"
    assert abs(first["brake.speed"] - 113.5) < 0.05 and len(repr(first["brake.speed"])) > 8




def _browser_page(page_file: Path, screenshot: str | None = None, element: str | None = None):
    """Open ``page_file`` in headless Chromium; returns what a reader sees, as a dict of texts and counts."""
    with chromium_page(page_file) as (page, problems, _):
        seen = {
            "groups": page.locator("section.group h2").all_inner_texts(),
            "scatters": page.locator("svg.scatter").count(),
            "points": page.locator("svg.scatter circle").count(),
            "failed points": page.locator("svg.scatter circle.failed").count(),
            "error points": page.locator("svg.scatter circle.error").count(),
            "heat maps": page.locator("table.heat").count(),
            "not sampled cells": page.locator("table.heat td.notsampled").count(),
            "failing rows": page.locator("#failing tbody tr").all_inner_texts(),
            "records": page.locator("table.records tbody tr").all_inner_texts(),
            "callouts": page.locator(".callout").all_inner_texts(),
        }
        if screenshot:
            folder = Path(os.environ.get("SCENARIO_ARTIFACTS", Path(__file__).resolve().parents[1] / ".ci" /
                                         "artifacts"))
            folder.mkdir(parents=True, exist_ok=True)
            if element:
                page.locator(element).first.screenshot(path=str(folder / screenshot))
                page.screenshot(path=str(folder / screenshot.replace(".png", "-page.png")), full_page=True)
            else:
                page.screenshot(path=str(folder / screenshot), full_page=True)
            seen["screenshot"] = folder / screenshot
    assert problems == []
    return seen


def test_the_html_report_shows_every_section(braking):
    done = coverage("html", "results", "--plan", "plan.yaml", "-o", "coverage.html", cwd=braking)
    assert done.returncode == 0 and done.stdout.startswith("wrote coverage.html"), done.stderr
    seen = _browser_page(braking / "coverage.html")
    assert seen["groups"] == ["Failures by kind (5 in 2 group(s))", "Items at a glance", "Varied parameters",
                              "Cover items", "Record items", "Failing runs (5)"]
    assert seen["scatters"] == 1 and seen["points"] == 12
    assert seen["failed points"] == 2 and seen["error points"] == 3
    assert seen["heat maps"] == 6 and seen["not sampled cells"] == 2
    assert len(seen["failing rows"]) == 5 and "hold=60s" in seen["failing rows"][1]
    assert "timed out after 3 s" in seen["failing rows"][1]
    assert "brake.reaction_time" in seen["records"][0]
    assert any("the plan names 'brake.no_such_item'" in c for c in seen["callouts"])


SWEEP = ("# 60 runs of a braking test: failures where the reaction takes more than 2 s.\n"
         + BRAKING_PARAMETERS.format(name="sweep") + """\
    record(reaction_time, expression: reaction, unit: s, event: finish)
    do serial:
        wait elapsed(10ms)
        compare(reaction, "<=", 2.0s)
""")


def test_a_60_run_lhs_braking_sweep_in_the_browser(tmp_path):
    """The picture of the issue: two sampled ranges as a scatter of runs (failures at a reaction above 2 s),
    the enum crossed with each range as heat maps. The screenshot is kept for people to look at."""
    (tmp_path / "sweep.osc").write_text(SWEEP, encoding="utf-8")
    run(str(BIN / "scenario_variation"), "sweep.osc", "--strategy", "lhs", "--samples", "60", "--seed", "3",
        "-o", "out", cwd=tmp_path)
    run(str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "results", "-j", "2", cwd=tmp_path)
    assert coverage("html", "results", "-o", "sweep.html", cwd=tmp_path).returncode == 0
    seen = _browser_page(tmp_path / "sweep.html", "coverage-braking-sweep.png", "article:has(svg.scatter)")
    assert seen["points"] == 60 and seen["failed points"] == 15 and seen["heat maps"] == 2
    assert seen["screenshot"].stat().st_size > 20_000
    text = (tmp_path / "sweep.html").read_text(encoding="utf-8")
    assert "[20 kph..25 kph)" in text and "[0.5 s..0.6 s)" in text
