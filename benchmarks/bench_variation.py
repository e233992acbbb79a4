"""Benchmark ``scenario_variation`` against the reference coverage tool (issue 4 speed goals).

Runs both tools as child processes on the same generated scenarios and prints wall time, peak RSS
of the child (``os.wait4`` rusage) and the ratio:

* a three-keep scenario (self-contained, no library import) with 512 (8x8x8) and 4096 (16x16x16)
  variants: goal ours <= 0.05 x reference;
* 100,000 variants (100x100x10): goal < 10 s and peak RSS < 150 MB (ours only: the reference would
  take about an hour);
* 512 variants of a three-keep scenario with ``import osc.helpers``: goal < 1 s (the reference takes
  about 166 ms per variant; it is run on ``--helpers-reference-variants`` variants and scaled
  linearly unless ``--full-reference``);
* the size of one ``.sce`` of the ``osc.helpers`` scenario: goal <= 2 KB.

The reference is ``scenario_variation`` of IntelLabs/scenario_execution (``scenario_execution_coverage``,
tag 1.3.0) run with the reference ``scenario_execution`` 1.8.0, given as a command with
``--reference "PYTHON SCRIPT"`` (default: ``/tmp/refvenv/bin/python /tmp/refcov/scenario_variation.py``
when both exist). Without it, the fixed figures from the issue are used as the baseline.

Usage::

    python benchmarks/bench_variation.py                 # everything
    python benchmarks/bench_variation.py --quick         # 512-variant cases only
"""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

#: Figures from issue 4, used when the reference cannot be run here: seconds, peak MB.
ISSUE_FIGURES = {"three_keep_512": (2.3, 273.0), "three_keep_4096": (21.7, 273.0), "helpers_512": (85.0, 560.0)}
ISSUE_SCE_SIZE = 58 * 1024
DEFAULT_REFERENCE = ("/tmp/refvenv/bin/python", "/tmp/refcov/scenario_variation.py")


def scenario_text(sizes: tuple[int, int, int], helpers: bool) -> str:
    """A scenario with three keeps of ``sizes`` string values each."""
    head = "import osc.helpers\n" if helpers else "action log:\n    msg: string\n"
    keeps = []
    for k, size in enumerate(sizes):
        values = ", ".join(f"'{'abc'[k]}{i}'" for i in range(size))
        keeps.append(f"        log() with:\n            keep(it.msg in [{values}])\n")
    return f"{head}\nscenario test:\n    do serial:\n" + "".join(keeps)


def run_child(argv: list[str], cwd: Path) -> tuple[float, float, int, str]:
    """Run ``argv``; returns (seconds, peak RSS in MB, exit code, output tail); prints its CPU time.

    Wall time is what the goals are about; CPU time (user + system) is printed too because it is far
    less sensitive to other load on the machine.
    """
    started = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    output = proc.stdout.read()
    _pid, status, usage = os.wait4(proc.pid, 0)
    elapsed = time.perf_counter() - started
    proc.returncode = os.waitstatus_to_exitcode(status)
    rss_mb = usage.ru_maxrss / 1024 if sys.platform != "darwin" else usage.ru_maxrss / 2**20
    print(f"  {Path(argv[1]).name if len(argv) > 1 else argv[0]} {Path(argv[-3]).name}: wall {elapsed:.3f} s, "
          f"cpu {usage.ru_utime + usage.ru_stime:.3f} s", file=sys.stderr)
    return elapsed, rss_mb, proc.returncode, output.decode(errors="replace")[-600:]


def ours_argv(osc: Path, out: Path, store: Path) -> list[str]:
    exe = shutil.which("scenario_variation")
    base = [exe] if exe else [sys.executable, "-m", "cli.scenario_variation"]
    return [*base, str(osc), "-o", str(out), "--store", f"sqlite:///{store}"]


def sce_size(out: Path) -> int:
    files = sorted(out.glob("*.sce"))
    return files[0].stat().st_size if files else 0


