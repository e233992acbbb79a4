"""``scenario_batch_execution``: run every scenario file of a folder as a job of a durable queue.

Thin click commands: options are parsed here, the work is done by :mod:`executor.batch`, and errors
become one line on stderr and an exit code (a traceback only with ``-d/--debug``).

    scenario_batch_execution -i DIR -o OUT [options] [-- CMD … {SCENARIO} … {OUTPUT_DIR} …]
    scenario_batch_execution worker|status|report --store URL …

The first argument selects a subcommand only when it is exactly ``worker``, ``status`` or ``report``,
so the seed command line works unchanged. Exit codes: 0 every job passed · 1 a job did not pass, or
a runtime error (files, store, report) · 2 the command line is malformed (click.UsageError and
:class:`BatchUsageError`) · 130/143 interrupted by SIGINT/SIGTERM.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING, NoReturn

import click

from cli.batch_options import JobsType, RepeatType, ShardType
from cli.boundary import Boundary
from cli.options import Seconds, debug_option, store_option
from coverage_engine.results.files import RESULT_FILE
from executor.batch.errors import BatchError, BatchUsageError
from executor.output.terminal import printable

if TYPE_CHECKING:
    from executor.batch.flaky import VariantRecord
    from executor.batch.inputs import Shard
    from executor.batch.orchestration import BatchRequest, LocalRun
    from executor.output.folder_lock import FolderLock
    from store.jobs import Batch, Job
    from store.queue import QueueStore

PROG = "scenario_batch_execution"
CONTEXT = {"help_option_names": ["-h", "--help"]}


def _check_command(command: Sequence[str]) -> None:
    """The launch command's form (not empty, both placeholders) is checked before anything is touched."""
    from executor.batch.errors import BadCommand
    from executor.batch.inputs import check_command

    try:
        check_command(command, require_executable=False)
    except BadCommand as exc:
        raise click.UsageError(str(exc)) from exc


def _open_store(url: str | None, *, existing: bool = False) -> QueueStore:
    """The store at ``url``; ``existing``: it must exist already and is neither created nor migrated."""
    from store.queue import QueueStore

    return QueueStore.open_existing(url) if existing else QueueStore.open(url)


def _typed_options() -> list[str]:
    """The options ``--resume`` compares with the stored batch that were given on the command line or
    through the environment; they are the input folder and the batch options of
    :data:`executor.batch.orchestration.OPTION_FLAGS`, whose names the click parameters share."""
    from executor.batch.orchestration import OPTION_FLAGS

    ctx = click.get_current_context()
    typed = (click.core.ParameterSource.COMMANDLINE, click.core.ParameterSource.ENVIRONMENT)
    given = [name for name in OPTION_FLAGS if ctx.get_parameter_source(name) in typed]
    if ctx.get_parameter_source("input_dirs") in typed:
        given.insert(0, "input_dir")
    return given


def _check_post_run(hooks: Sequence[str]) -> None:
    """Each ``--post-run`` must split into a command line (an empty one would run the job folder)."""
    from executor.children.hooks import split_hook

    for hook in hooks:
        try:
            split_hook(hook)
        except ValueError as exc:
            raise click.UsageError(f"--post-run '{hook}': {exc}") from exc


@click.command(context_settings={**CONTEXT, "allow_interspersed_args": False})
@click.version_option(package_name="scenario-coverage", message="%(prog)s %(version)s")
@click.option("-i", "--input-dir", "input_dirs", multiple=True, type=click.Path(file_okay=False),
              help="Folder with the .sce/.osc files (repeat -i for several folders).")
@click.option("--recursive", is_flag=True, help="Take the scenario files of the input folders' subfolders too.")
@click.option("-o", "--output-dir", required=True, type=click.Path(file_okay=False),
              help="Output folder: <out>/<scenario>/ per job and the merged <out>/test.xml.")
