"""What the command line calls: create or resume a batch, run it with local workers, write the report.

The single-host run is nothing more than the shared queue: a batch in the store (an SQLite file by
default), a :class:`Worker` scoped to it, and the merged report built from the store's results.
"""

from __future__ import annotations

import os
import shlex
import signal
import socket
import sys
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path
from types import FrameType

from coverage_engine.domains import InputDomain, declared_text, header_domains
from coverage_engine.proposals import SEARCH_FILE
from coverage_engine.results.atomic import write_output, write_text_atomically
from coverage_engine.results.files import DECLARED_FILE, RESULT_FILE
from executor.batch import folder_history
from executor.batch.batch_outcome import BatchOutcome, batch_outcome
from executor.batch.errors import BatchError, NothingToResume
from executor.batch.inputs import Shard, check_command, discover, job_specs, not_utf8
from executor.batch.junit_merge import merged_report, variants_of
from executor.batch.progress import Reporter
from executor.batch.repeats import expand_specs
from executor.batch.worker import Worker, WorkerSettings, WorkerSummary
from executor.batch.worker_server import EarlyServer
from executor.children.process import disk_full
from store.jobs import Batch, BatchOptions, JobSpec
from store.queue import DEFAULT_LEASE, QueueStore
from store.states import JobState
from store.variant_lookup import VariantInfo

#: Exit codes of an interrupted run: 128 + the signal number, as shells report it.
EXIT_INTERRUPTED: dict[int, int] = {signal.SIGINT: 130, signal.SIGTERM: 143}

#: How the report of an interrupted run names the interruption.
INTERRUPTION_NAMES: dict[int, str] = {signal.SIGINT: "Ctrl-C", signal.SIGTERM: "SIGTERM"}


@dataclass(frozen=True)
class BatchRequest:
    """A batch as asked for on the command line."""

    input_dir: str | None
    output_dir: str
    command: tuple[str, ...]
    options: BatchOptions
    shard: Shard | None = None
    #: More input folders after ``input_dir`` (``-i a -i b``), and whether subfolders count.
    more_inputs: tuple[str, ...] = ()
    recursive: bool = False


def output_folder(path: str) -> str:
    """The absolute output folder (created with its parents), the key under which a batch is resumed."""
    folder = Path(path).expanduser().resolve()
    for place in (folder, *folder.parents):
        if place.exists():
            if not place.is_dir():
                raise BatchError(f"cannot make the output folder {folder}: {place} is not a folder")
            break
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BatchError(f"cannot make the output folder {folder}: {exc.strerror or exc}") from exc
    return str(folder)


def create_batch(store: QueueStore, request: BatchRequest, *, mode: str = "local") -> Batch:
    """Discover the scenario files, keep the shard's share, and enqueue one job per file."""
    specs = _discovered_specs(request, mode)
    return store.create_batch(mode=mode, input_dir=str(Path(request.input_dir or ".").resolve()),
                              output_dir=request.output_dir, host=socket.gethostname(),
                              command=request.command, options=_shard_options(request), specs=specs)


@dataclass(frozen=True)
class OnlyNew:
    """What ``--only-new`` made: the batch of new files (None when there is none), the folder's earlier
    batch it continues (None for a folder with no batch yet) and how many files it passed over."""

    batch: Batch | None
    earlier: Batch | None
    passed_over: int


def create_only_new_batch(store: QueueStore, request: BatchRequest, *, mode: str = "local") -> OnlyNew:
    """``--only-new``: a batch of the files of the input that have no verdict in the output folder yet.

    A file counts as run when a job of the folder's batches ran the same path with the same content
    and has a verdict; the new batch continues the folder's latest batch, so its report holds the
    earlier verdicts and the new ones (``scenario_variation --only-new`` then this: only the new
    variants run, and the report covers them all).
    """
    specs = _discovered_specs(request, mode)
    earlier = store.latest_batch(output_dir=request.output_dir)
    fresh = folder_history.new_specs(store, earlier, specs)
    if specs and not fresh:
        return OnlyNew(None, earlier, len(specs))
    options = _shard_options(request)
    if earlier is not None:
        options = replace(options, continues=earlier.id)
    batch = store.create_batch(mode=mode, input_dir=str(Path(request.input_dir or ".").resolve()),
                               output_dir=request.output_dir, host=socket.gethostname(),
                               command=request.command, options=options, specs=fresh)
    return OnlyNew(batch, earlier, len(specs) - len(fresh))


