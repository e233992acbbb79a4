"""``--dot``: write each scenario's behaviour tree as ``<scenario>.dot`` (plus png/svg with Graphviz)."""

from __future__ import annotations

import os
import shutil
import subprocess
from collections.abc import Sequence

from executor.runtime.logger import Logger
from executor.runtime.planned_runs import PlannedRun


def write_dot_files(runs: Sequence[PlannedRun], directory: str, logger: Logger) -> list[str]:
    """Write one ``.dot`` per distinct scenario name into ``directory``; returns the paths written."""
    import py_trees

    from executor.runtime.builder import build_tree
    from executor.runtime.context import ScenarioContext
    from executor.runtime.simulation import WallClock

    os.makedirs(directory, exist_ok=True)
    graphviz = shutil.which("dot")
    written: list[str] = []
    seen: set[str] = set()
    for run in runs:
        if run.scenario.name in seen:
            continue
        seen.add(run.scenario.name)
        context = ScenarioContext(name=run.scenario.name, clock=WallClock(), logger=logger)
        root = build_tree(run.scenario, context)
        text = py_trees.display.dot_tree(root).to_string()
        base = os.path.join(directory, run.scenario.name.lower())
        with open(base + ".dot", "w", encoding="utf-8") as out:
            out.write(text)
        written.append(base + ".dot")
        if graphviz:
            for fmt in ("png", "svg"):
                done = subprocess.run([graphviz, f"-T{fmt}", base + ".dot", "-o", f"{base}.{fmt}"],
                                      capture_output=True, text=True)
                if done.returncode == 0:
                    written.append(f"{base}.{fmt}")
                else:
                    logger.warning(f"dot -T{fmt} failed: {done.stderr.strip()}")
        logger.info(f"Wrote {', '.join(os.path.relpath(p) for p in written[-3:] if p.startswith(base))}")
    if not graphviz:
        logger.info("Graphviz 'dot' not found: wrote .dot files only (install graphviz for png/svg)")
    return written