@click.option("-j", "--jobs", "slots", type=JobsType(), default="1", show_default=True,
              help="Jobs run in parallel ('auto': one per usable CPU).")
@click.option("--timeout", type=Seconds(), metavar="S",
              help="Seconds a job may run, counted from its process's start (start-up included); then its "
                   "process group gets SIGTERM, then SIGKILL after --grace.")
@click.option("--grace", type=Seconds(), default=5.0, show_default=True, metavar="S",
              help="Seconds between SIGTERM/SIGINT and SIGKILL.")
@click.option("--retries", type=click.IntRange(min=0), default=0, show_default=True, metavar="K",
              help="Repeat a job up to K times after an infrastructure error (no result, signal, timeout).")
@click.option("--resume", is_flag=True, help="Finish the latest unfinished batch of this output folder.")
@click.option("--shard", type=ShardType(), metavar="i/N", help="Run only the i-th of N subsets (stable hash of file content).")
@click.option("--halt-on-failure", is_flag=True, help="Start no new job after the first job that did not pass.")
@click.option("-r", "--ignore-process-return-value", "ignore_return_value", is_flag=True,
              help="Judge a job by its test.xml alone.")
@click.option("--post-run", multiple=True, metavar="CMD", help="Run 'CMD <job output folder>' after each job.")
@click.option("--enqueue-only", is_flag=True, help="Put the jobs into the (shared) store; 'worker' runs them.")
@click.option("--lease", type=Seconds(0.2), default=60.0, show_default=True, metavar="S",
              help="Seconds a job is held without a heartbeat before another worker may take it.")
@click.option("--wait", is_flag=True,
              help="When another batch writes into the output folder, wait for it instead of stopping.")
@click.option("--simulation", metavar="MODULE:CLASS",
              help="Built-in runner: run every job step-based on this simulation (as scenario_execution "
                   "--simulation); with a launch command, put it in the command instead.")
@click.option("--rerun-failed", is_flag=True,
              help="Run again, as a new batch, the jobs of -o whose latest verdict is not a pass (like pytest "
                   "--lf); the report keeps the latest verdict of every job of -o.")
@click.option("--only-new", is_flag=True,
              help="Run only the files of -i that no earlier batch of -o ran (same path and content), e.g. after "
                   "'scenario_variation --only-new'; the report keeps the earlier verdicts too.")
@click.option("--repeat", type=RepeatType(), default="1", show_default=True,
              help="Run each variant N times, each attempt its own job and folder (<name>@<k>, $SCENARIO_ATTEMPT=k); "
                   "'until-fail:N' stops a variant's attempts at its first failure. The variant's verdict is its "
                   "pass rate against --pass-rate; the JUnit report keeps one testcase per variant.")
@click.option("--pass-rate", type=click.FloatRange(0, 1), default=1.0, show_default=True, metavar="R",
              help="With --repeat: the share of a variant's attempts that must pass for it to pass (0.9: 9 in 10).")
