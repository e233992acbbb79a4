"""Is the batch process the bottleneck? Its own CPU per job, launched mode against xargs, jobs/s per -j (issue 34).

Four figures, each for this tree and (with ``--baseline DIR``) for an older source tree run by the
same interpreter, side by side in one run:

1. **The batch process's own CPU per job**: ``scenario_batch_execution -j 2`` with the built-in runner
   over ``--variants`` trivial variants (``scenario_variation`` of a tutorial-style file: a serial
   ``log()`` and ``emit end``). "Own" is the utime + stime of every thread of that one process,
   children excluded (the fork server, the jobs it forks, the watchdog): read from
   ``/proc/<pid>/stat`` (fields 14 and 15) after the process has exited but before it is reaped
   (``waitid(..., WEXITED | WNOWAIT)``), so nothing of its last moments is missed and nothing of its
   children (which ``wait4``'s rusage would add) is counted. Start-up and the merged report are in
   it (divided over the jobs). Goal: <= 0.5 ms per job.

   In the same run, the **forking processes' own CPU per job** (:class:`ServerWatch`): the fork
   server's, or with several forkers each forker's and the dispatcher's, from the moment each was
   ready. Each is one process whatever ``-j``, as the batch process is, so the busiest of them all
   caps the jobs/s a worker reaches on many cores ("one-core cap"). ``--cpu-slots 8 --pretend-cores
   16`` runs this figure as a 16-core machine would (two forkers at -j 8), to see the split on a
   smaller one.
2. **Launched mode against xargs**: ``--launched`` jobs whose command is a shell writing a one-testcase
   ``test.xml``, ``-j 2``, against ``xargs -P 2`` running one shell per job that does the same work our
   runner asks for (make the job's folder, send its output to ``log.txt``, write ``test.xml``). Goal:
   ours <= 1.3x xargs (wall time).
3. **The machine's speed today**: the own CPU of a fixed pure-Python workload (:data:`REFERENCE`: frozen
   records, JSON, small XML, the batch process's kind of work) in a fresh interpreter, best of the rounds.
   Shared VMs differ in speed from day to day (on this project's 2-core VM the same commit measured 0.81 ms
   per job one day and 1.41 ms another), so the CPU per job is also printed per second of it, a figure
   that compares machines and days.
4. **Throughput per -j**: jobs/s of the built-in runner over ``--throughput`` variants with -j 1, 2, 4, …
   up to the CPUs this process may use (or the counts ``--jobs 1,2,4,8,16`` names): over the whole run,
   and while the jobs ran (from the first job's start to the last one's end, the store's times). The
   batch's start-up and its report are the same for every -j (about half a second on the 2-core VM),
   so over 500 trivial jobs they weigh on the fast runs: at 1,000 jobs/s the whole run could not
   reach 10x a -j 1 run of 120 jobs/s however cheap a job became. The second figure shows what the
   slots themselves reach.

The figures are printed as a table and, last, as one JSON line (``{"cpus": …, "trees": {label: {"cpu_ms_per_job":
…, "launched_over_xargs": …, "jobs_per_s": {"1": …}}}, …}``) for scripts that compare machines. Only the
core dependencies are needed (the standard library here; the project's console scripts in this
interpreter's folder).

Both trees' modules are compiled to bytecode first (``compileall``), as pip leaves an installed tool: where
``PYTHONDONTWRITEBYTECODE`` is set, every run would otherwise compile some ninety modules from source
(0.09 s a run here), a cost no user of an installed release pays.

Every run writes into a fresh folder with a copy of the variation's store (a store that grows
run after run would tilt the comparison). Runs of this tree and the baseline alternate.

The baseline tree is a plain source tree of an older commit, e.g.::

    git archive f0e4cc8 | (mkdir -p /tmp/base && tar -x -C /tmp/base)
    .venv/bin/python benchmarks/bench_batch_process.py --baseline /tmp/base

(its packages are put first on ``PYTHONPATH``; the console scripts and the interpreter are this venv's).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import sqlite3
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

BIN = Path(sys.executable).parent
HERE = Path(__file__).resolve().parent.parent

#: The launched child: a shell writing a one-testcase test.xml into its output folder.
CHILD = 'echo "<testsuite><testcase name=\\"t\\"/></testsuite>" > "$2/test.xml"'

#: What xargs runs per job: the same shell, also doing what our runner does for it (folder and log).
XARGS_CHILD = 'mkdir -p "$2" && exec > "$2/log.txt" 2>&1; ' + CHILD

CLOCK_TICKS = os.sysconf("SC_CLK_TCK")


@dataclass(frozen=True)
class Tree:
    """A source tree to measure: its label and the PYTHONPATH that selects it (None: the installed one)."""

    label: str
    path: str | None


@dataclass(frozen=True)
class Measured:
    """One run: wall seconds and the own CPU seconds of the measured process (children excluded), and
    the own CPU seconds of each fork server it started (see :class:`ServerWatch`)."""

    wall: float
    cpu: float
    #: Each fork server's own CPU seconds once it served (from its first child on: its start and preload left out).
    servers: tuple[float, ...] = ()
    #: Seconds from the first job's start to the last job's end (the store's times): the run without
    #: the batch's start-up and its report.
    running: float | None = None


#: How often :class:`ServerWatch` reads the fork servers' CPU (what a server spends in its last interval is missed).
WATCH_EVERY = 0.02


class ServerWatch(threading.Thread):
    """The own CPU (utime + stime, children excluded) of every process that forks a batch's jobs, read
    from ``/proc`` every :data:`WATCH_EVERY` seconds while they live (the last reading of each is kept).

    Those are the fork server (a child of the batch process whose command line runs
    ``executor.batch.fork_server``) and, with several forkers (:mod:`executor.batch.fork_dispatch`),
    the server's children that have children of their own (a trivial job has none). Forking is the
    batch's other work for every job (a ``fork`` of a warm interpreter, and the copies of the pages the
    forking process writes afterwards), done by processes of its own: with many cores, the busiest of
    them and the batch process bound the jobs/s. A process's start (imports, the probe runs of the
    preload) is left out: its CPU is counted from the first reading that finds a child of its own (it
    forks none before it is ready)."""

    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.pid = pid
        self.done = threading.Event()
        self.cpu: dict[int, float] = {}
        self.ready: dict[int, float] = {}          # a forking process's CPU when it was first seen with a child
        self._servers: set[int] = set()
        self._others: set[int] = set()

    def run(self) -> None:
        while not self.done.wait(WATCH_EVERY):
            children = _children(self.pid)
            if children is None:
                return
            for child in children:
                if child not in self._servers and child not in self._others:
                    self._classify(child)
            watched = set(self._servers)
            for server in self._servers:
                watched.update(_children(server) or ())
            for pid in watched:
                try:
                    with open(f"/proc/{pid}/stat", "rb") as handle:
                        fields = handle.read().rsplit(b")", 1)[1].split()
                except OSError:
                    continue
                self.cpu[pid] = (int(fields[11]) + int(fields[12])) / CLOCK_TICKS
                if pid not in self.ready and _children(pid):
                    self.ready[pid] = self.cpu[pid]

    def _classify(self, pid: int) -> None:
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as handle:
                server = b"executor.batch.fork_server" in handle.read()
        except OSError:
            return
        (self._servers if server else self._others).add(pid)

    def finish(self) -> tuple[float, ...]:
        self.done.set()
        self.join()
        return tuple(self.cpu[pid] - self.ready[pid] for pid in sorted(self.ready))


def _children(pid: int) -> list[int] | None:
    """The children of ``pid`` (None when it is gone)."""
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as handle:
            return [int(child) for child in handle.read().split()]
    except OSError:
        return None


def own_cpu_at_exit(proc: subprocess.Popen) -> float:
    """utime + stime of ``proc`` (all its threads, not its children) once it has exited; then reap it."""
    os.waitid(os.P_PID, proc.pid, os.WEXITED | os.WNOWAIT)
    with open(f"/proc/{proc.pid}/stat", "rb") as handle:
        fields = handle.read().rsplit(b")", 1)[1].split()
    proc.wait()
    return (int(fields[11]) + int(fields[12])) / CLOCK_TICKS   # fields 14 and 15 of stat(5)


#: The tree's packages the console scripts import (compiled before measuring).
PACKAGES = ("cli", "coverage_engine", "executor", "store")


def compile_tree(tree: Tree) -> None:
    """Write the bytecode of ``tree``'s packages (see the module doc), quietly; a failure is loud."""
    root = Path(tree.path) if tree.path is not None else HERE
    folders = [str(root / name) for name in PACKAGES if (root / name).is_dir()]
    subprocess.run([sys.executable, "-m", "compileall", "-q", *folders], check=True, stdout=subprocess.DEVNULL)


