"""``scenario_variation``: expand the ``keep(… in [...])`` constraints of an ``.osc`` into concrete ``.sce`` files.

Thin click command: options in, a :class:`~executor.variation.request.VariationRequest` to
:mod:`executor.variation` out; errors become one ``file:line:col: error: …`` message and an exit code
in :mod:`cli.boundary`. Only click is imported at start-up; the front end, rich and SQLAlchemy are
imported when needed, so ``-h`` and errors are quick.

Exit codes: 0 every combination was generated · 1 the input is wrong, the store cannot be used,
more combinations than ``--max-variants``, or some combinations did not resolve (they are reported
and skipped, the others are written) · 2 usage error · 130 interrupted (SIGINT or SIGTERM; the files
written so far are all recorded in the store).
"""

from __future__ import annotations

import click

from cli.boundary import Boundary
from cli.options import debug_option, goal_options, store_option
from coverage_engine.search import ADAPTIVE
from coverage_engine.suffixes import OSC_SUFFIX
from executor.variation.request import DEFAULT_MAX_VARIANTS, VariationRequest
from executor.variation.writing import VariationStoreError

#: --strategy values (coverage_engine.variation.strategies.STRATEGIES, spelled here so -h imports nothing more,
#: then the adaptive strategies of --from).
STRATEGIES = ("full", "pairwise", "t-way", "random", "lhs", "halton", "sobol", *ADAPTIVE)


@click.command(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="scenario-coverage", message="%(prog)s %(version)s")
@click.option("-o", "-t", "--output-dir", default="out", show_default=True, type=click.Path(file_okay=False),
              help="Directory for the generated .sce files (-t is an alias). Earlier .sce files there are replaced.")
@debug_option
@click.option("-l", "--log-model", is_flag=True, help="Print the resolved model of each generated variant.")
@click.option("--list", "list_only", is_flag=True,
              help="Print the assignments that would be generated; write nothing.")
@store_option
@click.option("--scenario-parameter-file", type=click.Path(dir_okay=False),
              help="YAML file of scenario parameter values; each document is one more dimension.")
@click.option("--max-variants", type=click.IntRange(min=1), default=DEFAULT_MAX_VARIANTS, show_default=True,
              metavar="N", help="Refuse to start when the file has more combinations than N.")
@click.option("--strategy", type=click.Choice(STRATEGIES), default="full", show_default=True,
              help="Which combinations: the full product, a covering array (pairwise, t-way), a seeded "
                   "sample (random, lhs, halton, sobol), or proposals from earlier results (boundary, fill-holes, "
                   "falsify; with --from).")
@click.option("--strength", type=click.IntRange(min=2), default=2, show_default=True, metavar="T",
              help="t-way: every combination of values of any T dimensions appears in some variant.")
@click.option("--samples", type=click.IntRange(min=1, max=10_000_000), metavar="N",
              help="random/lhs/halton/sobol: how many variants to draw.")
@click.option("--seed", type=click.IntRange(min=0, max=2**63 - 1), metavar="S",
              help="Seed of pairwise/t-way/sampling (the same seed gives the same variants); chosen and printed "
                   "when left out.")
@click.option("--wait", is_flag=True,
              help="When another run writes into the output folder, wait for it instead of stopping.")
@click.option("--only-new", is_flag=True,
              help="Add to earlier runs of the same file in the output folder: write only variants the store does "
                   "not hold yet (a sampler continues its draw, a covering array its rows).")
@click.option("--from", "from_results", multiple=True, type=click.Path(file_okay=False), metavar="RESULTS",
              help="Results folder of earlier runs of the same file (repeatable): boundary, fill-holes and falsify "
                   "propose the next variants from them. With --store on the command line, the batches of that "
                   "store written into these folders are read instead (the folders need not be on this host).")
@goal_options
@click.option("--round", "round_number", type=click.IntRange(min=1), metavar="N",
              help="The round written in each variant's proposal line (default: one more than the highest read).")
@click.argument("scenarios", nargs=-1, required=True, type=click.Path())
@click.pass_context
def command(ctx: click.Context, scenarios: tuple[str, ...], output_dir: str, debug: bool, log_model: bool,
            list_only: bool, store_url: str | None, scenario_parameter_file: str | None, max_variants: int,
            strategy: str, strength: int, samples: int | None, seed: int | None, wait: bool, only_new: bool,
            from_results: tuple[str, ...], objective: str | None, maximise: bool, threshold: float | None,
            resolution: float, pass_rate: float | None, along: str | None, round_number: int | None) -> int:
    """Generate concrete scenarios (.sce) from the values listed or ranged in each SCENARIO (.osc file, or a
    folder: its .osc files).

    Every keep(it.<param> in [v1, v2, ...]) or keep(it.<param> in [low..high]) is one dimension; with the
    default --strategy full every combination is written, the first dimension varying slowest.
    """
    from coverage_engine.errors import OscError
    from coverage_engine.search.target import SearchTarget
    from executor.variation.generation import run

    files = _scenario_files(scenarios)
    code = 0
    for scenario in files:
        request = VariationRequest(
            scenario=scenario, output_dir=output_dir, parameter_file=scenario_parameter_file, list_only=list_only,
            log_model=log_model, debug=debug, store=store_url, max_variants=max_variants, strategy=strategy,
            strength=strength, samples=samples, seed=seed, wait=wait, only_new=only_new,
            from_results=tuple(from_results),
            target=SearchTarget(objective, maximise, threshold, resolution, pass_rate, along),
            round_number=round_number, from_store=bool(from_results) and _store_named())
        if len(files) == 1:
            return run(request)
        try:                     # several files: each is done on its own; one that fails stops only itself
            code = max(code, run(request))
        except (OscError, VariationStoreError, OSError) as exc:
            code = max(code, ctx.obj.report(exc))
    return code


def _store_named() -> bool:
    """Whether ``--store`` is on the command line: then ``--from`` is read from that store, as
    ``scenario_coverage report RESULTS --store URL`` reads it (``$SCENARIO_STORE`` alone does not)."""
    source = click.get_current_context().get_parameter_source("store_url")
    return source is click.core.ParameterSource.COMMANDLINE


def _scenario_files(given: tuple[str, ...]) -> list[str]:
    """The files to vary: each file as given, each folder's ``.osc`` files in name order."""
    from pathlib import Path

    files: list[str] = []
    for item in given:
        path = Path(item)
        if path.is_dir():
            found = sorted(str(p) for p in path.iterdir() if p.suffix == OSC_SUFFIX and p.is_file())
            if not found:
                raise click.UsageError(f"{item}: a folder without .osc files")
            files += found
        else:
            files.append(item)
    return files


def main(args: list[str] | None = None) -> None:
    """Console script entry point."""
    Boundary("scenario_variation").main(command, args)


if __name__ == "__main__":  # pragma: no cover
    main()
