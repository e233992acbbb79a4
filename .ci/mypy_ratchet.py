"""Run mypy and fail when a package has more type errors than ``.ci/mypy-ratchet.txt`` allows.

The allowed counts may only shrink: a change that fixes errors lowers the number in the file (this
script says so), a change that adds errors fails CI. Run from the repository root:
``python .ci/mypy_ratchet.py``.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

RATCHET = Path(__file__).with_name("mypy-ratchet.txt")
ERROR = re.compile(r"^(?P<path>[^:\s]+\.py):\d+: error: ")


def allowed_counts(text: str) -> dict[str, int]:
    """``package count`` per line; ``#`` starts a comment."""
    counts = {}
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        if line:
            package, number = line.split()
            counts[package] = int(number)
    return counts


def found_counts(mypy_output: str) -> Counter[str]:
    """Errors per top-level package in mypy's output."""
    return Counter(Path(m["path"]).parts[0] for m in map(ERROR.match, mypy_output.splitlines()) if m)


def main() -> int:
    allowed = allowed_counts(RATCHET.read_text(encoding="utf-8"))
    done = subprocess.run([sys.executable, "-m", "mypy"], capture_output=True, text=True)
    if done.returncode not in (0, 1):  # 2: mypy itself failed (bad configuration, crash)
        print(done.stdout + done.stderr)
        print("mypy ratchet: mypy did not run")
        return 2
    found = found_counts(done.stdout)
    failed = False
    for package in sorted(set(allowed) | set(found)):
        limit, count = allowed.get(package, 0), found.get(package, 0)
        if count > limit:
            failed = True
            print(f"mypy ratchet: {package} has {count} type errors, {limit} allowed by {RATCHET}:")
            print("\n".join(line for line in done.stdout.splitlines()
                            if line.startswith(f"{package}/") and ERROR.match(line)))
        elif count < limit:
            print(f"mypy ratchet: {package} is down to {count} type errors: lower its line in {RATCHET} "
                  f"from {limit} to {count}")
        else:
            print(f"mypy ratchet: {package} {count} type errors (allowed {limit})")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
