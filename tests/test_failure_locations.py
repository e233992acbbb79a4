"""Every failure names where it happened (issue 31 item 7): ``file:line:col`` in each JUnit failure message,
and for a variant the line of the ``.osc`` the user wrote before the ``.sce`` line that ran
(``emit fail at gap.osc:11:9 (out/gap3.sce:26:9)``); through the real CLIs, read from the files they write."""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent

#: A method the ``external`` failure calls.
MODULE = "def boom():\n    raise RuntimeError('kaputt')\n"

HEAD = "import osc.helpers\n\nstruct lib:\n    def boom() -> int is external m.boom()\n\nscenario s:\n"

#: The failing line (line 9 of the file, column 9), and the message that names it.
FAILURES = {
    "emit fail": ("emit fail", "emit fail at {at}"),
    "failing action": ('run_process("false")', "'run_process' at {at} failed: 'false' failed with exit code 1"),
    "false check": ('compare(1, ">", 2)', "'compare' at {at} failed: 1 > 2 is False"),
    "external method": ("log(lib.boom())", "{at4}: external method 'lib.boom' (m.boom) failed: RuntimeError: kaputt"),
    "unknown action": ("no_such_action()", "{at}: error: unknown action 'no_such_action'"),
    "unknown name": ("log(nosuch)", "{at4}: error: unknown name 'nosuch'"),
}


def run(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, NO_COLOR="1", PYTHONPATH=str(cwd))
    env.pop("SCENARIO_STORE", None)
    return subprocess.run([str(BIN / args[0]), *args[1:]], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=120)


def failure_messages(report: Path) -> dict[str, str]:
    return {case.get("name"): next(iter(case)).get("message")
            for case in ET.parse(report).iter("testcase") if len(case)}


@pytest.mark.parametrize("kind", FAILURES)
def test_a_failure_in_an_osc_file_names_its_file_line_and_column(tmp_path, kind):
    line, message = FAILURES[kind]
    (tmp_path / "m.py").write_text(MODULE)
    (tmp_path / "bad.osc").write_text(HEAD + "    do serial:\n        log('a')\n        " + line + "\n")
    done = run(tmp_path, "scenario_execution", "bad.osc", "-o", "r")
    assert done.returncode == 1 and "Traceback" not in done.stdout + done.stderr
    assert list(failure_messages(tmp_path / "r" / "test.xml").values()) == \
        [message.format(at="bad.osc:9:9", at4="bad.osc:9:13")]


VARIED = """import osc.helpers

scenario gap:
    gap: length with:
        keep(it in [1m, 2m,
                    3m, 4m])
    lane: int with:
        keep(it in [1, 2])
    do serial:
        log("start")
        emit fail
"""


def test_a_failing_variant_names_the_osc_line_and_the_sce_line(tmp_path):
    (tmp_path / "gap.osc").write_text(VARIED)
    assert run(tmp_path, "scenario_variation", "gap.osc").returncode == 0
    sce = (tmp_path / "out" / "gap3.sce").read_text().splitlines()
    assert sce[25].strip() == "emit fail"                      # line 26 of the .sce (2 domain lines in its header), line 11 of the .osc
    done = run(tmp_path, "scenario_execution", "out/gap3.sce", "-o", "r")
    assert done.returncode == 1
    assert list(failure_messages(tmp_path / "r" / "test.xml").values()) == ["emit fail at gap.osc:11:9 "
                                                                           "(out/gap3.sce:26:9)"]
    assert "Scenario 'gap' failed: emit fail at gap.osc:11:9 (out/gap3.sce:26:9)" in done.stdout


def test_a_variant_that_does_not_load_names_both_lines(tmp_path):
    (tmp_path / "gap.osc").write_text(VARIED)
    assert run(tmp_path, "scenario_variation", "gap.osc").returncode == 0
    sce = tmp_path / "out" / "gap3.sce"
    sce.write_text(sce.read_text().replace('log("start")', "log(nosuch)"))
    done = run(tmp_path, "scenario_execution", "out/gap3.sce", "-o", "r")
    assert done.returncode == 1
    assert list(failure_messages(tmp_path / "r" / "test.xml").values()) == \
        ["gap.osc:10:13 (out/gap3.sce:25:13): error: unknown name 'nosuch'"]


def test_the_batch_report_and_summary_name_both_lines_of_each_failing_variant(tmp_path):
    (tmp_path / "gap.osc").write_text(VARIED)
    assert run(tmp_path, "scenario_variation", "gap.osc").returncode == 0
    done = run(tmp_path, "scenario_batch_execution", "-i", "out", "-o", "results")
    assert done.returncode == 1
    messages = failure_messages(tmp_path / "results" / "test.xml")
    assert len(messages) == 8
    for index in range(8):
        name = next(n for n in messages if n.startswith(f"gap{index}["))
        assert messages[name] == f"emit fail at {tmp_path / 'gap.osc'}:11:9 ({tmp_path / 'out' / f'gap{index}.sce'}:26:9)"
    assert f"emit fail at {tmp_path / 'gap.osc'}:11:9 ({tmp_path / 'out' / 'gap3.sce'}:26:9)" in done.stdout
