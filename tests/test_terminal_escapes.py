"""Names and values from files never send raw escapes to a terminal, a pipe or a file (issue 32 item 5).

A clear-screen (CSI 2J), a colour (CSI 31m) and an OSC 52 clipboard write are put into a coverage
item's name and values, a run's reason, a scenario file's name and a source line; every command shows
them escaped (``\\x1b``).
"""

from __future__ import annotations

import json
import shutil

from coverage_support import BIN, coverage, run

CLEAR, RED, CLIPBOARD = "\x1b[2J", "\x1b[31m", "\x1b]52;c;cHduZWQ=\x07"


def _hostile_run_folder(root):
    from coverage_engine.coverage.run_file import RunCoverageBuilder, write_run_coverage

    (root / "one.osc").write_text('import osc.helpers\nscenario one:\n    do serial:\n        log("hi")\n',
                                  encoding="utf-8")
    ran = run(str(BIN / "scenario_execution"), "one.osc", "-o", "r1", cwd=root)
    assert ran.returncode == 0, ran.stdout + ran.stderr
    builder = RunCoverageBuilder("one", variant=f"v{RED}1")
    builder.cover(f"mode{CLEAR}", path="one", value_type="string").add(f"fast{CLIPBOARD}")
    builder.record(f"[bold]ttc{RED}", path="one", value_type="string").add(f"x{CLEAR}")
    write_run_coverage(root / "r1", builder.build("failed", reason=f"bad{CLIPBOARD}"))


def test_the_coverage_report_escapes_every_name_and_value(tmp_path):
    _hostile_run_folder(tmp_path)
    done = coverage("report", "r1", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "\x1b" not in done.stdout and "\x07" not in done.stdout
    assert "mode\\x1b[2J" in done.stdout and "[bold]ttc\\x1b[31m" in done.stdout
    written = coverage("report", "r1", "-o", "report.txt", cwd=tmp_path)
    assert written.returncode == 0, written.stderr
    text = (tmp_path / "report.txt").read_text(encoding="utf-8")
    assert "\x1b" not in text and "mode\\x1b[2J" in text
    doc = json.loads(coverage("json", "r1", cwd=tmp_path).stdout)       # JSON keeps the value (escaped by JSON)
    assert any(item["name"] == f"one.mode{CLEAR}" for item in doc["items"])


def test_scenario_execution_errors_escape_the_file_name_and_the_source_line(tmp_path):
    name = f"bad{CLEAR}.osc"
    (tmp_path / name).write_text(f'import osc.helpers\nscenario s:\n    do serial:\n        log("{RED}" +)\n',
                                 encoding="utf-8")
    done = run(str(BIN / "scenario_execution"), name, "-o", "out", cwd=tmp_path, check=False)
    assert done.returncode == 1
    assert "\x1b" not in done.stdout + done.stderr
    assert "bad\\x1b[2J.osc:4:" in done.stderr and 'log("\\x1b[31m" +)' in done.stderr


def test_a_huge_line_is_shown_clipped_around_the_column(tmp_path):
    (tmp_path / "long.osc").write_text("scenario s:\n    do serial:\n        log(\"" + "x" * 400_000 + "\" +)\n",
                                       encoding="utf-8")
    done = run(str(BIN / "scenario_execution"), "long.osc", "-o", "out", cwd=tmp_path, check=False)
    assert done.returncode == 1 and "long.osc:3:" in done.stderr
    assert max(len(line) for line in done.stderr.splitlines()) < 400, done.stderr[:2000]
    source, caret = done.stderr.splitlines()[1:3]
    assert source[caret.index("^")] == ")"


def test_scenario_variation_escapes_what_it_wrote(tmp_path):
    source = tmp_path / f"cut{RED}.osc"
    shutil.copy(__file__.replace("test_terminal_escapes.py", "coverage_child.py"), tmp_path / "unused.py")
    source.write_text("import osc.helpers\nscenario cut:\n    speed: float = 1.0\n    keep(speed in [1.0, 2.0])\n"
                      "    do serial:\n        log(speed)\n", encoding="utf-8")
    done = run(str(BIN / "scenario_variation"), source.name, "-o", f"out{CLEAR}", "-d", "--store",
               f"sqlite:///{tmp_path / 's.db'}", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "\x1b" not in done.stdout + done.stderr
    assert "wrote out\\x1b[2J/cut\\x1b[31m1.sce" in done.stdout.replace("\\\\", "\\")
