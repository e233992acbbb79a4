"""Python side of the flaky example: a draw seeded with the attempt number, so each attempt of
``--repeat`` gets its own value and every rerun of the batch the same ones."""

import os
import random


def draw() -> float:
    """A number in [0, 1) from a generator seeded with ``$SCENARIO_ATTEMPT`` (0 when not repeated)."""
    return random.Random("seed-" + os.environ.get("SCENARIO_ATTEMPT", "0")).random()
