"""``scenario_search``: vary, run, read the results, vary again — until ``--budget`` runs or the goal is met.

    scenario_search SCENARIO --goal boundary|fill-holes|falsify [--budget N] [--round N] [-j N] -o DIR
                    [--timeout S] [--seed S] [--objective NAME|margin] [--store URL] [-- CMD {SCENARIO} {OUTPUT_DIR}]
    scenario_search --resume -o DIR

Thin click command: options in, a :class:`~executor.search.request.SearchRequest` to
:mod:`executor.search` out; errors become one message and an exit code in :mod:`cli.boundary`.

Exit codes: 0 the search ran to its end (failures found or not: finding them is its purpose) · 1 the
input is wrong, a round could not be written or run, the store cannot be used · 2 usage error · 130/143
interrupted by SIGINT/SIGTERM (``--resume`` continues).
"""

from __future__ import annotations

import click

from cli.boundary import Boundary
from cli.options import Seconds, debug_option, goal_options, store_option
from cli.scenario_batch_execution import JobsType
from coverage_engine.search import ADAPTIVE

PROG = "scenario_search"


#: Defaults of --budget and --round.
DEFAULT_BUDGET = 200
DEFAULT_ROUND = 40

#: The settings --resume compares with the search's own (the click parameters share these names).
SETTING_OPTIONS = ("scenario", "goal", "budget", "round_size", "seed", "objective", "maximise", "threshold",
                   "resolution", "pass_rate", "along", "command", "timeout", "grace", "retries", "simulation")


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="scenario-coverage", message="%(prog)s %(version)s")
@click.option("-o", "--output-dir", required=True, type=click.Path(file_okay=False),
              help="Folder of the search: search.json and one folder per round (roundN/variants, roundN/results).")
@click.option("--goal", type=click.Choice(ADAPTIVE), default="boundary", show_default=True,
              help="What the rounds after the first look for: where pass turns to fail, the coverage holes, or "
                   "a failure (the worst value of --objective).")
@click.option("--budget", type=click.IntRange(min=1), default=DEFAULT_BUDGET, show_default=True, metavar="N",
              help="Runs in all: the search stops when it has spent them (or when the goal is met).")
@click.option("--round", "round_size", type=click.IntRange(min=1), default=DEFAULT_ROUND, show_default=True,
              metavar="N", help="Variants a round runs (the last round runs what is left of the budget).")
@click.option("-j", "--jobs", "slots", type=JobsType(), default="1", show_default=True,
              help="Jobs run in parallel ('auto': one per usable CPU).")
@click.option("--timeout", type=Seconds(), metavar="S", help="Seconds a job may run (as scenario_batch_execution).")
@click.option("--grace", type=Seconds(), default=5.0, show_default=True, metavar="S",
              help="Seconds between SIGTERM/SIGINT and SIGKILL of a job.")
@click.option("--retries", type=click.IntRange(min=0), default=0, show_default=True, metavar="K",
              help="Repeat a job up to K times after an infrastructure error (no result, signal, timeout).")
@click.option("--simulation", metavar="MODULE:CLASS",
              help="Built-in runner: run every job step-based on this simulation.")
@click.option("--seed", type=click.IntRange(min=0, max=2**62), metavar="S",
              help="Seed of the search (round N draws with S+N-1); chosen and printed when left out.")
@goal_options
@click.option("--resume", is_flag=True,
              help="Continue the search of -o where it stopped (Ctrl-C, a lost machine), with the scenario, goal, "
                   "seed, command and job limits it was started with (a larger --budget runs more rounds).")
@click.option("--lease", type=Seconds(0.2), default=60.0, show_default=True, metavar="S",
              help="Seconds a job is held without a heartbeat before another worker may take it.")
@click.option("--enqueue-only", is_flag=True,
              help="Queue each round's jobs in the shared store (--store) for 'scenario_batch_execution worker' "
                   "on other hosts; the search runs none and waits for each round before proposing the next.")
@click.option("--wait", is_flag=True, help="When another search uses -o, wait for it instead of stopping.")
@store_option
@debug_option
@click.argument("scenario", required=False, type=click.Path(dir_okay=False))
@click.argument("command", nargs=-1, type=click.UNPROCESSED)
def command(output_dir: str, goal: str, budget: int, round_size: int, slots: int, timeout: float | None,
            grace: float, retries: int, simulation: str | None, seed: int | None, objective: str | None,
            maximise: bool, threshold: float | None, resolution: float, pass_rate: float | None,
            along: str | None, resume: bool, lease: float, enqueue_only: bool,
            wait: bool,
            store_url: str | None, debug: bool, scenario: str | None, command: tuple[str, ...]) -> int:
    """Search the values of SCENARIO (.osc) round by round: round 1 samples its ranges, each later round
    proposes variants from the results of the rounds before it (--goal), until --budget runs are spent or
    the goal is met. Each round is a variation and a batch, as scenario_variation and
    scenario_batch_execution make them; with '-- CMD {SCENARIO} {OUTPUT_DIR}' each job runs CMD instead of
    the built-in runner.
    """
    import os

    from coverage_engine.search.target import SearchTarget
    from executor.search.loop import run_search
    from executor.search.request import SearchRequest, SearchSettings

    if scenario is None and not resume:
        raise click.UsageError("missing SCENARIO (the .osc file to search; only --resume goes without it)")
    if simulation and command:
        raise click.UsageError("--simulation is for the built-in runner; with a launch command, pass it in the "
                               "command")
    if command:
        from executor.batch.errors import BadCommand
        from executor.batch.inputs import check_command

        try:
            check_command(command, require_executable=False)
        except BadCommand as exc:
            raise click.UsageError(str(exc)) from exc
    if seed is None and not resume:
        import secrets

        seed = secrets.randbelow(2**31)
    settings = SearchSettings(scenario=os.path.abspath(scenario) if scenario else "", goal=goal, budget=budget,
                              round_size=round_size, seed=seed or 0,
                              target=SearchTarget(objective, maximise, threshold, resolution, pass_rate, along),
                              command=tuple(command),
                              timeout=timeout, grace=grace, retries=retries, simulation=simulation)
    ctx = click.get_current_context()
    typed = (click.core.ParameterSource.COMMANDLINE, click.core.ParameterSource.ENVIRONMENT)
    given = tuple(name for name in SETTING_OPTIONS if ctx.get_parameter_source(name) in typed)
    request = SearchRequest(settings=settings, output_dir=output_dir, slots=slots, lease=lease, store=store_url,
                            resume=resume, wait=wait, debug=debug, typed=given,
                            enqueue_only=enqueue_only)
    return run_search(request)


def main(args: list[str] | None = None) -> None:
    """Console script entry point."""
    Boundary(PROG).main(command, args)


if __name__ == "__main__":  # pragma: no cover
    main()
