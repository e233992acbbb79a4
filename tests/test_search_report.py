"""``scenario_coverage`` on a search's folder: the rounds, the estimate, the runs coloured by round.

The folder is laid out as ``scenario_search`` lays it out (``roundN/variants``, ``roundN/results``,
``search.json``), made by the real ``scenario_variation`` and ``scenario_batch_execution``, with the
estimates written as the adaptive variation writes them (the contract of issue 35): the report must
not depend on which strategy proposed the variants. The ``Search`` section of the plain report is
compared with a golden text (``SCENARIO_UPDATE_GOLDEN=1`` rewrites it); the HTML is read in headless
Chromium.
"""

from __future__ import annotations

import json
import os
import re
import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from coverage_support import BIN, chromium_page, coverage, run
from search_support import fails, round_runs, write_brake
from test_coverage_report_golden import compare_with_golden, sections

#: The estimate of round 2 as the variation writes it: the boundary as variants (two ranges: not one
#: dimension), the worst case found, the goal not met yet.
ROUND_TWO = {
    "format": "scenario-coverage/search", "round": 2, "strategy": "boundary", "from": ["search/round1/results"],
    "runs_read": 5, "objective": None, "maximise": False,
    "estimate": {"boundary": {"axes": {}, "variants": [{"brake.speed": 12.0, "brake.gap": 26.0},
                                                       {"brake.speed": 18.0, "brake.gap": 45.0},
                                                       {"brake.speed": 24.0, "brake.gap": 72.0},
                                                       {"brake.speed": 27.0, "brake.gap": 88.0}],
                              "pairs": 3, "located": 1},
                 "worst": {"objective": "margin", "value": -31.5, "assignment": {"brake.speed": 28.0,
                                                                                 "brake.gap": 24.0},
                           "failed": True},
                 "holes": None, "done": False}}


@pytest.fixture(scope="module")
def searched(tmp_path_factory) -> Iterator[Path]:
    """Two rounds of the braking test (5 and 4 runs) in a search's folder, with the search's own file."""
    root = tmp_path_factory.mktemp("search-report")
    write_brake(root)
    env_store = dict(os.environ)
    env_store.pop("SCENARIO_STORE", None)
    for number, seed, samples in ((1, 1, 5), (2, 2, 4)):
        variants, results = f"search/round{number}/variants", f"search/round{number}/results"
        run(str(BIN / "scenario_variation"), "brake.osc", "--strategy", "lhs", "--samples", str(samples),
            "--seed", str(seed), "-o", variants, cwd=root)
        if number == 2:
            (root / variants / "search.json").write_text(json.dumps(ROUND_TWO), encoding="utf-8")
        run(str(BIN / "scenario_batch_execution"), "-i", variants, "-o", results, "-j", "2", cwd=root)
    runs = {n: round_runs(root / f"search/round{n}/results") for n in (1, 2)}
    whole = dict(ROUND_TWO, rounds=[{"round": n, "strategy": "lhs" if n == 1 else "boundary", "runs": len(r),
                                     "failed": sum(1 for _, s, _, _ in r if s != "passed")} for n, r in runs.items()],
                 settings={"scenario": str(root / "brake.osc"), "goal": "boundary", "budget": 9, "round_size": 5,
                           "seed": 1})
    (root / "search" / "search.json").write_text(json.dumps(whole), encoding="utf-8")
    yield root
    shutil.rmtree(root, ignore_errors=True)


def _search_section(text: str) -> str:
    found = [block for block in sections(text) if block.startswith("Search:")]
    assert len(found) == 1, text
    return found[0] + "\n"


def test_the_batch_keeps_the_rounds_estimate_in_its_results(searched):
    copied = json.loads((searched / "search/round2/results/search.json").read_text(encoding="utf-8"))
    assert copied == ROUND_TWO
    assert not (searched / "search/round1/results/search.json").exists()     # round 1 estimated nothing


def test_the_plain_report_has_a_search_section_after_the_summary(searched):
    done = coverage("report", "search", cwd=searched)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    blocks = sections(done.stdout)
    assert blocks[0].startswith("Scenario coverage of search: 9 run(s)")
    assert "note: a search of 2 round(s): round1, round2" in blocks[0]
    assert blocks[1].startswith("Search: goal boundary, 9 of 9 run(s) in 2 round(s)")
    section = _search_section(done.stdout)
    compare_with_golden(section, "search_section.txt")
    runs = {n: round_runs(searched / f"search/round{n}/results") for n in (1, 2)}
    for number, strategy in ((1, "lhs"), (2, "boundary")):        # the rows count what the rounds ran
        failed = sum(1 for _, _, speed, gap in runs[number] if fails(speed, gap))
        row = f"{number:>7}  {strategy:<8}  {len(runs[number]):>4}  {len(runs[number]) - failed:>6}  {failed:>10}"
        assert row in section.splitlines(), (row, section)
    failing = blocks[-1].splitlines()
    assert failing[0] == "Failing runs (3)"                            # each named by its round: the rounds
    assert sum(1 for line in failing if re.match(r" round[12]/brake\d ", line)) == 3     # name variants alike


def test_a_rounds_results_folder_reports_that_round(searched):
    done = coverage("report", "search/round2/results", cwd=searched)
    assert done.returncode == 0, done.stderr
    section = _search_section(done.stdout)
    assert section.startswith("Search: 4 run(s) in 1 round(s)")
    assert "      2  boundary     4" in section and "worst case: margin = -31.5 (failed)" in section
    plain = coverage("report", "search/round1/results", cwd=searched)
    assert "Search:" not in plain.stdout                  # a batch of no search: the report keeps its form