@store_option
@debug_option
@click.argument("command", nargs=-1, type=click.UNPROCESSED)
def run_command(input_dirs: tuple[str, ...], recursive: bool, output_dir: str, slots: int, timeout: float | None,
                grace: float, retries: int, resume: bool, shard: Shard | None, halt_on_failure: bool,
                ignore_return_value: bool, post_run: tuple[str, ...], enqueue_only: bool, lease: float, wait: bool,
                simulation: str | None, rerun_failed: bool, only_new: bool, repeat: tuple[int, bool],
                pass_rate: float, store_url: str | None, debug: bool, command: tuple[str, ...]) -> int:
    """Run CMD once per .sce/.osc file of the input folder; {SCENARIO} and {OUTPUT_DIR} are filled in.

    Without CMD the built-in runner runs each file as 'scenario_execution {SCENARIO} --output-dir
    {OUTPUT_DIR}' would, forked from a process that has the runtime loaded (much faster).

    Subcommands for several hosts sharing one store: worker, status, report (see '<subcommand> --help').
    """
    input_dir = input_dirs[0] if input_dirs else None
    _check_run_options(input_dir=input_dir, command=command, simulation=simulation, resume=resume,
                       rerun_failed=rerun_failed, only_new=only_new, enqueue_only=enqueue_only, post_run=post_run)
    from executor.batch.worker_server import start_early

    # the built-in runner's fork server starts now, so that its imports and preload overlap ours (the store,
    # the inputs); the worker adopts it
    early = start_early(slots) if not (command or resume or rerun_failed or enqueue_only) else None
    try:
        from executor.batch import orchestration
        from executor.batch.progress import make_reporter
        from store.jobs import BatchOptions

        request = orchestration.BatchRequest(
            input_dir=input_dir, output_dir=orchestration.output_folder(output_dir), command=tuple(command),
            options=BatchOptions(timeout=timeout, retries=retries, post_run=tuple(post_run),
                                 ignore_return_value=ignore_return_value, halt_on_failure=halt_on_failure, grace=grace,
                                 simulation=simulation, repeat=repeat[0], until_fail=repeat[1] and repeat[0] > 1,
                                 pass_rate=pass_rate),
            shard=shard, more_inputs=tuple(input_dirs[1:]), recursive=recursive)
        store = _open_store(store_url)
        lock = None
        try:
            if not resume and not enqueue_only:   # --resume joins a batch (the store coordinates); others wait or stop
                lock = _lock_output(request.output_dir, wait)
            batch = _batch_to_run(store, request, output_dir, resume=resume, rerun_failed=rerun_failed,
                                  only_new=only_new, enqueue_only=enqueue_only)
            if isinstance(batch, int):
                return batch
            if enqueue_only:
                count = sum(store.counts(batch.id).values())
                click.echo(f"batch {batch.id}: {count} job(s) queued in {store.url}; run "
                           f"'{PROG} worker --store URL' on each host")
                return 0
            ran = orchestration.run_local(store, batch, slots, make_reporter(slots), lease=lease, early=early)
            return _report_run(store, batch, ran, shard)
        finally:
            store.close()
            if lock is not None:
                lock.release()
    finally:
        if early is not None:
            early.server.close()          # (the worker has closed it already, when it ran)


def _check_run_options(*, input_dir: str | None, command: Sequence[str], simulation: str | None, resume: bool,
                       rerun_failed: bool, only_new: bool, enqueue_only: bool, post_run: Sequence[str]) -> None:
    """The options of a batch run that do not go together, or are missing, are usage errors before anything
    is touched."""
    if simulation and command:
        raise click.UsageError("--simulation is for the built-in runner; with a launch command, pass it in the "
                               "command (-- scenario_execution {SCENARIO} -o {OUTPUT_DIR} --simulation ...)")
    if rerun_failed and (resume or enqueue_only or input_dir is not None or command):
        raise click.UsageError("--rerun-failed takes only -o (and -j, --store): it reruns the jobs of the folder "
                               "that did not pass, with its latest batch's input, command and options")
    if only_new and (resume or rerun_failed):
        raise click.UsageError("--only-new starts a batch of the new files of -i: it does not go with "
                               + ("--resume" if resume else "--rerun-failed"))
    if not resume and not rerun_failed and input_dir is None:
        raise click.UsageError("missing -i/--input-dir")
    if command:                  # none: the built-in runner (scenario_execution forked, not launched)
        _check_command(command)
    _check_post_run(post_run)


