"""Issue 32 items 4 and 8: inputs that used to grow without bound, timed with a memory and time cap.

Each probe runs a real command under ``prlimit --as`` and ``timeout`` and prints its wall time, peak
memory (``/usr/bin/time``) and exit code:

* a file of N scenarios, run (``scenario_execution -o``) and dry-run (``-n``), N = 5,000 / 20,000 / 80,000
  (``--million`` adds 1,000,000, dry run only);
* pairwise over 10 dimensions of 50 values (``scenario_variation --list``);
* t-way 3 over 40 dimensions of 50 values;
* a parameter file of 50,000 aliases of one 4 MB string (``scenario_variation``).

``--baseline DIR`` runs the same probes with the code of DIR first on ``PYTHONPATH`` (an exported
tree of an earlier commit: ``git archive b6b4d4d | tar -x -C /tmp/base``), side by side.

    python benchmarks/bench_input_scale.py [--baseline /tmp/base] [--timeout 300] [--million]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MEMORY = "4000000000"


def scenarios_file(folder: Path, count: int) -> Path:
    path = folder / f"many{count}.osc"
    with open(path, "w", encoding="utf-8") as handle:
        handle.write("import osc.helpers\n")
        for index in range(count):
            handle.write(f'scenario s{index}:\n    do serial:\n        log("x")\n')
    return path


def wide_file(folder: Path, dimensions: int, values: int) -> Path:
    path = folder / f"wide{dimensions}x{values}.osc"
    lines = ["import osc.helpers", "scenario big:"]
    lines += [f"    p{i}: int = 0" for i in range(dimensions)]
    lines += [f"    keep(p{i} in [{', '.join(str(v) for v in range(values))}])" for i in range(dimensions)]
    path.write_text("\n".join([*lines, "    do serial:", "        log(p0)"]) + "\n", encoding="utf-8")
    return path


def bytes_bomb(folder: Path) -> Path:
    path = folder / "bytes.yaml"
    path.write_text("big: &big " + "x" * (4 * 1024 * 1024) + "\nmany: [" + ", ".join(["*big"] * 50_000) + "]\n")
    return path


def probe(label: str, module: str, args: list[str], cwd: Path, code: Path, timeout: int) -> None:
    env = dict(os.environ, PYTHONPATH=str(code), NO_COLOR="1")
    command = ["/usr/bin/time", "-f", "%e %M", "prlimit", f"--as={MEMORY}", "timeout", str(timeout),
               sys.executable, "-m", module, *args]
    done = subprocess.run(command, cwd=cwd, env=env, capture_output=True, text=True)
    seconds, kib = done.stderr.strip().splitlines()[-1].split()
    said = next((line for line in done.stderr.splitlines() if "error" in line), "")[:110]
    state = "timed out" if done.returncode == 124 else f"exit {done.returncode}"
    print(f"{label:<34} {float(seconds):8.1f} s {int(kib) / 1024:8.0f} MiB  {state:<10} {said}", flush=True)


def run_all(code: Path, folder: Path, timeout: int, million: bool) -> None:
    store = f"sqlite:///{folder / 'store.db'}"
    for count in (5_000, 20_000, 80_000, *((1_000_000,) if million else ())):
        path = scenarios_file(folder, count)
        if count < 1_000_000:
            probe(f"{count:,} scenarios, run", "cli.scenario_execution", [str(path), "-o", f"out{count}"],
                  folder, code, timeout)
        probe(f"{count:,} scenarios, dry run", "cli.scenario_execution", ["-n", str(path)], folder, code, timeout)
    variation = ["--seed", "1", "--store", store, "-o", "variants"]
    probe("pairwise 10 x 50 (--list)", "cli.scenario_variation",
          [str(wide_file(folder, 10, 50)), "--strategy", "pairwise", "--list", *variation], folder, code, timeout)
    probe("t-way 3 over 40 x 50", "cli.scenario_variation",
          [str(wide_file(folder, 40, 50)), "--strategy", "t-way", "--strength", "3", *variation], folder, code,
          timeout)
    probe("alias bomb of bytes (50,000 x 4 MB)", "cli.scenario_variation",
          [str(ROOT / "examples" / "hello_world" / "hello_world.osc"), "--scenario-parameter-file",
           str(bytes_bomb(folder)), *variation], folder, code, timeout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", type=Path, help="a tree of the earlier code to run side by side")
    parser.add_argument("--timeout", type=int, default=300)
    parser.add_argument("--million", action="store_true", help="also a dry run of 1,000,000 scenarios")
    options = parser.parse_args()
    for name, code in (("this tree", ROOT), *((("baseline", options.baseline),) if options.baseline else ())):
        print(f"--- {name}: {code} (prlimit --as={MEMORY}, timeout {options.timeout} s)", flush=True)
        with tempfile.TemporaryDirectory() as folder:
            run_all(code, Path(folder), options.timeout, options.million)


if __name__ == "__main__":
    main()
