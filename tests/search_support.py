"""What the search tests share: a braking scenario whose answer is known by arithmetic, and readers of
what a search leaves in its folder (the verdict and values of every run, per round)."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from pathlib import Path

#: Constant deceleration (m/s²) and reaction time (s) of :data:`BRAKE`.
DECEL, REACTION = 6.0, 1.0

#: A braking test that fails when the stopping distance, speed²/(2·decel) + speed·reaction, is more than
#: the gap. ``{hold}``: how long each run waits before the check (long enough to interrupt a round).
BRAKE = """\
import osc.helpers

scenario brake:
    speed: speed with:
        keep(it in [5mps..30mps])
    gap: length with:
        keep(it in [20m..80m])
    decel: acceleration = 6mpss
    reaction: time = 1s
    record(stop_distance, expression: speed * (speed / (2 * decel) + reaction), unit: m)
    do serial:
        wait elapsed({hold})
        compare(speed * (speed / (2 * decel) + reaction), "<=", gap)
"""


def write_brake(folder: Path, hold: str = "1ms") -> Path:
    """The braking scenario as ``folder/brake.osc``."""
    path = folder / "brake.osc"
    path.write_text(BRAKE.format(hold=hold), encoding="utf-8")
    return path


def fails(speed: float, gap: float) -> bool:
    """Whether the braking test fails at ``speed`` (m/s) and ``gap`` (m): the arithmetic of the scenario."""
    return speed * speed / (2 * DECEL) + speed * REACTION > gap


def round_runs(results: Path) -> list[tuple[str, str, float, float]]:
    """``(job, status, speed, gap)`` of every testsuite of a round's merged ``test.xml``."""
    runs = []
    for suite in ET.parse(results / "test.xml").getroot().iter("testsuite"):
        properties = {p.get("name"): p.get("value") for p in suite.iter("property")}
        runs.append((suite.get("name") or "", properties["status"], float(properties["variation.brake.speed"]),
                     float(properties["variation.brake.gap"])))
    return runs


def search_file(folder: Path) -> dict:
    """The search's own ``search.json``."""
    return json.loads((folder / "search.json").read_text(encoding="utf-8"))
