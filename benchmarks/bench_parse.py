"""Parse-speed benchmark: N scenarios x 20 actions, to show parse time grows linearly with file size.

Usage: ``python benchmarks/bench_parse.py [N ...]`` (default 10 100 300). Prints lines, seconds and
microseconds per line for each N (best of 3), plus the cold import+first-parse time of the parser.
"""

from __future__ import annotations

import subprocess
import sys
import time


def make_source(scenarios: int, actions: int = 20) -> str:
    """An ``.osc`` text of ``scenarios`` scenarios, each a ``serial:`` of ``actions`` log/wait members."""
    out = ["import osc.helpers", ""]
    for i in range(scenarios):
        out.append(f"scenario scenario_{i}:")
        out.append(f"    speed_{i}: speed = {i}.5mps with:")
        out.append("        keep(it in [1.0mps..5.0mps])")
        out.append("    do serial:")
        for j in range(actions):
            if j % 2:
                out.append(f"        wait elapsed({j}ms)")
            else:
                out.append(f"        log(\"scenario {i} step {j}: \" + \"done\")")
        out.append("")
    return "\n".join(out)


def main(argv: list[str]) -> None:
    sizes = [int(a) for a in argv] or [10, 100, 300]
    cold = subprocess.run(
        [sys.executable, "-c", "import time; t=time.perf_counter(); from coverage_engine.parser import parse_text;"
         "parse_text('scenario a:\\n    do log(\"x\")\\n', 'x.osc'); print(time.perf_counter()-t)"],
        capture_output=True, text=True, check=True)
    print(f"cold import + first parse: {float(cold.stdout) * 1000:.1f} ms")
    from coverage_engine.parser import parse_text

    for n in sizes:
        text = make_source(n)
        lines = text.count("\n") + 1
        best = float("inf")
        for _ in range(3):
            start = time.perf_counter()
            parse_text(text, "bench.osc")
            best = min(best, time.perf_counter() - start)
        print(f"N={n:4d}  lines={lines:6d}  parse={best:.3f} s  ({best / lines * 1e6:.1f} us/line)")


if __name__ == "__main__":
    main(sys.argv[1:])
