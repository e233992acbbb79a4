"""The variation example end to end: scenario_variation, then scenario_batch_execution on its output."""

from __future__ import annotations

import subprocess
import xml.etree.ElementTree as ET

import pytest


@pytest.mark.slow
def test_variation_example_expands_and_runs_in_a_batch(project_root, tmp_path):
    source = project_root / "examples" / "example_scenario_variation" / "example_scenario_variation.osc"
    store = f"sqlite:///{tmp_path / 'store.db'}"
    made = subprocess.run(["scenario_variation", str(source), "-o", "out", "--store", store],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert made.returncode == 0, made.stdout + made.stderr
    variants = sorted(p.name for p in (tmp_path / "out").glob("*.sce"))
    assert variants == [f"example_scenario_variation{i}.sce" for i in range(4)]

    ran = subprocess.run(["scenario_batch_execution", "-i", "out", "-o", "results", "--store", store, "--",
                          "scenario_execution", "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    # The first keep varies slowest: variant 1 greets with "Hello" and addresses the robot.
    log = (tmp_path / "results" / "example_scenario_variation1" / "log.txt").read_text(encoding="utf-8")
    assert "Hello" in log and "robot" in log and "Good morning" not in log
    merged = ET.parse(tmp_path / "results" / "test.xml").getroot()
    assert sum(int(s.get("tests")) for s in merged.iter("testsuite")) == 4
    assert sum(int(s.get("failures")) + int(s.get("errors")) for s in merged.iter("testsuite")) == 0


def test_a_variant_finds_the_user_modules_beside_its_source(tmp_path):
    source = tmp_path / "src"
    source.mkdir()
    (source / "mylib.py").write_text("def twice(n):\n    return 2 * n\n", encoding="utf-8")
    (source / "e.osc").write_text(
        "import osc.helpers\n"
        "struct lib:\n"
        "    def twice(n: int) -> int is external mylib.twice()\n"
        "scenario e:\n"
        "    do serial:\n"
        "        log(lib.twice(21))\n"
        "        log() with:\n"
        "            keep(it.msg in ['a', 'b'])\n", encoding="utf-8")
    made = subprocess.run(["scenario_variation", "src/e.osc", "-o", "out", "--store",
                           f"sqlite:///{tmp_path / 'store.db'}"], cwd=tmp_path, capture_output=True, text=True)
    assert made.returncode == 0, made.stdout + made.stderr
    ran = subprocess.run(["scenario_execution", "e1.sce"], cwd=tmp_path / "out", capture_output=True, text=True,
                         timeout=60)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    assert "42" in ran.stdout + ran.stderr