def _batch_to_run(store: QueueStore, request: BatchRequest, output_dir: str, *, resume: bool, rerun_failed: bool,
                  only_new: bool, enqueue_only: bool) -> Batch | int:
    """The batch this run works on: the reruns of the folder's failures, its new files, the unfinished batch
    it resumes, or a new batch of the input; or the exit code when there is nothing to run (``output_dir``:
    the output folder as the command line gave it)."""
    from executor.batch import orchestration

    if rerun_failed:
        earlier, rerun = orchestration.rerun_failed_batch(store, request.output_dir)
        if rerun is None:
            click.echo(f"every job of batch {earlier.id} passed: nothing to rerun")
            return 0
        click.echo(f"batch {rerun.id}: rerunning {sum(store.counts(rerun.id).values())} job(s) that did not "
                   f"pass in batch {earlier.id}")
        return rerun
    if only_new:
        made = orchestration.create_only_new_batch(store, request, mode="shared" if enqueue_only else "local")
        if made.batch is None:
            click.echo(f"nothing new: each of the {made.passed_over} scenario file(s) of -i has a verdict in "
                       f"{output_dir} already; nothing ran")
            return orchestration.EXIT_NOTHING_RAN
        if made.earlier is not None:
            click.echo(f"batch {made.batch.id}: {sum(store.counts(made.batch.id).values())} new scenario file(s); "
                       f"{made.passed_over} already have a verdict in batch {made.earlier.id} (the report "
                       "keeps theirs)")
        return made.batch
    if resume:
        return orchestration.resume_batch(store, request.output_dir, request.command, request, _typed_options())
    return orchestration.create_batch(store, request, mode="shared" if enqueue_only else "local")


def _report_run(store: QueueStore, batch: Batch, ran: LocalRun, shard: Shard | None) -> int:
    """Print what the run of ``batch`` left (failures, flaky variants, the summary line, a full disk, an empty
    shard) and return its exit code."""
    from executor.batch import orchestration

    counts, signum = ran.counts, ran.signum
    report: str | None = os.path.join(batch.output_dir, RESULT_FILE)
    _print_failures(store, batch, ran.outcome.listed if ran.outcome is not None else None)
    if ran.outcome is not None:
        from executor.batch.batch_outcome import flaky_lines

        for text in flaky_lines(ran.outcome):
            click.echo(text)
    if ran.report_error is not None:
        report = None
    line = orchestration.summary_line(batch, counts, report, ran.outcome)
    if signum is not None:
        line += "; interrupted, finish with --resume"
    click.echo(line)
    if ran.disk_full is not None:
        click.echo(f"error: no space left on the device holding {ran.disk_full}: the batch stopped; "
                   + (f"{ran.report_error}, " if ran.report_error else "")
                   + f"every finished result is in the store ({store.url}); make room, then run the same "
                   "command with --resume to finish it", err=True)
        return orchestration.EXIT_FAILED if signum is None else orchestration.exit_code(counts, signum)
    if not sum(counts.values()) and signum is None:
        where = f"shard {shard.index}/{shard.count} holds" if shard is not None else "the batch has"
        click.echo(f"warning: {where} no scenario file: nothing ran (exit {orchestration.EXIT_NOTHING_RAN}, as "
                   "pytest exits when it collects no test)", err=True)
    return orchestration.exit_code(counts, signum)


@click.command(context_settings=CONTEXT)
@store_option
@click.option("-j", "--jobs", "slots", type=JobsType(), default="1", show_default=True,
              help="Jobs this worker runs in parallel ('auto': one per usable CPU).")
@click.option("--batch", "batch_id", type=int, help="Only this batch (default: every shared batch).")
@click.option("-o", "--output-dir", "--output-root", "output_root", type=click.Path(file_okay=False),
              help="Put job folders here instead of the batch's output folder (-o means the output folder, as "
                   "for the run itself; --output-root is the older name).")
@click.option("--lease", type=Seconds(0.2), default=60.0, show_default=True, metavar="S",
              help="Seconds a job is held without a heartbeat.")
@click.option("--poll", type=Seconds(0.01), default=1.0, show_default=True, metavar="S",
              help="Seconds between looks at an empty queue.")
