"""Parser-only speed: parse time of generated files of N scenarios x 20 actions, and cold start.

``python benchmarks/bench_parser_only.py [N ...]`` (default 10 100 300). Prints lines, best-of-3 wall
and CPU seconds, and microseconds per line, so linear growth is visible; then the cost of a fresh
process importing the parser and parsing osc.types + osc.helpers. (Whole-process figures against the
reference are in ``bench_dry_run.py``.)
"""

from __future__ import annotations

import subprocess
import sys
import time


def make_source(scenarios: int, actions: int = 20) -> str:
    """``scenarios`` scenarios, each with a constrained parameter and a serial of ``actions`` members."""
    out = ["import osc.helpers", ""]
    for i in range(scenarios):
        out += [f"scenario scenario_{i}:", f"    speed_{i}: speed = {i}.5mps with:",
                "        keep(it in [1.0mps..5.0mps])", "    do serial:"]
        for j in range(actions):
            out.append(f"        wait elapsed({j}ms)" if j % 2 else f"        log(\"scenario {i} step {j}: \" + \"done\")")
        out.append("")
    return "\n".join(out)


COLD = ("import time; t = time.perf_counter(); from coverage_engine.parse.parser import parse_file;"
        "from coverage_engine.resolve.libraries import find_library;"
        "[parse_file(find_library(n)) for n in ('osc.types', 'osc.helpers')];"
        "print(time.perf_counter() - t)")


def main(argv: list[str]) -> None:
    from coverage_engine.parse.parser import parse_text

    for n in [int(a) for a in argv] or [10, 100, 300]:
        text = make_source(n)
        lines = text.count("\n") + 1
        parse_text(text, "warm.osc")
        wall = cpu = float("inf")
        for _ in range(3):
            w, c = time.perf_counter(), time.process_time()
            parse_text(text, "bench.osc")
            wall, cpu = min(wall, time.perf_counter() - w), min(cpu, time.process_time() - c)
        print(f"N={n:4d} lines={lines:6d} wall={wall:.3f}s cpu={cpu:.3f}s ({cpu / lines * 1e6:.1f} us/line)")
    runs = sorted(float(subprocess.run([sys.executable, "-c", COLD], capture_output=True, text=True,
                                       check=True).stdout) for _ in range(5))
    print(f"fresh process: import parser + parse osc.types and osc.helpers: median {runs[2] * 1000:.1f} ms")


if __name__ == "__main__":
    main(sys.argv[1:])
