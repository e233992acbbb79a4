"""Big inputs to ``scenario_execution -n`` (issue 21 item 8), each beside its floor in one run.

* a string literal of ``--mb`` MB (default 50): time and peak RSS of ``-n`` against a child that only
  reads the file; goal: peak RSS under 10x the input (before: 6.2 GB and 15.6 s for 50 MB);
* a parameter file of ``--documents`` documents (default 100,000): time of ``-n`` against a child that
  only loads the YAML with PyYAML's C loader; goal: under 30 s (before: about 2 ms a document).

    python benchmarks/bench_big_inputs.py [--mb 50] [--documents 100000]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent


def measure(argv: list[str], cwd: Path) -> tuple[float, float, int]:
    """Wall seconds, peak RSS (MB) and exit code of a child."""
    start = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    return time.perf_counter() - start, usage.ru_maxrss / 1024, os.waitstatus_to_exitcode(status)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mb", type=int, default=50)
    parser.add_argument("--documents", type=int, default=100_000)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        big = folder / "big.osc"
        big.write_text('import osc.helpers\nscenario s:\n    do serial:\n        log("' + "x" * (args.mb * 1_000_000)
                       + '")\n', encoding="utf-8")
        ours = measure([str(BIN / "scenario_execution"), "-n", str(big)], folder)
        floor = measure([sys.executable, "-c", f"open({str(big)!r}).read()"], folder)
        print(f"{args.mb} MB string literal: -n {ours[0]:.2f} s, peak {ours[1]:.0f} MB ({ours[1] / args.mb:.1f}x the "
              f"input; exit {ours[2]}); reading the file alone {floor[0]:.2f} s, {floor[1]:.0f} MB")

        (folder / "p.osc").write_text("import osc.helpers\nscenario s:\n    v: int = 1\n    do serial:\n        log(v)\n")
        (folder / "p.yaml").write_text("---\n".join(f"s:\n  v: {i}\n" for i in range(args.documents)))
        ours = measure([str(BIN / "scenario_execution"), "-n", "p.osc", "--scenario-parameter-file", "p.yaml"],
                       folder)
        floor = measure([sys.executable, "-c", "import yaml; list(yaml.load_all(open('p.yaml'), "
                                                "Loader=yaml.CSafeLoader))"], folder)
        print(f"{args.documents} parameter documents: -n {ours[0]:.2f} s (exit {ours[2]}, peak {ours[1]:.0f} MB); "
              f"loading the YAML alone {floor[0]:.2f} s; ratio {ours[0] / floor[0]:.1f}x (goal: under 30 s)")


if __name__ == "__main__":
    main()