@click.option("--wait", "wait_for_work", is_flag=True, help="Keep waiting for new batches (a long-lived pod).")
@debug_option
def worker_command(store_url: str | None, slots: int, batch_id: int | None, output_root: str | None, lease: float,
                   poll: float, wait_for_work: bool, debug: bool) -> int:
    """Run queued jobs of the shared store until none is left."""
    from executor.batch.orchestration import EXIT_INTERRUPTED, run_worker
    from executor.batch.progress import PlainReporter
    from executor.batch.worker import WorkerSettings

    store = _open_store(store_url)
    try:
        if batch_id is not None:
            store.batch(batch_id)
        settings = WorkerSettings(slots=slots, batch_id=batch_id, lease=lease, poll=poll,
                                  output_root=os.path.abspath(output_root) if output_root else None,
                                  wait_for_work=wait_for_work, cwd=os.getcwd())
        summary, signum = run_worker(store, settings, PlainReporter())
    finally:
        store.close()
    if summary.nothing_to_do:
        click.echo("nothing to do: no queued or running job in the store")
    else:
        done = ", ".join(f"{n} {s.value}" for s, n in sorted(summary.verdicts.items())) or "no job finished"
        click.echo(f"worker done: {done}")
    return EXIT_INTERRUPTED.get(signum, 0) if signum is not None else 0


def _pick_batch(store: QueueStore, batch_id: int | None) -> Batch:
    if batch_id is not None:
        return store.batch(batch_id)
    batch = store.latest_batch()
    if batch is None:
        raise BatchError(f"the store {store.url} holds no batch")
    return batch


@click.command(context_settings=CONTEXT)
@store_option
@click.option("--batch", "batch_id", type=int, help="Batch to show (default: the latest).")
@click.option("--list", "list_state", type=click.Choice(["failed", "flaky"]),
              help="List the jobs that did not pass (failed, error, timeout: name, reason and log), or the flaky "
                   "variants (passed and failed, in this batch's attempts or the store's earlier batches).")
@click.option("--json", "as_json", is_flag=True, help="Print the status (and the --list) as JSON, for scripts.")
@debug_option
def status_command(store_url: str | None, batch_id: int | None, list_state: str | None, as_json: bool,
                   debug: bool) -> int:
    """Show jobs per state, running jobs per worker and host, and an ETA."""
    from executor.batch.failure_summary import not_passed_in_store
    from executor.batch.status import render, snapshot

    store = _open_store(store_url, existing=True)
    try:
        batch = _pick_batch(store, batch_id)
        snap = snapshot(store, batch)
        failed = not_passed_in_store(store, batch.id) if list_state == "failed" else None
        flaky = _flaky_records(store, batch) if list_state == "flaky" else None
        if as_json:
            import json

            document: dict[str, object] = {
                "batch": batch.id, "total": snap.total,
                "counts": {state.value: count for state, count in snap.counts.items()},
                "running": [{"host": host, "worker": worker, "jobs": n} for (host, worker), n in snap.running.items()],
                "eta_seconds": snap.eta_seconds}
            if failed is not None:
                document["not_passed"] = [item.as_dict() for item in failed]
            if flaky is not None:
                document["flaky"] = [{"name": r.variant, "passed": r.passed, "not_passed": r.not_passed}
                                     for r in flaky]
            click.echo(json.dumps(document, indent=2))
            return 0
        render(snap, sys.stdout)
        for item in failed or ():
            click.echo(item.line())
        if flaky is not None:
            click.echo(f"{len(flaky)} flaky variant(s)")
        for record in flaky or ():
            click.echo(f"FLAKY    {printable(record.variant)} - {record.text()}")
    finally:
        store.close()
    return 0


@click.command(context_settings=CONTEXT)
@store_option
@click.option("--batch", "batch_id", type=int, help="Batch to report (default: the latest).")
@click.option("-o", "--output", default=RESULT_FILE, show_default=True, type=click.Path(dir_okay=False),
              help="File for the merged JUnit report ('-': standard output).")
