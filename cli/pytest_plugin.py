"""pytest plugin: ``pytest --osc DIR_OR_FILE`` collects scenarios and variants as test items.

Registered through the ``pytest11`` entry point, so it is loaded by every pytest run where this
package is installed; it does nothing unless ``--osc`` is given (it only adds its options, and imports
nothing of ours until it collects). With ``--osc``:

- every ``.osc`` file (one item per file, named after its scenario) and every ``.sce`` variant (named
  after the variant) under the given paths is a test item; with no other path on the command line,
  only those are collected;
- an item runs ``scenario_execution FILE --output-dir <--osc-output>/<item>`` in a subprocess of its own
  process group (a crash, a hang or a leaked global cannot touch pytest or the next item; at
  ``--osc-timeout`` the whole group gets SIGTERM, then SIGKILL), and passes when the scenario does; each
  item's folder is its own (a short hash of its id is added where two ids read alike);
- a failure is reported with the scenario's own located message (``file:line:col``, the failing
  action) and the end of the run's log;
- everything pytest offers applies: ``-k``, ``-x``, ``--lf``, ``--junitxml``, ``-n auto``
  (pytest-xdist), IDE runners; ``cover()`` samples land in each item's ``coverage.json``.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

from coverage_engine.results.files import LOG_FILE, RESULT_FILE
from coverage_engine.suffixes import OSC_SUFFIX, SCENARIO_SUFFIXES

if TYPE_CHECKING:   # pytest's own types for repr_failure (not exported under a public name)
    from _pytest._code.code import TerminalRepr, TracebackStyle

#: Lines of a failing run's log shown under its message.
LOG_TAIL_LINES = 30
#: Seconds a timed-out scenario's process group has between SIGTERM and SIGKILL.
GRACE = 5.0


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("osc", "OpenSCENARIO DSL scenarios (scenario-coverage)")
    group.addoption("--osc", action="append", default=[], metavar="PATH",
                    help="collect every .osc scenario and .sce variant under PATH as a test (repeatable)")
    group.addoption("--osc-output", default="osc-results", metavar="DIR",
                    help="folder for each scenario run's output (test.xml, log.txt, coverage.json) [osc-results]")
    group.addoption("--osc-timeout", type=float, default=600.0, metavar="S",
                    help="seconds a scenario may run before it fails [600]")


def pytest_configure(config: pytest.Config) -> None:
    paths = config.getoption("osc")
    if not paths:
        return
    roots = [Path(p).resolve() for p in paths]
    missing = [p for p, r in zip(paths, roots, strict=True) if not r.exists()]
    if missing:
        raise pytest.UsageError(f"--osc {missing[0]}: no such file or folder")
    config.stash[_ROOTS] = roots
    if not config.option.file_or_dir:         # only the scenarios, not the project's own tests
        config.args[:] = [str(r) for r in roots]
    else:
        config.args.extend(str(r) for r in roots)


_ROOTS = pytest.StashKey[list]()


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    roots = parent.config.stash.get(_ROOTS, None)
    if not roots or file_path.suffix not in SCENARIO_SUFFIXES:
        return None
    resolved = file_path.resolve()
    if not any(resolved == root or root in resolved.parents for root in roots):
        return None
    return ScenarioFile.from_parent(parent, path=file_path)


class ScenarioFile(pytest.File):
    """A scenario file: one item, named after its scenario (``.osc``) or variant (``.sce``)."""

    def collect(self) -> Iterator[ScenarioItem]:
        yield ScenarioItem.from_parent(self, name=_item_name(self.path))


def _item_name(path: Path) -> str:
    """The scenario's name for an ``.osc`` with exactly one scenario, else the file's stem."""
    if path.suffix == OSC_SUFFIX:
        try:
            from coverage_engine.parse.parser import parse_text
            from coverage_engine.variation.dimensions import scenario_names

            names = scenario_names(parse_text(path.read_text(encoding="utf-8"), str(path)))
            if len(names) == 1:
                return names[0]
        except Exception:  # noqa: BLE001 - a file that does not parse still becomes an item (and fails with why)
            pass
    return path.stem


class ScenarioFailed(Exception):
    """The scenario failed; carries its located message and the end of its log."""

    def __init__(self, message: str, log_tail: str) -> None:
        super().__init__(message)
        self.message = message
        self.log_tail = log_tail


class ScenarioItem(pytest.Item):
    """One scenario run through ``scenario_execution`` in a subprocess."""

    #: The item's folder under ``--osc-output`` (set at collection: unique among the collected items).
    folder = ""

    def runtest(self) -> None:
        """Run the scenario in its own process group (the log written straight into ``log.txt``); at the
        timeout the whole group gets SIGTERM, then SIGKILL after the grace, as a batch job's does."""
        from executor.children.process import ChildProcess

        config = self.config
        output = Path(config.getoption("osc_output")).resolve() / (self.folder or _readable(self.nodeid))
        output.mkdir(parents=True, exist_ok=True)
        command = [sys.executable, "-m", "cli.scenario_execution", str(self.path), "--output-dir", str(output)]
        root = str(Path(__file__).resolve().parent.parent)
        env = {"NO_COLOR": "1", "PYTHONUNBUFFERED": "1",
               "PYTHONPATH": os.pathsep.join(p for p in (root, os.environ.get("PYTHONPATH")) if p)}
        timeout = config.getoption("osc_timeout")
        child = ChildProcess(command, str(output / LOG_FILE), cwd=str(self.path.parent), timeout=timeout,
                             grace=GRACE, environment=env)
        child.start()
        try:
            outcome = child.wait()
        except BaseException:               # Ctrl-C of pytest: the scenario's whole group ends too
            child.cancel(0)
            child.wait()
            raise
        log = (output / LOG_FILE).read_bytes().decode("utf-8", "replace")
        if outcome.timed_out:
            raise ScenarioFailed(f"timed out after {timeout:g} s", _tail(log))
        if outcome.returncode != 0:
            raise ScenarioFailed(_failure_message(output / RESULT_FILE, log), _tail(log))

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException],
                     style: TracebackStyle | None = None) -> str | TerminalRepr:
        if isinstance(excinfo.value, ScenarioFailed):
            failure = excinfo.value
            return f"{failure.message}\n\n--- end of the run's log ---\n{failure.log_tail}"
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self) -> tuple[Path, None, str]:
        return self.path, None, f"scenario {self.name}"


