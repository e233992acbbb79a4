"""``-t/--live-tree``: a rich live view of the tree with each behaviour's status, updated per tick.

Redraws are limited to about ten per second, so a fast step-based run is not slowed down by the
terminal.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:   # py_trees and rich are imported when the live view starts
    from py_trees.behaviour import Behaviour


class LiveTree:
    """Owns one ``rich.live.Live``; :meth:`observers` gives the tick observer for a scenario run."""

    def __init__(self, refresh_per_second: float = 10.0) -> None:
        from rich.console import Console
        from rich.live import Live

        self.console = Console()
        self.live = Live(console=self.console, refresh_per_second=refresh_per_second, transient=False,
                         redirect_stdout=True, redirect_stderr=True)
        self.interval = 1.0 / refresh_per_second
        self.last = 0.0
        self.started = False

    def observers(self, run_name: str) -> list[Callable[[Behaviour], None]]:
        """The observers for one scenario run (called by the session before the run)."""
        self.last = 0.0
        return [lambda root: self.show(run_name, root)]

    def show(self, run_name: str, root: Behaviour, force: bool = False) -> None:
        now = time.monotonic()
        if not force and now - self.last < self.interval and root.status.name == "RUNNING":
            return
        self.last = now
        import py_trees
        from rich.panel import Panel
        from rich.text import Text

        tree = py_trees.display.unicode_tree(root, show_status=True)
        if not self.started:
            self.live.start()
            self.started = True
        self.live.update(Panel(Text.from_ansi(tree), title=run_name, subtitle=root.status.name))

    def close(self) -> None:
        if self.started:
            self.live.stop()
            self.started = False