def _discovered_specs(request: BatchRequest, mode: str) -> list[JobSpec]:
    """One job spec per scenario file of the request's input folders, limited to its shard."""
    if request.input_dir is None:
        raise BatchError("-i/--input-dir is required (except with --resume)")
    files = discover(request.input_dir, *request.more_inputs, recursive=request.recursive)
    for name in not_utf8(files):
        print(f"warning: {name}: the file name is not UTF-8; its job fails (rename the file)", file=sys.stderr)
    if request.command:                  # an empty command: the built-in runner
        check_command(request.command, require_executable=mode == "local")
    return expand_specs(job_specs(files, request.shard, keep_texts=mode != "local"), request.options.repeat)


def _shard_options(request: BatchRequest) -> BatchOptions:
    if request.shard is None:
        return request.options
    return replace(request.options, shard=f"{request.shard.index}/{request.shard.count}")


def rerun_failed_batch(store: QueueStore, output_dir: str) -> tuple[Batch, Batch | None]:
    """``--rerun-failed``: a new batch of the jobs of ``output_dir`` whose latest verdict is not a pass.

    Returns ``(earlier, new)``: the folder's latest batch, and the new one (None when every job of the
    folder passed). The new batch runs like the earlier one (its command and options), writes into the
    same job folders (their earlier logs are kept as ``log.<n>.txt``) and continues the earlier batch,
    so the folder's report keeps every job's latest verdict however many reruns follow.
    """
    earlier = store.latest_batch(output_dir=output_dir)
    if earlier is None:
        raise NothingToResume(f"there is no batch for {output_dir} in the store {store.url}: nothing to rerun")
    files = list(dict.fromkeys(Path(job.scenario_path)                   # a repeated variant's attempts: once
                               for job in folder_history.not_passed(store, earlier)))
    missing = [str(f) for f in files if not f.is_file()]
    if missing:
        raise BatchError(f"--rerun-failed: scenario file(s) gone since batch {earlier.id}: {', '.join(missing[:3])}")
    if not files:
        return earlier, None
    batch = store.create_batch(mode="local", input_dir=earlier.input_dir, output_dir=output_dir,
                               host=socket.gethostname(), command=earlier.command,
                               options=replace(earlier.options, continues=earlier.id),
                               specs=expand_specs(job_specs(files, keep_texts=False), earlier.options.repeat))
    return earlier, batch


#: The options stored with a batch (the fields of :class:`store.jobs.BatchOptions`) and their command-line
#: flags: the one definition of what ``--resume`` compares (the command line's parameters share these names).
OPTION_FLAGS = {"timeout": "--timeout", "retries": "--retries", "post_run": "--post-run",
                "ignore_return_value": "--ignore-process-return-value", "halt_on_failure": "--halt-on-failure",
                "grace": "--grace", "shard": "--shard", "simulation": "--simulation", "repeat": "--repeat",
                "pass_rate": "--pass-rate"}


def _shown(value: object) -> str:
    if value is None:
        return "none"
    if isinstance(value, tuple):
        return " ".join(shlex.quote(v) for v in value) if value else "none"
    return f"{value:g}" if isinstance(value, float) else str(value)


def option_differences(batch: Batch, request: BatchRequest, given: Iterable[str]) -> list[str]:
    """``--flag X (the batch has Y)`` for each option in ``given`` (as typed) that differs from the stored batch."""
    wanted = set(given)
    options = _shard_options(request)
    out = []
    if "input_dir" in wanted and request.input_dir is not None and \
            str(Path(request.input_dir).resolve()) != batch.input_dir:
        out.append(f"-i {request.input_dir} (the batch has {batch.input_dir})")
    for name, flag in OPTION_FLAGS.items():
        mine, stored = getattr(options, name), getattr(batch.options, name)
        if name in wanted and mine != stored:
            out.append(f"{flag} {_shown(mine)} (the batch has {_shown(stored)})")
    return out


def resume_batch(store: QueueStore, output_dir: str, command: Sequence[str],
                 request: BatchRequest | None = None, given: Iterable[str] = ()) -> Batch:
    """The latest batch for ``output_dir``, its cancelled jobs queued again.

    The command and every option named in ``given`` (those typed on the command line) must match the
    stored batch: a resumed batch runs all its jobs alike, so a difference is refused, not ignored.
    """
    batch = store.latest_batch(output_dir=output_dir)
    if batch is None:
        raise NothingToResume(f"there is no batch for {output_dir} in the store {store.url} to resume")
    if command and tuple(command) != batch.command:
        raise BatchError(f"--resume: the batch was started with a different command: {' '.join(batch.command)}")
    differences = option_differences(batch, request, given) if request is not None else []
    if differences:
        raise BatchError("--resume: the batch was started with other options; it keeps them, so leave these "
                         "out or start a new batch without --resume: " + "; ".join(differences))
    store.resume(batch.id)
    return batch