def _readable(nodeid: str) -> str:
    """The item's id with every character but letters, digits, ``-``, ``_`` and ``.`` written ``_``."""
    return "".join(c if c.isalnum() or c in "-_." else "_" for c in nodeid)[-150:]


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Give each scenario item its folder: the readable id, with a short hash of the full id appended
    where two items' readable ids are the same (``x y.osc`` and ``x_y.osc``). Every pytest-xdist worker
    collects the same items before any is deselected, so each names an item's folder alike."""
    import hashlib
    from collections import Counter

    scenario_items = [item for item in items if isinstance(item, ScenarioItem)]
    counts = Counter(_readable(item.nodeid) for item in scenario_items)
    for item in scenario_items:
        readable = _readable(item.nodeid)
        if counts[readable] > 1:
            readable = readable[-140:] + "-" + hashlib.sha256(item.nodeid.encode("utf-8", "surrogateescape")
                                                              ).hexdigest()[:8]
        item.folder = readable


def _failure_message(report: Path, log: str) -> str:
    """The first failure or error message of the run's ``test.xml`` (it holds the location), else the log's
    last error line."""
    from coverage_engine.results.read import JunitUnreadable, read_cases

    try:
        for case in read_cases(report.read_text(encoding="utf-8", errors="replace")):
            if case.problem and case.message:
                return f"{case.name}: {case.message}"
    except (OSError, JunitUnreadable):      # no readable report: fall back to the log
        pass
    errors = [line for line in log.splitlines() if "error" in line.lower()]
    return errors[-1] if errors else "the scenario failed (see its log)"


def _tail(log: str) -> str:
    return "\n".join(log.rstrip("\n").splitlines()[-LOG_TAIL_LINES:])
