"""One root for every error a user can cause (issue 34 item 6): each package's errors derive from
``UserError``, ``cli/boundary.py`` alone turns one into its message and exit code, and a location of a
file as a whole is its own kind (``file: error: …``, never ``file:0:0``)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import click
import pytest
from cli_support import EXE, run_cli

from cli.boundary import EXIT_FAILED, EXIT_USAGE, Boundary
from coverage_engine.coverage.errors import ResultsError
from coverage_engine.errors import OscError, UserError
from coverage_engine.location import Location
from coverage_engine.resolve.evaluate import EvaluationError
from executor.actions.base import ActionError
from executor.batch.errors import BadShard, BatchError
from executor.runtime.pipeline import UsageProblem
from executor.runtime.simulation import SimulationError
from executor.variation.writing import VariationStoreError
from store.database import StoreError, StoreMissing
from store.queue import StoreUnavailable


@pytest.mark.parametrize("error", [OscError, ResultsError, StoreError, StoreMissing, StoreUnavailable, BatchError,
                                   BadShard, UsageProblem, VariationStoreError, EvaluationError, ActionError,
                                   SimulationError])
def test_every_package_roots_its_user_errors_in_one_class(error):
    assert issubclass(error, UserError)
    assert error("it went wrong").message == "it went wrong"


def test_only_malformed_command_lines_are_usage_errors():
    assert StoreMissing.usage and BadShard.usage
    assert not StoreError.usage and not BatchError.usage and not OscError.usage and not UsageProblem.usage


def test_the_message_alone_is_str_so_it_can_be_wrapped_but_a_file_error_says_where():
    where = Location("a.osc", 3, 7)
    assert str(StoreError("no store", where)) == "no store"
    assert str(OscError("bad", where)) == "a.osc:3:7: error: bad"
    assert StoreError("no store", where).located() == "a.osc:3:7: error: no store"
    assert BatchError().located() == "error: The batch cannot be run as asked."


def test_a_whole_file_location_has_no_line_or_column():
    whole = Location.whole_file("plan.yaml")
    assert whole.is_whole_file and not Location("plan.yaml", 1, 1).is_whole_file
    assert str(whole) == "plan.yaml"
    assert OscError("not UTF-8 text", whole).render() == "plan.yaml: error: not UTF-8 text"
    assert Location.at("plan.yaml", 0, 0) == whole
    assert str(Location.at("plan.yaml", 2, 5)) == "plan.yaml:2:5"


def _run(error: BaseException, one_line: bool = False) -> int:
    @click.command()
    def fails() -> None:
        raise error

    return Boundary("prog", one_line_name="prog" if one_line else None).run(fails, [])


def test_the_boundary_says_a_user_error_with_its_place_and_caret_and_exits_1(capsys):
    error = OscError("unknown name 'x'", Location("s.osc", 2, 8), source_line="    do x()", hint="did you mean y?")
    assert _run(error) == EXIT_FAILED
    assert capsys.readouterr().err.splitlines() == [
        "s.osc:2:8: error: unknown name 'x'", "        do x()", "           ^", "hint: did you mean y?"]


def test_the_boundary_exits_2_for_a_usage_error_and_keeps_one_line_when_asked(capsys):
    assert _run(StoreMissing("there is no store at /x.db"), one_line=True) == EXIT_USAGE
    assert capsys.readouterr().err == "prog: error: there is no store at /x.db\n"
    assert _run(UsageProblem("--step-duration must be positive")) == EXIT_FAILED
    assert capsys.readouterr().err == "error: --step-duration must be positive\n"


def test_a_missing_parameter_file_is_named_as_a_whole_file(tmp_path: Path):
    (tmp_path / "s.osc").write_text("import osc.helpers\nscenario s:\n    do log('ran')\n", encoding="utf-8")
    done = run_cli("s.osc", "--scenario-parameter-file", "missing.yaml", "-n", cwd=tmp_path)
    assert done.returncode == 1
    assert done.stdout.strip() == "missing.yaml: error: scenario parameter file not found"


def test_a_misspelt_batch_subcommand_is_one_usage_error_line(tmp_path: Path):
    batch = Path(EXE).with_name("scenario_batch_execution")
    done = subprocess.run([str(batch), "wroker"], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert done.returncode == EXIT_USAGE
    assert done.stderr == ("scenario_batch_execution: error: no such subcommand 'wroker' "
                           "(subcommands: worker, status, report). Did you mean 'worker'?\n")
