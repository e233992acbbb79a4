"""``scenario_variation --strategy``: covering arrays against their peers, and a large seeded sample.

Side by side, in one run:

* **pairwise, 20 parameters x 10 values**: rows and whole-process time of ours
  (``scenario_variation --strategy pairwise --list``) against covertable and allpairspy on the same
  model (goal: rows no more than the best peer, under 2 s). The peers are imported from
  ``--peers-python`` (a Python with ``covertable`` and ``allpairspy`` installed, e.g. a scratch
  virtualenv: ``python3 -m venv /tmp/peers && /tmp/peers/bin/pip install covertable allpairspy``); without
  one they are skipped with a message.
* **lhs, 10 continuous ranges, ``--samples N``** (default 100,000): time and peak RSS of ours against a
  bare loop creating the same number of files of the same size (the floor any generator writing one
  file per variant stands on; goal under 10 s, under 200 MB).

    python benchmarks/bench_variation_strategies.py [--samples 100000] [--peers-python /tmp/peers/bin/python]
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
PEERS = """
import sys, time
from covertable import make
from allpairspy import AllPairs
factors = [list(range(10)) for _ in range(20)]
start = time.perf_counter(); rows = make(factors, length=2); print("covertable", len(rows), time.perf_counter() - start)
start = time.perf_counter(); rows = list(AllPairs(factors)); print("allpairspy", len(rows), time.perf_counter() - start)
"""


def scenario(folder: Path, kind: str) -> Path:
    lines = ["import osc.helpers", "", "scenario big:"]
    for i in range(20 if kind == "pairwise" else 10):
        if kind == "pairwise":
            lines += [f"    p{i}: int = 0 with:", "        keep(it in [0..9])"]
        else:
            lines += [f"    p{i}: float = 0.0 with:", "        keep(it in [0.0..10.0])"]
    lines += ["    do serial:", "        log(p0)", ""]
    path = folder / f"{kind}.osc"
    path.write_text("\n".join(lines))
    return path


def rss_of(argv: list[str], cwd: Path) -> tuple[float, int, str]:
    start = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            env=dict(os.environ, NO_COLOR="1"))
    assert proc.stdout is not None
    out = proc.stdout.read().decode("utf-8", "replace")
    _, _, usage = os.wait4(proc.pid, 0)
    return time.perf_counter() - start, usage.ru_maxrss, out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=100_000)
    parser.add_argument("--peers-python", default="/tmp/peers/bin/python" if os.path.exists("/tmp/peers/bin/python")
                        else None)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        pairwise = scenario(folder, "pairwise")
        seconds, _, out = rss_of([str(BIN / "scenario_variation"), str(pairwise), "--strategy", "pairwise",
                                  "--seed", "1", "--list"], folder)
        ours = int(out.strip().splitlines()[-1].split()[0])
        print(f"pairwise 20x10: ours {ours} rows in {seconds:.2f} s (whole process)")
        if args.peers_python:
            done = subprocess.run([args.peers_python, "-c", PEERS], capture_output=True, text=True)
            best = None
            for line in done.stdout.splitlines():
                name, rows, peer_seconds = line.split()
                best = int(rows) if best is None else min(best, int(rows))
                print(f"pairwise 20x10: {name} {rows} rows in {float(peer_seconds):.2f} s (generation only)")
            if best:
                print(f"pairwise rows ratio ours/best peer: {ours / best:.3f} (goal <= 1.0)")
        else:
            print("pairwise peers skipped: pass --peers-python with covertable and allpairspy installed")

        lhs = scenario(folder, "lhs")
        seconds, rss, out = rss_of([str(BIN / "scenario_variation"), str(lhs), "-o", "lhs_out", "--strategy", "lhs",
                                    "--samples", str(args.samples), "--seed", "1",
                                    "--store", f"sqlite:///{folder / 'store.db'}"], folder)
        size = (folder / "lhs_out" / "lhs0.sce").stat().st_size
        print(f"lhs {args.samples} x 10 ranges: ours {seconds:.2f} s, peak RSS {rss / 1024:.0f} MB")
        floor = folder / "floor"
        floor.mkdir()
        data = b"x" * size
        start = time.perf_counter()
        for i in range(args.samples):
            fd = os.open(floor / f"f{i}.sce", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.write(fd, data)
            os.close(fd)
        bare = time.perf_counter() - start
        print(f"bare loop creating {args.samples} files of {size} bytes: {bare:.2f} s; ratio ours/bare "
              f"{seconds / bare:.2f}")


if __name__ == "__main__":
    main()