#: A fixed pure-Python workload of the batch process's kind (frozen records, JSON, small XML, string work),
#: run in a fresh interpreter each round: its CPU seconds are the yardstick of this machine's speed today.
REFERENCE = """
import json
from dataclasses import dataclass, replace
from xml.etree import ElementTree as ET

@dataclass(frozen=True)
class Row:
    id: int
    name: str
    status: str
    started: float
    finished: float

text = '<testsuite><testcase name="t" classname="c" time="0.1"/></testsuite>'
for i in range(20000):
    row = Row(i, f"job{i}", "passed", i * 0.5, i * 0.5 + 0.1)
    message = json.loads(json.dumps({"id": row.id, "event": "exited", "status": 0}))
    case = ET.fromstring(text).find("testcase")
    name = f"{row.name}[{case.get('name')}={message['status']}]".upper().lower()
"""


def reference(env: dict[str, str]) -> float:
    """Own CPU seconds of :data:`REFERENCE` in a fresh interpreter (see the module doc)."""
    proc = subprocess.Popen([sys.executable, "-c", REFERENCE], env=env)
    cpu = own_cpu_at_exit(proc)
    if proc.returncode != 0:
        raise SystemExit(f"the reference workload failed ({proc.returncode})")
    return cpu


def run(argv: Sequence[str], cwd: Path, env: dict[str, str]) -> Measured:
    """Run ``argv`` with output to /dev/null (as in CI: no terminal); fail loudly on a bad exit."""
    start = time.perf_counter()
    with tempfile.TemporaryFile() as errors:
        proc = subprocess.Popen(list(argv), cwd=cwd, env=env, stdout=subprocess.DEVNULL, stderr=errors)
        watch = ServerWatch(proc.pid)
        watch.start()
        cpu = own_cpu_at_exit(proc)
        wall = time.perf_counter() - start
        servers = watch.finish()
        if proc.returncode != 0:
            errors.seek(0)
            raise SystemExit(f"{argv[0]} failed ({proc.returncode}): {errors.read()[-2000:].decode(errors='replace')}")
    return Measured(wall, cpu, servers)


