"""A full disk under scenario_variation and scenario_batch_execution (issue 21, items 3 and 7).

The output folder is a small tmpfs mounted in a private mount namespace (``unshare -rm``), so the disk
really fills up, for the real commands, without touching the machine's mounts; the namespace ends with
the script, so each script looks at the folder (and "makes room" by growing the tmpfs) before it ends.
Skipped where the machine allows no user namespace.
"""

from __future__ import annotations

import json
import os
import shlex
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BIN = Path(sys.executable).parent


def _namespaces_work() -> bool:
    if not shutil.which("unshare") or sys.platform != "linux":
        return False
    probe = subprocess.run(["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt 2>/dev/null || "
                            "mount -t tmpfs -o size=64k tmpfs /tmp"], capture_output=True)
    return probe.returncode == 0


pytestmark = pytest.mark.skipif(not _namespaces_work(), reason="needs unshare -rm and tmpfs (user namespaces)")

#: Looks at a folder from inside the namespace: every file's name and SHA-256 (hidden ones too).
SNAPSHOT = """
import hashlib, json, os, sys
folder, target = sys.argv[1], sys.argv[2]
files = {}
for base, _dirs, names in os.walk(folder):
    for name in names:
        path = os.path.join(base, name)
        with open(path, 'rb') as handle:
            files[os.path.relpath(path, folder)] = hashlib.sha256(handle.read()).hexdigest()
json.dump(files, open(target, 'w'))
"""


def on_small_disk(tmp_path: Path, folder: Path, size_kb: int, steps: list[str]) -> None:
    """Mount a ``size_kb`` tmpfs on ``folder`` in a private namespace and run the shell ``steps`` there.

    Each step's exit code goes to ``rc<n>``; ``snapshot N`` (a step) stores the folder's files in ``snapN.json``;
    ``grow`` makes the tmpfs 64 MB (room made)."""
    folder.mkdir()
    (tmp_path / "snapshot.py").write_text(SNAPSHOT)
    lines = [f"mount -t tmpfs -o size={size_kb}k tmpfs {shlex.quote(str(folder))} || exit 99"]
    for number, step in enumerate(steps):
        if step.startswith("snapshot "):
            lines.append(f"{shlex.quote(sys.executable)} snapshot.py {shlex.quote(str(folder))} "
                         f"snap{step.split()[1]}.json")
        elif step == "grow":
            lines.append(f"mount -o remount,size=64m {shlex.quote(str(folder))}")
        else:
            lines.append(f"{step} > out{number}.txt 2> err{number}.txt; echo $? > rc{number}")
    env = dict(os.environ, PATH=f"{BIN}:{os.environ['PATH']}", PYTHONPATH=str(ROOT), NO_COLOR="1")
    env.pop("SCENARIO_STORE", None)
    done = subprocess.run(["unshare", "-rm", "sh", "-c", "\n".join(lines)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr


def step_result(tmp_path: Path, number: int) -> tuple[int, str, str]:
    return (int((tmp_path / f"rc{number}").read_text()), (tmp_path / f"out{number}.txt").read_text(),
            (tmp_path / f"err{number}.txt").read_text())


VARIED = """import osc.helpers

scenario test:
    x: int with:
        keep(it in [1..{count}])
    do serial:
        log("a message long enough to make every variant file take a few hundred bytes on the disk")
"""


@pytest.mark.parametrize("count", [400, 6000], ids=["in-process-writer", "background-writer"])
def test_variation_on_a_full_disk_records_exactly_the_files_written(tmp_path, count):
    (tmp_path / "cut.osc").write_text(VARIED.format(count=count))
    out = tmp_path / "out"
    vary = f"scenario_variation cut.osc -o {out} --store sqlite:///{tmp_path}/s.db"
    on_small_disk(tmp_path, out, 240, [vary, "snapshot 1", "cp s.db s1.db", "grow", vary, "snapshot 2"])

    code, stdout, stderr = step_result(tmp_path, 0)
    assert code == 1, stdout + stderr
    assert "Traceback" not in stderr
    message = [line for line in stderr.splitlines() if "No space left on device" in line]
    assert len(message) == 1, stderr
    assert f"cannot write {out}/cut" in message[0] and "were written (and recorded)" in message[0]

    files = json.loads((tmp_path / "snap1.json").read_text())
    assert not [name for name in files if name.endswith(".part")], "a cut-short temporary file was left"
    written = {name: digest for name, digest in files.items() if name.endswith(".sce")}
    assert 0 < len(written) < count
    with sqlite3.connect(tmp_path / "s1.db") as db:        # the store as the first run left it
        rows = db.execute("SELECT file_path, content_hash FROM variants WHERE file_path IS NOT NULL").fetchall()
    recorded = {os.path.relpath(path, out): digest for path, digest in rows}
    assert recorded == written, "the store and the folder differ after the disk filled up"
    recorded_count = int(message[0].split("; ")[1].split(" of ")[0])
    assert recorded_count == len(written)

    code, stdout, stderr = step_result(tmp_path, 4)
    assert code == 0, stdout + stderr
    files = json.loads((tmp_path / "snap2.json").read_text())
    assert len([name for name in files if name.endswith(".sce")]) == count
    with sqlite3.connect(tmp_path / "s.db") as db:
        paths = {os.path.relpath(p, out) for (p,) in db.execute(
            "SELECT file_path FROM variants WHERE file_path IS NOT NULL")}
    assert paths == {f"cut{i}.sce" for i in range(count)}


JOB = """import osc.helpers

scenario test:
    do serial:
        log("{text}")
"""


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_batch_on_a_full_disk_stops_once_and_resume_finishes_it(tmp_path, jobs):
    inputs = tmp_path / "in"
    inputs.mkdir()
    for number in range(40):
        (inputs / f"s{number:02}.osc").write_text(JOB.format(text="x" * 200))
    out = tmp_path / "res"
    store = f"sqlite:///{tmp_path}/store.db"
    run = f"scenario_batch_execution -i {inputs} -o {out} -j {jobs} --store {store}"
    on_small_disk(tmp_path, out, 160, [run, "grow", f"{run} --resume", "snapshot 1"])

    code, stdout, stderr = step_result(tmp_path, 0)
    assert code == 1, stdout + stderr
    assert "Traceback" not in stdout + stderr
    assert stderr.count("error: no space left on the device holding") == 1, stderr
    assert "--resume" in stderr
    assert "batch 1: 40 job(s):" in stdout and " passed" in stdout
    assert "error " not in stdout.replace("error:", ""), "a job was judged an error because of the disk"

    code, stdout, stderr = step_result(tmp_path, 2)
    assert code == 0, stdout + stderr
    assert "batch 1: 40 job(s): 40 passed" in stdout
    files = json.loads((tmp_path / "snap1.json").read_text())
    assert "test.xml" in files
    with sqlite3.connect(tmp_path / "store.db") as db:
        assert db.execute("SELECT status, count(*) FROM jobs GROUP BY status").fetchall() == [("passed", 40)]