@contextmanager
def interrupts_stop(worker: Worker) -> Iterator[list[int]]:
    """While inside, SIGINT/SIGTERM stop the worker (a second SIGINT kills the children at once)."""
    received: list[int] = []

    def handler(signum: int, _frame: FrameType | None) -> None:
        worker.stop(force=bool(received) and signum == signal.SIGINT)
        received.append(signum)

    previous = {sig: signal.signal(sig, handler) for sig in EXIT_INTERRUPTED}
    try:
        yield received
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


def run_worker(store: QueueStore, settings: WorkerSettings, reporter: Reporter,
               total: int | None = None, done: int = 0,
               early: EarlyServer | None = None) -> tuple[WorkerSummary, int | None]:
    """Run a worker until it runs out of work or is interrupted; returns its summary and the signal
    (``early``: a fork server launched for it before the batch was known, see ``worker_server.start_early``)."""
    worker = Worker(store, settings, reporter) if early is None else \
        Worker(store, settings, reporter, early.identity, early.server)
    reporter.begin(total, done)
    try:
        with interrupts_stop(worker) as received:
            summary = worker.run()
    finally:
        reporter.end()
    return summary, (received[0] if received else None)


@dataclass(frozen=True)
class LocalRun:
    """How a local run ended: the batch's counts, the signal that stopped it, and a full disk that did."""

    counts: dict[JobState, int]
    signum: int | None = None
    #: The output folder whose disk filled up (the run stopped there; ``--resume`` finishes it), else None.
    disk_full: str | None = None
    #: Why the merged report could not be written (a full disk), else None.
    report_error: str | None = None
    #: The batch per variant (flaky ones, repeated attempts), when its report was written.
    outcome: BatchOutcome | None = None


#: How the merged report names a run that a full disk stopped.
DISK_FULL_NAME = "no space left on device"


def run_local(store: QueueStore, batch: Batch, slots: int, reporter: Reporter, *,
              lease: float = DEFAULT_LEASE, echo_children: bool = True, early: EarlyServer | None = None) -> LocalRun:
    """Run the batch's remaining jobs here with ``slots`` parallel children; write the merged report.

    With one slot the child's own output is shown as it runs, unless ``echo_children`` is False (the
    search loop, whose output is a line per round). ``early``: a fork server the command line launched
    for this run before the batch was known (``worker_server.start_early``).

    A full disk stops the run like an interruption (the jobs it stopped stay resumable); the report of
    what finished is still attempted, and if it cannot be written either, the run says so instead of
    failing: the store holds every result, and ``report`` writes it once there is room.
    """
    counts = store.counts(batch.id)
    total = sum(counts.values())
    done = sum(counts[s] for s in (JobState.PASSED, JobState.FAILED, JobState.ERROR, JobState.TIMEOUT))
    settings = WorkerSettings(slots=slots, batch_id=batch.id, lease=lease, poll=0.2,
                              echo=sys.stdout.buffer if slots == 1 and echo_children else None, cwd=os.getcwd(), hand_over_ahead=True)
    summary, signum = run_worker(store, settings, reporter, total, done, early)
    interrupted = None if signum is None else INTERRUPTION_NAMES.get(signum, f"signal {int(signum)}")
    if summary.disk_full is not None and interrupted is None:
        interrupted = DISK_FULL_NAME
    try:
        outcome = write_outcome_report(store, batch, Path(batch.output_dir) / RESULT_FILE, interrupted=interrupted)
    except BatchError as exc:
        if summary.disk_full is None and not (exc.__cause__ and disk_full(exc.__cause__)):
            raise
        return LocalRun(store.counts(batch.id), signum, summary.disk_full or batch.output_dir, str(exc))
    return LocalRun(outcome.counts, signum, summary.disk_full, outcome=outcome)


def check_report_path(path: str | os.PathLike[str]) -> None:
    """Raise :class:`BatchError` when the report cannot go to ``path`` because a folder on its way is a file."""
    target = Path(path).absolute()
    if target.is_dir():
        raise BatchError(f"cannot write the report: {target} is a folder")
    for folder in target.parents:
        if folder.exists():
            if not folder.is_dir():
                raise BatchError(f"cannot write the report: {folder} is not a folder")
            return