def environment(tree: Tree) -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if k not in ("SCENARIO_STORE", "PYTHONPATH")}
    env["NO_COLOR"] = "1"
    if tree.path is not None:
        env["PYTHONPATH"] = tree.path
    return env


def variants(work: Path, count: int) -> Path:
    """``count`` trivial variants in ``work/variants`` (and their store, ``work/store.db``)."""
    work.mkdir(parents=True, exist_ok=True)
    values = ", ".join(f'"m{i}"' for i in range(count))
    (work / "bench.osc").write_text("import osc.helpers\n\nscenario bench:\n    do serial:\n"
                                    f"        log() with:\n            keep(it.msg in [{values}])\n"
                                    "        emit end\n")
    env = environment(Tree("this", None))
    run([str(BIN / "scenario_variation"), "bench.osc", "-o", "variants", "--store",
         f"sqlite:///{work / 'store.db'}"], work, env)
    return work


#: ``scenario_batch_execution`` in a process that takes the machine for one of ``sys.argv[1]`` cores
#: (``--pretend-cores``: the runner's own count patched, so it starts as many forkers as it would there).
AS_IF_CORES = ("import sys; import executor.batch.builtin_runner as runner; cores = int(sys.argv.pop(1)); "
               "runner.usable_cpus = lambda: cores; sys.argv[0] = 'scenario_batch_execution'; "
               "from cli.scenario_batch_execution import main; main()")


