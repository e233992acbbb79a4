"""A "foreign" batch child: not our runtime, only the file formats. Run as ``python coverage_child.py SCENARIO OUT``.

It reads the variant's assignment from the ``.sce`` (YAML), pretends to drive a cut-in, and writes a
JUnit ``test.xml`` and a ``coverage.json`` by hand (plain ``json``, none of our code), the way a
simulator wrapper in any language would. Deterministic, from the assignment alone:

* the run fails when ``gap`` is 5; it crashes (exit 3, no files) when ``speed`` is 30 and ``gap`` 10;
* ``ego_speed`` (end) = speed x 3.6 kph; ``cut_side`` (end) = the lane; ``speed_x_side`` their cross —
  ``end`` items are not sampled in a failing run;
* ``lateral_offset`` (finish, kept in failing runs) = 0 when failing (3, outside its range, at speed 30),
  else -1 left / 1 right; ``min_ttc`` (record, finish) = gap x 10 / speed, + 0.1 on the right lane.
"""

from __future__ import annotations

import json
import os
import sys

import yaml


def main() -> int:
    scenario, out = sys.argv[1], sys.argv[2]
    with open(scenario, encoding="utf-8") as handle:
        assignment = yaml.safe_load(handle)["assignment"]
    speed, gap, lane = assignment["cut_in.speed"], assignment["cut_in.gap"], assignment["cut_in.lane"]
    side = lane.split("!")[-1]
    if speed == 30 and gap == 10:
        print("simulator crashed", file=sys.stderr)
        return 3
    failed = gap == 5
    os.makedirs(out, exist_ok=True)
    end = [] if failed else None
    offset = (3 if speed == 30 else 0) if failed else (-1 if side == "left" else 1)
    items = [
        {"name": "ego_speed", "kind": "cover", "path": "cut_in", "type": "float", "unit": "kph",
         "range": [0, 150], "every": 25, "event": "end", "text": "ego speed when the cut-in ends",
         "samples": end if end is not None else [speed * 3.6]},
        {"name": "cut_side", "kind": "cover", "path": "cut_in", "type": "enum", "members": ["left", "right", "center"],
         "event": "end", "samples": end if end is not None else [side]},
        {"name": "speed_x_side", "kind": "cover", "path": "cut_in", "items": ["ego_speed", "cut_side"],
         "event": "end", "samples": end if end is not None else [[speed * 3.6, side]]},
        {"name": "lateral_offset", "kind": "cover", "path": "cut_in", "type": "int", "unit": "m", "range": [-2, 2],
         "every": 1, "event": "finish", "samples": [offset]},
        {"name": "min_ttc", "kind": "record", "path": "cut_in", "type": "float", "unit": "s", "event": "finish",
         "samples": [gap * 10 / speed + (0.1 if side == "right" else 0.0)]},
    ]
    variant = os.path.splitext(os.path.basename(scenario))[0]
    document = {"format": "scenario-coverage/run", "format_version": 1,
                "run": {"scenario": "cut_in", "source": scenario, "variant": variant, "assignment": assignment,
                        "verdict": "failed" if failed else "passed",
                        "reason": "cut-in too close" if failed else None},
                "items": items}
    with open(os.path.join(out, "coverage.json"), "w", encoding="utf-8") as handle:
        json.dump(document, handle)
    failure = '<failure message="cut-in too close" type="failure"/>' if failed else ""
    with open(os.path.join(out, "test.xml"), "w", encoding="utf-8") as handle:
        handle.write('<?xml version="1.0"?><testsuites><testsuite name="child" tests="1">'
                     f'<testcase name="cut_in" classname="child">{failure}</testcase></testsuite></testsuites>')
    print(f"cut-in at {speed} m/s, gap {gap} m, {side}: {'failed' if failed else 'passed'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