def write_batch_report(store: QueueStore, batch: Batch, path: str | os.PathLike[str], *,
                       interrupted: str | None = None) -> dict[JobState, int]:
    """Build the merged JUnit report of ``batch`` from the store and write it to ``path``; returns the counts
    (of variants: with ``--repeat`` a variant's attempts count once).

    ``interrupted`` (``Ctrl-C``, ``SIGTERM``) says the batch was stopped: its unfinished jobs are in the
    report too, as errors (stopped while running) or skipped (not started). A batch that continues
    earlier ones (``--rerun-failed``, ``--only-new``) reports, and counts, the latest verdict of every
    job of the folder (:mod:`executor.batch.folder_history`).
    """
    return write_outcome_report(store, batch, path, interrupted=interrupted).counts


def write_outcome_report(store: QueueStore, batch: Batch, path: str | os.PathLike[str], *,
                         interrupted: str | None = None) -> BatchOutcome:
    """:func:`write_batch_report`, returning the batch per variant (:mod:`executor.batch.batch_outcome`);
    a finished batch's figures are kept for ``scenario_coverage history`` (:mod:`executor.batch.history`)."""
    check_report_path(path)
    outcome = batch_outcome(store, batch)
    variants = variants_of(store.engine, [j.scenario_path for j in outcome.listed])
    xml_text = merged_report(outcome.jobs, variants, interrupted=interrupted, notes=outcome.notes)
    try:
        write_output(path, xml_text)     # a device or FIFO is written in place, '-' is standard output
        if str(path) != "-" and os.path.realpath(Path(path).parent) == os.path.realpath(batch.output_dir):
            write_declared(Path(path).parent, variants.values())   # the batch's own results folder only
            copy_search_estimate(Path(batch.input_dir), Path(path).parent)
    except OSError as exc:
        raise BatchError(f"cannot write the report {path}: {exc.strerror or exc}") from exc
    if interrupted is None:
        from executor.batch.history import record_batch_summary

        record_batch_summary(store, batch, outcome)
    return outcome


def write_declared(folder: Path, variants: Iterable[VariantInfo]) -> None:
    """Leave ``declared.json`` beside the merged report: what the variations of the batch's variants
    declared (their ``.sce`` headers, one per variation run), so the results folder alone is enough for
    ``scenario_coverage`` to report every declared value, also where the ``.sce`` files are not."""
    declared: dict[str, InputDomain] = {}
    for header in {variant.header for variant in variants if variant.header}:
        for domain in header_domains(header):
            known = declared.get(domain.key)
            declared[domain.key] = domain if known is None else known.merged(domain)
    if declared:
        write_text_atomically(folder / DECLARED_FILE, declared_text(declared.values()))


def copy_search_estimate(variants: Path, results: Path) -> None:
    """Copy the round's estimate (``search.json``, written by ``scenario_variation --from`` beside the
    variants) into the results folder, as ``declared.json`` is kept there: the results folder alone then
    tells ``scenario_coverage`` which round of a search it holds and what that round estimated."""
    source = variants / SEARCH_FILE
    if not source.is_file() or source.is_symlink() or os.path.realpath(variants) == os.path.realpath(results):
        return
    try:
        text = source.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return                        # an estimate that cannot be read is not copied; the report goes on
    write_text_atomically(results / SEARCH_FILE, text)


#: Exit code of a batch that did not pass, or could not go on (a full disk).
EXIT_FAILED = 1

#: Exit code of a batch with no job at all (an empty shard): pytest's "no tests collected", not a green run.
EXIT_NOTHING_RAN = 5


def exit_code(counts: dict[JobState, int], signum: int | None = None) -> int:
    """0 only when every job of the batch passed; 5 when it had none; 128+signal when interrupted."""
    if signum is not None:
        return EXIT_INTERRUPTED.get(signum, 128 + int(signum))
    total = sum(counts.values())
    if not total:
        return EXIT_NOTHING_RAN
    return 0 if counts[JobState.PASSED] == total else EXIT_FAILED


def summary_line(batch: Batch, counts: dict[JobState, int], report: str | None = None,
                 outcome: BatchOutcome | None = None) -> str:
    """One line saying how the batch fared (per variant, and its attempts' pass rate, with ``--repeat``)."""
    total = sum(counts.values())
    parts = [f"{counts[s]} {s.value}" for s in JobState if counts[s]]
    what = "job(s)" if batch.options.repeat <= 1 else f"variant(s) x {batch.options.repeat} attempts"
    text = f"batch {batch.id}: {total} {what}: " + ", ".join(parts or ["none"])
    if outcome is not None and batch.options.repeat > 1 and outcome.runs:
        text += f"; {outcome.runs_passed} of {outcome.runs} attempt(s) passed ({100 * outcome.runs_passed / outcome.runs:.0f} %)"
    if outcome is not None and outcome.flaky:
        text += f"; {len(outcome.flaky)} flaky"
    if report:
        text += f"; report {report}"
    return text