def batch(source: Path, run_dir: Path, tree: Tree, slots: int, command: Sequence[str] = (),
          cores: int | None = None) -> Measured:
    """``scenario_batch_execution -i variants -o results -j slots [-- command]`` in a fresh folder (as on a
    machine of ``cores`` usable cores, when given)."""
    run_dir.mkdir(parents=True)
    shutil.copy(source / "store.db", run_dir / "store.db")
    program = [str(BIN / "scenario_batch_execution")] if cores is None else \
        [sys.executable, "-c", AS_IF_CORES, str(cores)]
    argv = [*program, "-i", str(source / "variants"), "-o", "results", "-j",
            str(slots), "--store", f"sqlite:///{run_dir / 'store.db'}"]
    if command:
        argv += ["--", *command]
    measured = run(argv, run_dir, environment(tree))
    if not (run_dir / "results" / "test.xml").is_file():
        raise SystemExit(f"no merged report in {run_dir}")
    with sqlite3.connect(run_dir / "store.db") as conn:
        first, last = conn.execute("SELECT MIN(started_at), MAX(finished_at) FROM jobs").fetchone()
    return replace(measured, running=last - first)


def xargs(source: Path, run_dir: Path) -> float:
    """Wall seconds of ``xargs -P 2`` running :data:`XARGS_CHILD` once per scenario file."""
    run_dir.mkdir(parents=True)
    files = sorted((source / "variants").glob("*.sce"))
    pairs = "".join(f"{f}\n{run_dir / 'results' / f.stem}\n" for f in files).encode()
    start = time.perf_counter()
    subprocess.run(["xargs", "-d", "\n", "-P", "2", "-n", "2", "sh", "-c", XARGS_CHILD, "sh"], input=pairs,
                   check=True, cwd=run_dir)
    return time.perf_counter() - start


def slot_counts(cpus: int) -> list[int]:
    """1, 2, 4, … and the CPU count itself."""
    counts, n = [], 1
    while n < cpus:
        counts.append(n)
        n *= 2
    return [*counts, cpus]


def usable_cpus() -> int:
    return len(os.sched_getaffinity(0))


def job_counts(text: str | None, cpus: int) -> list[int]:
    """The -j values of the throughput sweep: ``--jobs 1,2,4`` as given (1 first, for the ratios), else :func:`slot_counts`."""
    if not text:
        return slot_counts(cpus)
    counts = sorted({int(part) for part in text.split(",") if part.strip()} | {1})
    if counts[0] < 1:
        raise SystemExit(f"--jobs: each count must be 1 or more: {text}")
    return counts


def span(measured: Measured) -> float:
    """Seconds from the first job's start to the last one's end (the whole run when unknown)."""
    return measured.running if measured.running else measured.wall


def busiest(measured: Measured, jobs: int) -> float:
    """The own CPU per job (ms) of the busiest fork server of a run (0 when it started none)."""
    return max(measured.servers, default=0.0) / jobs * 1000


def serial_cap(measured: Measured, jobs: int) -> float:
    """Jobs/s that one core allows the busier of the batch process and its busiest fork server (each is
    one process, whatever -j): the ceiling of the built-in runner's throughput on many cores."""
    return 1000 / max(measured.cpu / jobs * 1000, busiest(measured, jobs))


