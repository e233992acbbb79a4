"""The outcome of one executed scenario, as written to ``test.xml``."""

from __future__ import annotations

#: The JUnit property of a run holding how close its closest ``compare`` came to flipping (relative: the
#: difference over the larger magnitude; negative when a check failed), what ``--objective margin`` reads.
CHECK_MARGIN_PROPERTY = "check.margin"


class ScenarioResult:
    """``passed`` or not; on failure a one-line ``message`` and ``output`` (the last tree snapshot).

    ``skipped``: the scenario never started (the session was aborted before it); ``message`` says why.
    ``error``: the scenario could not run at all (its output folder could not be made, say): an error,
    not a failure of the scenario, in ``test.xml``.

    A plain class rather than a dataclass: it is imported on every run, where start-up time counts.
    """

    __slots__ = ("name", "passed", "message", "output", "duration", "start_time", "output_dir", "aborted",
                 "skipped", "error", "properties")

    def __init__(self, name: str, passed: bool, message: str = "", output: str = "", duration: float = 0.0,
                 start_time: float = 0.0, output_dir: str | None = None, aborted: bool = False,
                 skipped: bool = False, error: bool = False) -> None:
        self.name = name
        self.passed = passed
        self.message = message
        self.output = output
        self.duration = duration
        self.start_time = start_time
        self.output_dir = output_dir
        self.aborted = aborted
        self.skipped = skipped
        self.error = error
        #: JUnit properties of the run (one per coverage item sampled, and its check margin), added to its suite's.
        self.properties: dict[str, str] = {}

    def __repr__(self) -> str:
        state = "passed" if self.passed else f"{'skipped' if self.skipped else 'failed'}: {self.message}"
        return f"ScenarioResult({self.name!r}, {state})"
