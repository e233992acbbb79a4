"""Variation + batch + merged report for 1,000 and 10,000 trivial variants, ours against the reference (issue 14).

The input is a tutorial-style file (``import osc.helpers``; a serial block of ``log() with:
keep(it.msg in [...])`` and ``emit end``), with 10 values per keep: three keeps give 1,000 variants,
four give 10,000. Ours: ``scenario_variation`` then ``scenario_batch_execution -i out -o res -j 2``
with the built-in runner (no launch command; the merged report is written at its end). The
reference: ``scenario_variation.py`` and ``scenario_batch_execution.py`` of the reference coverage
package with its own child, ``scenario_execution {SCENARIO} --output-dir {OUTPUT_DIR}`` (it runs jobs
one by one; it has no ``-j``). A full reference run of 1,000 variants would take far more than ten
minutes here, so the reference runs 8 and 32 variants of the same file shape, and its time for N is
the straight line through those two points (start-up + N x time per variant); the output says so.

Also measured: the built-in runner's per-job overhead over the scenario's own run time, with
``-j 1`` on two batch sizes (the difference cancels start-up and report) against the same variants
run one after another inside one warm process (``scenario_execution``'s ``main()``: what a job does
once its process exists).

Goals: ours <= 0.02 x the reference end to end; 10,000 variants under 60 s on 2 cores; built-in
overhead <= 10 ms per job.

The reference is not on PyPI; set it up outside the repository (as for bench_variation.py)::

    python3 -m venv /tmp/refvenv && /tmp/refvenv/bin/pip install scenario_execution==1.8.0 defusedxml
    mkdir -p /tmp/refcov && for f in scenario_variation.py scenario_batch_execution.py; do
      git -C /work/.mirror/IntelLabs+scenario_execution/repo show \\
        HEAD:scenario_execution_coverage/scenario_execution_coverage/$f > /tmp/refcov/$f; done

Usage::

    python benchmarks/bench_pipeline.py                  # 1,000 and 10,000, reference sampled
    python benchmarks/bench_pipeline.py --sizes 1000 --no-reference
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BIN = Path(sys.executable).parent
REF_PYTHON = "/tmp/refvenv/bin/python"
REF_DIR = Path("/tmp/refcov")
REF_EXEC = "/tmp/refvenv/bin/scenario_execution"


def tutorial_file(values_per_keep: list[int]) -> str:
    """A scenario with one logged keep per entry, each with that many string values."""
    lines = ["import osc.helpers", "", "scenario bench:", "    do serial:"]
    for k, size in enumerate(values_per_keep):
        values = ", ".join(f'"m{k}_{i}"' for i in range(size))
        lines += [f"        step{k}: log() with:", f"            keep(it.msg in [{values}])"]
    lines.append("        emit end")
    return "\n".join(lines) + "\n"


def shape(count: int) -> list[int]:
    """Keeps of 10 values (a last smaller one when ``count`` is not a power of ten)."""
    sizes = []
    while count >= 10:
        sizes.append(10)
        count //= 10
    if count > 1:
        sizes.append(count)
    return sizes or [1]


def folder_cost(root: Path, count: int = 300) -> float:
    """Seconds to make one empty folder under ``root`` (the mean of ``count``; nothing is deleted).

    A batch makes three files or folders per job, so the file system's cost of a new one is part of
    every figure here. It is not fixed: on ext4 without a journal (this machine's root) the kernel
    skips inode numbers freed in the last minutes, scanning past each of them, so for a few minutes
    after a large ``rm -rf`` every new file costs several times as much. Measured here: 25-35 µs per
    folder on a quiet file system, 150 µs right after deleting the results of a 10,000-job batch, and
    the same 10,000-job batch took 83.4 s instead of 77.9 s. So this benchmark deletes nothing until
    it has measured everything; a reading far above ~50 µs says the figures are not comparable with a
    quiet run.
    """
    probe = root / "folder_cost"
    probe.mkdir()
    start = time.perf_counter()
    for i in range(count):
        (probe / str(i)).mkdir()
    return (time.perf_counter() - start) / count


def timed(argv: list[str], cwd: Path, env: dict[str, str]) -> tuple[float, float]:
    """Run ``argv``; (wall seconds, CPU seconds of it and its children). Fails loudly on a bad exit."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv[:3])} … failed ({done.returncode}): {done.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def ours(work: Path, count: int, env: dict[str, str], slots: int = 2) -> dict[str, float]:
    """Our pipeline on ``count`` variants: variation, batch with the built-in runner and merged report."""
    work.mkdir(parents=True)
    (work / "bench.osc").write_text(tutorial_file(shape(count)))
    store = f"sqlite:///{work / 'store.db'}"
    variation = timed([str(BIN / "scenario_variation"), "bench.osc", "-o", "out", "--store", store], work, env)
    batch = timed([str(BIN / "scenario_batch_execution"), "-i", "out", "-o", "res", "-j", str(slots),
                   "--store", store], work, env)
    made = sum(1 for p in (work / "res").iterdir() if p.is_dir())
    assert made == count, f"{made} job folders for {count} variants"
    return {"variation": variation[0], "batch": batch[0], "cpu": variation[1] + batch[1]}


def reference(work: Path, count: int, env: dict[str, str]) -> dict[str, float]:
    """The reference pipeline on ``count`` variants (its batch runs one job at a time)."""
    work.mkdir(parents=True)
    (work / "bench.osc").write_text(tutorial_file(shape(count)))
    variation = timed([REF_PYTHON, str(REF_DIR / "scenario_variation.py"), "bench.osc", "-o", "out"], work, env)
    batch = timed([REF_PYTHON, str(REF_DIR / "scenario_batch_execution.py"), "-i", "out", "-o", "res", "--",
                   REF_EXEC, "{SCENARIO}", "--output-dir", "{OUTPUT_DIR}"], work, env)
    assert (work / "res" / "test.xml").exists()
    return {"variation": variation[0], "batch": batch[0]}


IN_PROCESS = r'''
import os, sys, time, glob
from importlib.metadata import entry_points
main = [ep for ep in entry_points(group="console_scripts") if ep.name == "scenario_execution"][0].load()
files = sorted(glob.glob(os.path.join(sys.argv[1], "*.sce")))
def run(path, out):
    sys.argv = ["scenario_execution", path, "--output-dir", out]
    try:
        main()
    except SystemExit:
        pass
null = os.open(os.devnull, os.O_WRONLY)
saved = os.dup(1)
os.dup2(null, 1)
for path in files[:5]:
    run(path, os.path.join(sys.argv[2], "warm", os.path.basename(path)))
start = time.perf_counter()
for path in files:
    run(path, os.path.join(sys.argv[2], os.path.basename(path)))
took = time.perf_counter() - start
os.dup2(saved, 1)
print(took / len(files))
'''


def overhead(work: Path, env: dict[str, str], small: int = 100, large: int = 400) -> dict[str, float]:
    """Per-job cost of the built-in runner with -j 1 minus the scenario's own cost (warm, in one process)."""
    walls = {}
    for count in (small, large):
        walls[count] = ours(work / f"j1_{count}", count, env, slots=1)["batch"]
    per_job = (walls[large] - walls[small]) / (large - small)
    done = subprocess.run([sys.executable, "-c", IN_PROCESS, str(work / f"j1_{large}" / "out"),
                           str(work / "inproc")], cwd=work, env=env, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"in-process run failed: {done.stderr[-2000:]}")
    own = float(done.stdout.strip().splitlines()[-1])
    return {"per_job": per_job, "own": own}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", default="1000,10000", help="variant counts (comma separated)")
    parser.add_argument("--no-reference", action="store_true", help="ours only")
    parser.add_argument("--no-overhead", action="store_true", help="skip the -j 1 overhead measurement")
    args = parser.parse_args()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "SCENARIO_STORE")}
    env["NO_COLOR"] = "1"
    sizes = [int(s) for s in args.sizes.split(",")]
    have_reference = not args.no_reference and Path(REF_PYTHON).exists() and (REF_DIR / "scenario_variation.py").exists()
    print(f"{os.cpu_count()} CPUs; load average {os.getloadavg()[0]:.2f} at start")
    with tempfile.TemporaryDirectory(prefix="bench_pipeline_") as tmp:
        root = Path(tmp)
        print(f"making a folder here takes {folder_cost(root) * 1e6:.0f} µs (see folder_cost)")
        line = None
        if have_reference:
            small, large = (reference(root / f"ref{n}", n, env) for n in (8, 32))
            slope = {k: (large[k] - small[k]) / 24 for k in ("variation", "batch")}
            start = {k: small[k] - 8 * slope[k] for k in ("variation", "batch")}
            line = (start, slope)
            print(f"reference, measured: 8 variants {small['variation']:.2f} + {small['batch']:.2f} s, "
                  f"32 variants {large['variation']:.2f} + {large['batch']:.2f} s (variation + batch); "
                  f"per variant {slope['variation'] * 1000:.0f} + {slope['batch'] * 1000:.0f} ms")
        failures = 0
        for count in sizes:
            figures = ours(root / f"ours{count}", count, env)
            total = figures["variation"] + figures["batch"]
            text = (f"{count:>6} variants  ours: variation {figures['variation']:6.2f} s + batch and report "
                    f"{figures['batch']:6.2f} s = {total:6.2f} s (CPU {figures['cpu']:.1f} s)")
            if line is not None:
                start, slope = line
                ref = sum(start[k] + count * slope[k] for k in ("variation", "batch"))
                ratio = total / ref
                text += f" | reference (extrapolated) {ref:8.0f} s | ratio {ratio:.4f} (goal <= 0.02)"
                failures += ratio > 0.02
            if count >= 10000:
                text += f" | goal < 60 s: {'met' if total < 60 else 'MISSED'}"
                failures += total >= 60
            print(text, flush=True)
        if not args.no_overhead:
            cost = overhead(root / "overhead", env)
            extra = (cost["per_job"] - cost["own"]) * 1000
            print(f"built-in runner, -j 1: {cost['per_job'] * 1000:.1f} ms per job, the scenario's own run "
                  f"{cost['own'] * 1000:.1f} ms -> overhead {extra:.1f} ms per job (goal <= 10)")
            failures += extra > 10
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