def arguments() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", help="a source tree of an older commit to measure side by side")
    parser.add_argument("--variants", type=int, default=2000, help="built-in jobs for the CPU figure")
    parser.add_argument("--launched", type=int, default=500, help="launched jobs against xargs")
    parser.add_argument("--throughput", type=int, default=500, help="built-in jobs per -j for jobs/s")
    parser.add_argument("--rounds", type=int, default=1, help="runs of each; the best is reported")
    parser.add_argument("--jobs", help="the -j values of the throughput sweep, e.g. 1,2,4,8,16 (default: "
                                       "1, 2, 4, … up to the usable CPUs)")
    parser.add_argument("--cpu-slots", type=int, default=2, help="-j of the CPU figure's run (default 2)")
    parser.add_argument("--pretend-cores", type=int, help="run the built-in batches as on a machine with this "
                        "many usable cores (the runner starts the forkers it would start there), to see "
                        "each forking process's CPU per job on a smaller machine")
    return parser.parse_args()


#: The best run of each kind, by (tree label or "xargs"/"machine", kind).
Best = dict[tuple[str, str], Measured]


def measure(args: argparse.Namespace, trees: Sequence[Tree], sweep: Sequence[int], root: Path) -> Best:
    """Every run, ``--rounds`` times, the trees alternating; the best of each kind kept: the least own
    CPU for the CPU figure and the yardstick (a CPU figure's wall time is that run's), the shortest
    wall time else."""
    big, launched, small = (variants(root / name, n) for name, n in
                            (("big", args.variants), ("launched", args.launched), ("small", args.throughput)))
    best: Best = {}

    def keep(key: tuple[str, str], measured: Measured) -> None:
        def figure(run: Measured) -> float:
            return run.cpu if key[1] in ("cpu", "reference") else run.wall

        if key not in best or figure(measured) < figure(best[key]):
            best[key] = measured

    for round_ in range(args.rounds):
        for index, tree in enumerate(trees):
            tag = f"{round_}_{index}"
            keep((tree.label, "cpu"), batch(big, root / f"cpu_{tag}", tree, args.cpu_slots, cores=args.pretend_cores))
            keep((tree.label, "launched"), batch(launched, root / f"launched_{tag}", tree, 2,
                                                 ("sh", "-c", CHILD, "sh", "{SCENARIO}", "{OUTPUT_DIR}")))
            for slots in sweep:
                keep((tree.label, f"j{slots}"), batch(small, root / f"j{slots}_{tag}", tree, slots,
                                                      cores=args.pretend_cores))
        keep(("xargs", "launched"), Measured(xargs(launched, root / f"xargs_{round_}"), 0.0))
        keep(("machine", "reference"), Measured(0.0, reference(environment(Tree("this", None)))))
    return best


def row(title: str, cells: Sequence[str], note: str = "") -> None:
    print(f"{title:<28}" + "".join(f"{cell:>36}" for cell in cells) + note)


def print_table(args: argparse.Namespace, trees: Sequence[Tree], sweep: Sequence[int], best: Best) -> None:
    """The figures of each tree side by side, one row each."""
    print(f"\n{'':<28}" + "".join(f"{t.label[:34]:>36}" for t in trees))
    cpu = [best[(t.label, "cpu")] for t in trees]
    row(f"batch CPU/job, built-in -j{args.cpu_slots}",
        [f"{m.cpu / args.variants * 1000:.2f} ms ({m.cpu:.2f} s, wall {m.wall:.1f} s)" for m in cpu])
    row(f"forking CPU/job, -j{args.cpu_slots}", [f"{sum(m.servers) / args.variants * 1000:.2f} ms "
                                               f"({len(m.servers)} proc., busiest {busiest(m, args.variants):.2f})"
                                               for m in cpu])
    row("  one-core cap (busiest)", [f"{serial_cap(m, args.variants):.0f} jobs/s" for m in cpu])
    yardstick = best[("machine", "reference")].cpu
    row("  per reference second", [f"{m.cpu / args.variants * 1000 / yardstick:.2f} ms/ref-s" for m in cpu],
        f"   (reference workload: {yardstick:.2f} s CPU)")
    xargs_wall = best[("xargs", "launched")].wall
    row(f"launched {args.launched} jobs -j2", [f"{best[(t.label, 'launched')].wall:.2f} s = "
                                              f"{best[(t.label, 'launched')].wall / xargs_wall:.2f}x" for t in trees],
        f"   (xargs -P 2: {xargs_wall:.2f} s)")
    for slots in sweep:
        cells, running = [], []
        for t in trees:
            rate, one = (args.throughput / best[(t.label, key)].wall for key in (f"j{slots}", "j1"))
            cells.append(f"{rate:.0f} jobs/s ({rate / one:.2f}x -j1)")
            rate, one = (args.throughput / span(best[(t.label, key)]) for key in (f"j{slots}", "j1"))
            running.append(f"{rate:.0f} jobs/s ({rate / one:.2f}x -j1)")
        row(f"built-in -j{slots}, {args.throughput} jobs", cells)
        row("  while jobs ran", running)


