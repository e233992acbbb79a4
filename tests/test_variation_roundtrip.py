"""Round trip: every generated .sce logs exactly what the .osc logs with those values written in by hand."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

ABSTRACT = """import osc.helpers

struct pt:
    x: float
    y: float = 0.5

scenario roundtrip:
    speed: float
    keep(speed in [1.5, 2.5])
    p: pt with:
        keep(it.x in [1.0, 2.0])
    do serial:
        log() with:
            keep(it.msg in ['first', 'second'])
        log(speed)
        log(p)
"""

BY_HAND = """import osc.helpers

struct pt:
    x: float
    y: float = 0.5

scenario roundtrip:
    speed: float = {speed}
    p: pt = pt(x: {x})
    do serial:
        log({msg!r})
        log(speed)
        log(p)
"""


def _tool(name: str, *args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT), NO_COLOR="1")
    return subprocess.run([sys.executable, "-m", f"cli.{name}", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=60)


def _logged(result: subprocess.CompletedProcess) -> list[str]:
    return [line for line in (result.stdout + result.stderr).splitlines() if "[log]" in line]


def test_each_variant_logs_like_the_hand_written_file(tmp_path):
    (tmp_path / "rt.osc").write_text(ABSTRACT)
    generated = _tool("scenario_variation", "rt.osc", "-o", "variants", cwd=tmp_path)
    assert generated.returncode == 0, generated.stdout + generated.stderr
    values = itertools.product([1.5, 2.5], [1.0, 2.0], ["first", "second"])  # first keep slowest
    for index, (speed, x, msg) in enumerate(values):
        hand = tmp_path / f"hand{index}.osc"
        hand.write_text(BY_HAND.format(speed=speed, x=x, msg=msg))
        expected = _tool("scenario_execution", hand.name, "-o", f"r_hand{index}", cwd=tmp_path)
        actual = _tool("scenario_execution", f"variants/rt{index}.sce", "-o", f"r_sce{index}", cwd=tmp_path)
        assert expected.returncode == 0 and actual.returncode == 0, actual.stdout + actual.stderr
        assert _logged(actual) == _logged(expected) and len(_logged(actual)) == 3
        assert _logged(actual)[0].endswith(msg)
