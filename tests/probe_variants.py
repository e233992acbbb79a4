"""Variants whose jobs say where they ran: the probe scenario of the built-in runner's tests.

Its external method (``probe_mod.record``) lives in the scenario's folder and records, per call, the
job's name, the process it ran in, its parent, the process that imported the module, how often the
module was called in that process, and whether a global that an earlier job changed is still changed,
in the ledger ``$BATCH_LEDGER`` names. So a test sees where user code ran (a fresh child per job, forked
by which process) and whether one job's state reached the next.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from batch_fixtures import cli_env

BIN = Path(sys.executable).parent

PROBE_MODULE = '''
import os, signal, sys, time
CALLS = []
IMPORTED_IN = os.getpid()

def record(name, pause):
    CALLS.append(name)
    time.sleep(pause)
    import coverage_engine.results.run_report as junit
    leaked = getattr(junit, "LEAKED_BY", "-")
    junit.LEAKED_BY = name                      # global state a later job must never see
    line = "%s %d %d %d %d %s\\n" % (name, os.getpid(), os.getppid(), IMPORTED_IN, len(CALLS), leaked)
    fd = os.open(os.environ["BATCH_LEDGER"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    os.write(fd, line.encode())
    os.close(fd)
    if name == "crash":
        os.kill(os.getpid(), signal.SIGSEGV)
    if name == "hang":
        time.sleep(60)
    return name
'''


def scenario(names: list[str], pause: float) -> str:
    listed = ", ".join(f'"{n}"' for n in names)
    return f"""import osc.helpers

struct probe:
    def record(name: string, pause: float) -> string is external probe_mod.record()

scenario job:
    name: string = "x"
    keep(name in [{listed}])
    cover(name)
    do serial:
        log(probe.record(name, {pause}))
        check: compare(left_value: name, operator: "!=", right_value: "fail")
"""


def make_variants(root: Path, names: list[str], pause: float = 0.0) -> dict[str, str]:
    """Variants ``job0…`` of the probe scenario in ``root/out``; returns the cli environment."""
    (root / "src").mkdir(parents=True)
    (root / "src" / "probe_mod.py").write_text(PROBE_MODULE)
    (root / "src" / "job.osc").write_text(scenario(names, pause))
    env = cli_env(root)
    made = subprocess.run([str(BIN / "scenario_variation"), "src/job.osc", "-o", "out"], cwd=root, env=env,
                          capture_output=True, text=True)
    assert made.returncode == 0, made.stdout + made.stderr
    return env


def records(root: Path) -> list[list[str]]:
    path = root / "ledger.txt"
    return [line.split() for line in path.read_text().splitlines()] if path.exists() else []
