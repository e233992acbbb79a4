"""Fuzz the front end: N mutated inputs, counted by outcome (issue 11 item 4).

Inputs are mutations (token deletions, duplications, swaps, random bytes, truncation) of the standard
library and example ``.osc`` files, of parameter-file YAML and of ``.sce`` texts. Each is run in
process through what the commands run (parse + resolve; the parameter-file reader; the ``.sce``
reader) under a time limit per input. Counted:

* ``ok`` — accepted; ``located`` — one of our errors with file:line:col; ``unlocated`` — one of our
  errors without a position (fine for a whole-file problem, listed to look at);
* ``traceback`` — any other exception (a bug); ``hang`` — over the time limit (a bug);
* distinct failure messages (first line, numbers masked) per kind, the most common printed.

    python benchmarks/fuzz_front_end.py [-n 100000] [--seed 1] [--limit-s 2]
"""

from __future__ import annotations

import argparse
import collections
import random
import re
import signal
import sys
import tempfile
import time
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

TOKEN = re.compile(r"\s+|\w+|[^\w\s]")
PARAMETERS = ["s:\n  v: 2\n", "s:\n  v: 2\n---\ns:\n  v: [1, 2]\n", "a: &x {v: 1}\nb: *x\n", "s: {_output_dir: out}\n"]


class Hang(Exception):
    pass


def _alarm(_signum, _frame):
    raise Hang()


def mutate(text: str, rng: random.Random) -> str:
    tokens = TOKEN.findall(text) or [""]
    for _ in range(rng.randint(1, 4)):
        kind = rng.randrange(6)
        i = rng.randrange(len(tokens))
        if kind == 0:
            del tokens[i:i + rng.randint(1, 3)]
        elif kind == 1:
            tokens.insert(i, tokens[rng.randrange(len(tokens))] if tokens else "x")
        elif kind == 2 and len(tokens) > 1:
            j = rng.randrange(len(tokens))
            tokens[i], tokens[j] = tokens[j], tokens[i]
        elif kind == 3:
            tokens.insert(i, rng.choice(["(", ")", "[", "]", ":", "\n", "    ", "\t", "..", "@", "!", "#", "'", "\"",
                                         "keep(", "cover(", "\x00", "\ufeff", "1e999", "-", "[1..2]"]))
        elif kind == 4:
            tokens = tokens[:i] or [""]
        elif tokens:
            tokens[i] = "".join(chr(rng.randrange(32, 0x2FF)) for _ in range(rng.randint(1, 3)))
        if not tokens:
            tokens = [""]
    return "".join(tokens)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--limit-s", type=float, default=2.0)
    args = parser.parse_args()

    from coverage_engine.errors import OscError
    from coverage_engine.files.parameters import read_parameter_documents
    from coverage_engine.files.sce import parse_sce
    from coverage_engine.parse.parser import parse_text
    from coverage_engine.resolve.resolver import resolve

    sources = [p.read_text(encoding="utf-8") for p in sorted((ROOT / "coverage_engine" / "osc").glob("*.osc"))]
    sources += [p.read_text(encoding="utf-8") for p in sorted((ROOT / "examples").rglob("*.osc"))
                if "build" not in p.parts]
    from coverage_engine.files.sce_writer import render_sce

    model = "import osc.helpers\nscenario s:\n    do serial:\n        log('x')\n"
    sce_texts = [render_sce("s.osc", "0" * 64, ".", "s", i, {"s.log.msg": value}, {}, model)
                 for i, value in enumerate(["a", 2.5, "x\u0085y"])]
    rng = random.Random(args.seed)
    counts: collections.Counter[str] = collections.Counter()
    messages: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    slowest = 0.0
    signal.signal(signal.SIGALRM, _alarm)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for index in range(args.n):
            roll = rng.random()
            if roll < 0.8 or not sce_texts:
                kind, text = "osc", mutate(rng.choice(sources), rng)
            elif roll < 0.9:
                kind, text = "yaml", mutate(rng.choice(PARAMETERS), rng)
            else:
                kind, text = "sce", mutate(rng.choice(sce_texts), rng)
            began = time.perf_counter()
            signal.setitimer(signal.ITIMER_REAL, args.limit_s)
            try:
                if kind == "osc":
                    resolve(parse_text(text, str(folder / "f.osc")), base_dir=folder)
                elif kind == "yaml":
                    path = folder / "p.yaml"
                    path.write_text(text, encoding="utf-8", errors="surrogatepass")
                    read_parameter_documents(path)
                else:
                    parse_sce(text, str(folder / "v.sce"))
                outcome = "ok"
            except Hang:
                outcome = "hang"
            except OscError as exc:
                outcome = "located" if exc.location is not None else "unlocated"
                messages[outcome][re.sub(r"\d+", "N", exc.message.splitlines()[0])[:90]] += 1
            except RecursionError:
                outcome = "traceback"
                messages[outcome]["RecursionError"] += 1
            except Exception as exc:  # noqa: BLE001 - what we are looking for
                outcome = "traceback"
                messages[outcome][f"{type(exc).__name__}: {traceback.format_exc().splitlines()[-3].strip()}"] += 1
            finally:
                signal.setitimer(signal.ITIMER_REAL, 0)
            slowest = max(slowest, time.perf_counter() - began)
            counts[f"{kind}:{outcome}"] += 1
            counts[outcome] += 1
            if sys.stderr.isatty() and index % 1000 == 999:
                print(f"\r{index + 1}/{args.n}", end="", file=sys.stderr, flush=True)
    elapsed = time.perf_counter() - start
    print(f"{args.n} inputs in {elapsed:.1f} s (seed {args.seed}); slowest {slowest * 1000:.0f} ms")
    for outcome in ("ok", "located", "unlocated", "traceback", "hang"):
        print(f"  {outcome:<10} {counts[outcome]:>7}   " + "  ".join(
            f"{k.split(':')[0]} {v}" for k, v in sorted(counts.items()) if k.endswith(":" + outcome)))
    for outcome in ("traceback", "hang", "unlocated", "located"):
        if messages[outcome]:
            print(f"distinct {outcome} messages: {len(messages[outcome])}; most common:")
            for message, count in messages[outcome].most_common(5):
                print(f"  {count:>6}  {message}")


if __name__ == "__main__":
    main()