def tree_figures(args: argparse.Namespace, label: str, sweep: Sequence[int], best: Best) -> dict[str, object]:
    """One tree's figures for the JSON line."""
    cpu = best[(label, "cpu")]
    per_job = cpu.cpu / args.variants * 1000
    launched = best[(label, "launched")].wall
    return {
        "cpu_ms_per_job": round(per_job, 3),
        "cpu_ms_per_job_per_reference_s": round(per_job / best[("machine", "reference")].cpu, 3),
        "cpu_wall_s": round(cpu.wall, 3),
        "fork_server_cpu_ms_per_job": round(sum(cpu.servers) / args.variants * 1000, 3),
        "fork_servers": len(cpu.servers),
        "forking_cpu_ms_per_job_each": [round(each / args.variants * 1000, 3) for each in cpu.servers],
        "one_core_cap_jobs_per_s": round(serial_cap(cpu, args.variants), 1),
        "launched_s": round(launched, 3),
        "launched_over_xargs": round(launched / best[("xargs", "launched")].wall, 3),
        "jobs_per_s": {str(slots): round(args.throughput / best[(label, f"j{slots}")].wall, 1) for slots in sweep},
        "jobs_per_s_while_running": {str(slots): round(args.throughput / span(best[(label, f"j{slots}")]), 1)
                                     for slots in sweep}}


def main() -> int:
    args = arguments()
    trees = [Tree("this tree", None)]
    if args.baseline:
        trees.insert(0, Tree(f"baseline {args.baseline}", str(Path(args.baseline).resolve())))
    cpus = usable_cpus()
    sweep = job_counts(args.jobs, cpus)
    print(f"{cpus} usable CPUs; load average {os.getloadavg()[0]:.2f} at start", flush=True)
    for tree in trees:
        compile_tree(tree)
    with tempfile.TemporaryDirectory(prefix="bench_batch_process_") as tmp:
        best = measure(args, trees, sweep, Path(tmp))
    print_table(args, trees, sweep, best)
    mine = trees[-1].label
    per_job = best[(mine, "cpu")].cpu / args.variants * 1000
    ratio = best[(mine, "launched")].wall / best[("xargs", "launched")].wall
    print(f"\ngoals for {mine}: batch CPU/job {per_job:.2f} ms (<= 0.5: {'met' if per_job <= 0.5 else 'MISSED'}); "
          f"launched/xargs {ratio:.2f}x (<= 1.3: {'met' if ratio <= 1.3 else 'MISSED'})")
    print(json.dumps({"cpus": cpus, "reference_cpu_s": round(best[("machine", "reference")].cpu, 3),
                      "variants": args.variants, "launched": args.launched, "throughput_jobs": args.throughput,
                      "xargs_s": round(best[("xargs", "launched")].wall, 3),
                      "trees": {t.label: tree_figures(args, t.label, sweep, best) for t in trees},
                      "goals_met": {"cpu_ms_per_job": per_job <= 0.5, "launched_over_xargs": ratio <= 1.3}}))
    return 1 if per_job > 0.5 or ratio > 1.3 else 0


if __name__ == "__main__":
    sys.exit(main())