def test_the_json_report_has_a_search_section(searched):
    done = coverage("json", "search", cwd=searched)
    assert done.returncode == 0, done.stderr
    document = json.loads(done.stdout)
    found = document["search"]
    assert found["goal"] == "boundary" and found["budget"] == 9 and found["latest_round"] == 2
    assert [(r["round"], r["strategy"], r["runs"]) for r in found["rounds"]] == [(1, "lhs", 5), (2, "boundary", 4)]
    assert found["estimate"] == ROUND_TWO["estimate"]
    by_round = {}
    for entry in found["runs"]:
        by_round.setdefault(entry["round"], []).append(entry["name"])
    assert {n: len(names) for n, names in by_round.items()} == {1: 5, 2: 4}
    assert all(name.startswith(f"round{n}/") for n, names in by_round.items() for name in names)
    assert document["runs"]["total"] == 9
    plain = json.loads(coverage("json", "search/round1/results", cwd=searched).stdout)
    assert "search" not in plain


def test_the_html_report_draws_the_rounds_the_boundary_and_the_worst_case(searched):
    done = coverage("html", "search", "-o", "search.html", cwd=searched)
    assert done.returncode == 0, done.stderr
    with chromium_page(searched / "search.html") as (page, problems, requests):
        head = page.locator("#search h2").inner_text()
        marks = page.locator("svg.search .run")
        rounds = [marks.nth(i).get_attribute("data-round") for i in range(marks.count())]
        squares = page.locator("svg.search rect.run").count()
        colours = {page.locator(f"svg.search .run.r{n}").first.get_attribute("fill") for n in (1, 2)}
        boundary_line = page.locator("svg.search polyline.boundary").count()
        boundary_rings = page.locator("svg.search circle.boundary").count()
        worst = page.locator("svg.search g.worst").count()
        worst_tip = page.locator("svg.search g.worst title").text_content() or ""
        estimate = page.locator("#search ul.estimate li").all_inner_texts()
        rows = page.locator("#search table.rounds tbody tr").all_inner_texts()
        box = page.locator("svg.search").bounding_box()
        folder = Path(os.environ.get("SCENARIO_ARTIFACTS", Path(__file__).resolve().parents[1] / ".ci" / "artifacts"))
        folder.mkdir(parents=True, exist_ok=True)
        page.locator("#search").screenshot(path=str(folder / "search-braking.png"))
    assert problems == [] and all(url.startswith("file://") for url in requests)
    assert head == "Search: goal boundary, 9 of 9 run(s) in 2 round(s)"
    assert sorted(rounds) == ["1"] * 5 + ["2"] * 4
    failed = sum(1 for n in (1, 2) for _, _, speed, gap in round_runs(searched / f"search/round{n}/results")
                 if fails(speed, gap))
    assert squares == failed                                   # runs that did not pass are squares
    assert len(colours) == 2                                   # each round its own colour
    assert boundary_line == 1 and boundary_rings == 3          # the variant beyond the gap's range is left out
    assert worst == 1 and "margin = -31.5" in worst_tip
    assert estimate[:2] == ["boundary: 3 pair(s) of neighbouring runs disagree, 1 of them located to the resolution",
                            "boundary: 4 variant(s) where pass turns to fail"] and estimate[-1] == "goal not met yet"
    assert len(rows) == 2 and rows[1].split() == ["2", "boundary", "4", str(4 - sum(
        1 for _, _, s, g in round_runs(searched / "search/round2/results") if fails(s, g))),
        str(sum(1 for _, _, s, g in round_runs(searched / "search/round2/results") if fails(s, g)))]
    assert box is not None and box["width"] > 300


def test_a_boundary_along_one_range_is_a_line_with_its_error_as_a_band(searched, tmp_path):
    """A round's results folder whose estimate locates the boundary along the gap (one dimension)."""
    results = tmp_path / "results"
    shutil.copytree(searched / "search/round1/results", results)
    along = dict(ROUND_TWO, round=1, strategy="boundary",
                 estimate={"boundary": {"axes": {"brake.gap": {"value": 50.0, "error": 3.0, "unit": "m"}},
                                        "variants": []}, "worst": None, "holes": None, "done": True})
    (results / "search.json").write_text(json.dumps(along), encoding="utf-8")
    done = coverage("html", "results", "-o", "one.html", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    with chromium_page(tmp_path / "one.html") as (page, problems, _):
        band = page.locator("svg.search g.boundary rect")
        line = page.locator("svg.search g.boundary line")
        band_box, line_box = band.bounding_box(), line.bounding_box()
        plot = page.locator("svg.search > rect").first.bounding_box()
        tip = page.locator("svg.search g.boundary title").text_content() or ""
        estimate = page.locator("#search ul.estimate li").all_inner_texts()
    assert problems == []
    assert band_box and line_box and plot
    assert abs(band_box["width"] - plot["width"]) < 2 and band_box["height"] > 0     # across the speed range
    middle = plot["y"] + plot["height"] * (1 - (50.0 - 20.0) / 60.0)                 # gap 50 m of 20..80 m
    assert abs(line_box["y"] + line_box["height"] / 2 - middle) < 2
    assert abs(band_box["height"] - plot["height"] * 6.0 / 60.0) < 2                 # ± 3 m
    assert tip == "boundary: gap = 50 ± 3 m" and estimate == ["boundary: gap = 50 ± 3 m", "goal met"]