@click.option("--json", "as_json", is_flag=True, help="Print the counts and the jobs that did not pass as JSON.")
@debug_option
def report_command(store_url: str | None, batch_id: int | None, output: str, as_json: bool, debug: bool) -> int:
    """Write the merged JUnit report of a batch from the store (exit 0 only if every job passed)."""
    from executor.batch import orchestration

    store = _open_store(store_url, existing=True)
    try:
        batch = _pick_batch(store, batch_id)
        counts = orchestration.write_batch_report(store, batch, output)
        failed = None
        if as_json:
            from executor.batch.failure_summary import not_passed_in_folder

            failed = not_passed_in_folder(store, batch)
    finally:
        store.close()
    if failed is not None:
        import json

        click.echo(json.dumps({"batch": batch.id, "report": output if output == "-" else os.path.abspath(output),
                               "counts": {state.value: count for state, count in counts.items()},
                               "exit_code": orchestration.exit_code(counts),
                               "not_passed": [item.as_dict() for item in failed]}, indent=2))
    else:   # with -o - the report is standard output, and the summary goes to standard error
        click.echo(orchestration.summary_line(batch, counts, output), err=output == "-")
    return orchestration.exit_code(counts)


SUBCOMMANDS = {"worker": worker_command, "status": status_command, "report": report_command}


def _lock_output(folder: str, wait: bool) -> FolderLock:
    """Hold the output folder's lock (executor.output.folder_lock) for the run, or say who holds it."""
    from executor.output.folder_lock import FolderBusy, FolderLock

    try:
        return FolderLock(folder, PROG).acquire(wait, on_wait=lambda text: click.echo(text, err=True))
    except FolderBusy as exc:
        raise BatchError(f"{exc}; nothing was run") from None
    except OSError as exc:
        raise BatchError(f"cannot use the output folder {folder}: {exc.strerror or exc}") from None


def _flaky_records(store: QueueStore, batch: Batch) -> list[VariantRecord]:
    """The flaky variants of ``batch`` with their passes and failures over the store's batches up to it."""
    from executor.batch.flaky import variant_records

    records = variant_records(store, store.jobs(batch.id), batch.id)
    return [record for record in records.values() if record.flaky]


def _print_failures(store: QueueStore, batch: Batch, listed: Sequence[Job] | None = None) -> None:
    """The failures grouped by kind (the triage), then the short summary of the jobs of the folder whose
    latest verdict is not a pass (nothing when all passed); ``listed``: the folder's latest jobs, when known."""
    from executor.batch.failure_summary import not_passed_in_folder, summary_lines, triage

    items = not_passed_in_folder(store, batch, listed)
    for text in triage(store, items) + summary_lines(items):
        click.echo(text)


def _unknown_subcommand(word: str) -> NoReturn:
    """A bare word first is a subcommand or a mistake (the batch run itself takes only options): say which
    subcommands there are, and the nearest one, as click does for a misspelt option."""
    import difflib

    close = difflib.get_close_matches(word, list(SUBCOMMANDS), n=1, cutoff=0.6)
    hint = f" Did you mean '{close[0]}'?" if close else ""
    raise BatchUsageError(f"no such subcommand '{word}' (subcommands: {', '.join(SUBCOMMANDS)}).{hint}")


def main(argv: list[str] | None = None) -> None:
    """Console-script entry point: dispatch to a subcommand or the batch run, map errors to exit codes."""
    args = list(sys.argv[1:] if argv is None else argv)
    command, prog = run_command, PROG
    if args and args[0] in SUBCOMMANDS:
        command, prog = SUBCOMMANDS[args[0]], f"{PROG} {args[0]}"
        args = args[1:]
    boundary = Boundary(prog, one_line_name=PROG, quick_end=True)   # (its jobs run in processes of their own)
    if args and not args[0].startswith("-") and command is run_command:
        word = args[0]
        sys.exit(boundary.guarded(lambda: _unknown_subcommand(word)))
    boundary.main(command, args)


if __name__ == "__main__":
    main()
