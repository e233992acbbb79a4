"""The shared conformance corpus, run black-box against the installed commands.

Every case listed in ``tests/conformance_expected_pass.txt`` must pass; the list only grows. Cases
not listed are reported but do not fail the suite. The corpus lives outside the repository
(``../shared/conformance``); without it this test is skipped.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("CONFORMANCE_DIR", ROOT.parent / "shared" / "conformance"))
EXPECTED = Path(__file__).with_name("conformance_expected_pass.txt")


def expected_passing() -> list[str]:
    lines = EXPECTED.read_text(encoding="utf-8").splitlines() if EXPECTED.exists() else []
    return [line.strip() for line in lines if line.strip() and not line.startswith("#")]


@pytest.mark.slow
@pytest.mark.skipif(not (CORPUS / "run.py").exists(), reason=f"conformance corpus not found at {CORPUS}")
def test_no_conformance_regression(tmp_path):
    report = tmp_path / "report.json"
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    proc = subprocess.run(
        [sys.executable, str(CORPUS / "run.py"), "-j", "2", "--json", str(report)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=1500)
    assert report.exists(), proc.stdout[-3000:] + proc.stderr[-3000:]
    data = json.loads(report.read_text(encoding="utf-8"))
    cases = data["cases"] if isinstance(data, dict) and "cases" in data else data
    status = {c["name"]: c.get("status", c.get("result")) for c in cases}
    passed = sorted(name for name, s in status.items() if str(s).lower() == "pass")
    print(f"conformance: {len(passed)} of {len(status)} cases pass")
    regressions = [name for name in expected_passing() if status.get(name, "missing").lower() != "pass"]
    assert not regressions, "cases that passed before now fail: " + ", ".join(regressions)