def row(name: str, ours: tuple, base: tuple | None, base_label: str, goal: str) -> None:
    t, rss = ours[0], ours[1]
    if base is None:
        print(f"{name:<18} ours {t:8.3f} s {rss:7.1f} MB | {'-':>24} | {goal}")
        return
    bt, brss = base
    ratio = t / bt if bt else float("nan")
    print(f"{name:<18} ours {t:8.3f} s {rss:7.1f} MB | {base_label} {bt:8.2f} s {brss:7.1f} MB"
          f" | ratio {ratio:.4f} | {goal}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--reference", help="command running the reference scenario_variation (python + script)")
    parser.add_argument("--no-reference", action="store_true", help="use the issue's fixed figures")
    parser.add_argument("--quick", action="store_true", help="only the 512-variant cases")
    parser.add_argument("--full-reference", action="store_true",
                        help="run the reference on all 512 osc.helpers variants (about 90 s)")
    parser.add_argument("--helpers-reference-variants", type=int, default=64,
                        help="variants of the osc.helpers case the reference runs when not --full-reference")
    args = parser.parse_args()

    reference: list[str] | None = None
    if not args.no_reference:
        if args.reference:
            reference = shlex.split(args.reference)
        elif all(Path(p).exists() for p in DEFAULT_REFERENCE):
            reference = list(DEFAULT_REFERENCE)
    print(f"baseline: {'reference ' + ' '.join(reference) if reference else 'fixed figures of issue 4'}")

    cases = [("three_keep_512", (8, 8, 8), False), ("helpers_512", (8, 8, 8), True)]
    if not args.quick:
        cases += [("three_keep_4096", (16, 16, 16), False), ("variants_100k", (100, 100, 10), False)]
    failures = 0
    with tempfile.TemporaryDirectory(prefix="bench_variation_") as tmp:
        root = Path(tmp)
        for name, sizes, helpers in cases:
            work = root / name
            work.mkdir()
            osc = work / "bench.osc"
            osc.write_text(scenario_text(sizes, helpers))
            ours = run_child(ours_argv(osc, work / "ours", work / "store.db"), work)
            if ours[2] != 0:
                print(f"{name}: ours failed (rc {ours[2]}):\n{ours[3]}")
                failures += 1
                continue
            count = len(list((work / "ours").glob("*.sce")))
            base, label = None, "reference"
            if name == "variants_100k":
                goal_ok = ours[0] < 10 and ours[1] < 150
                goal = f"goal < 10 s, < 150 MB: {'met' if goal_ok else 'MISSED'} ({count} files)"
            else:
                if reference is not None:
                    ref_osc = osc
                    scale = 1.0
                    if helpers and not args.full_reference:
                        small = max(2, round(args.helpers_reference_variants ** (1 / 3)))
                        ref_osc = work / "bench_small.osc"
                        ref_osc.write_text(scenario_text((small, small, small), helpers))
                        scale = 512 / small ** 3
                        label = f"ref x{scale:.0f}"
                    bt, brss, brc, btail = run_child([*reference, str(ref_osc), "-o", str(work / "ref")], work)
                    if brc != 0:
                        print(f"{name}: reference failed (rc {brc}):\n{btail}")
                    else:
                        base = (bt * scale, brss)
                if base is None:
                    base, label = ISSUE_FIGURES[name], "issue    "
                if helpers:
                    goal_ok = ours[0] < 1.0
                    goal = f"goal < 1 s: {'met' if goal_ok else 'MISSED'}"
                else:
                    goal_ok = ours[0] <= 0.05 * base[0]
                    goal = f"goal <= 0.05x: {'met' if goal_ok else 'MISSED'}"
            row(name, ours, base, label, goal)
            failures += 0 if goal_ok else 1
            if helpers:
                size = sce_size(work / "ours")
                ref_size = sce_size(work / "ref") if (work / "ref").is_dir() else 0
                ref_text = f"reference {ref_size} bytes" if ref_size else f"issue {ISSUE_SCE_SIZE} bytes"
                ok = size <= 2048
                print(f"{'sce_size':<18} ours {size} bytes | {ref_text} | goal <= 2048: {'met' if ok else 'MISSED'}")
                failures += 0 if ok else 1
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
