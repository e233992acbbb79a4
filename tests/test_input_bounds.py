"""Every input is bounded (issue 32 item 4): a scenario file's size, the lines a message quotes, the
size of a covering array, and each long computation answers Ctrl-C and SIGTERM."""

from __future__ import annotations

import os

from coverage_support import BIN, run

HELLO = 'import osc.helpers\nscenario s:\n    do serial:\n        log("x")\n'


def test_a_stray_huge_scenario_file_is_refused_before_it_is_read(tmp_path):
    (tmp_path / "in").mkdir()
    (tmp_path / "in" / "ok.osc").write_text(HELLO, encoding="utf-8")
    with open(tmp_path / "in" / "huge.osc", "wb") as handle:     # 500 MB, sparse: one line, no newline
        handle.write(b"scenario s:" + b"x" * 1000)
        handle.truncate(500 * 1024 * 1024)
    done = run(str(BIN / "scenario_batch_execution"), "-i", "in", "-o", "results", "--store",
               f"sqlite:///{tmp_path / 's.db'}", cwd=tmp_path)
    assert done.returncode == 1
    log = tmp_path / "results" / "huge" / "log.txt"
    assert log.stat().st_size < 4096, log.read_bytes()[:2000]
    assert "larger than the limit of 64 MiB for a scenario file" in log.read_text(encoding="utf-8")
    assert len(done.stdout) + len(done.stderr) < 20_000
    assert (tmp_path / "results" / "ok" / "test.xml").is_file()
    assert os.path.getsize(tmp_path / "results" / "test.xml") < 20_000


def _many_values(path, dimensions: int, values: int) -> None:
    lines = ["import osc.helpers", "scenario big:"]
    lines += [f"    p{i}: int = 0" for i in range(dimensions)]
    lines += [f"    keep(p{i} in [{', '.join(str(v) for v in range(values))}])" for i in range(dimensions)]
    path.write_text("\n".join([*lines, "    do serial:", "        log(p0)"]) + "\n", encoding="utf-8")


def _variation(tmp_path, *args: str, timeout: float = 300):
    return run("prlimit", "--as=2000000000", str(BIN / "scenario_variation"), *args, "--seed", "1", "-o", "out",
               "--store", f"sqlite:///{tmp_path / 's.db'}", cwd=tmp_path, timeout=timeout, check=False)


def test_a_covering_array_too_big_to_build_is_refused_with_the_estimate_and_alternatives(tmp_path):
    _many_values(tmp_path / "wide.osc", 40, 50)
    done = _variation(tmp_path, "wide.osc", "--strategy", "t-way", "--strength", "3")
    assert done.returncode == 1 and "Traceback" not in done.stderr
    assert "has 1,235,000,000 3-tuples to cover (at least 125,000 variants)" in done.stderr
    assert "hint: use --strategy pairwise" in done.stderr
    rows = _variation(tmp_path, "wide.osc", "--strategy", "pairwise", "--max-variants", "1000")
    assert rows.returncode == 1 and "needs at least 2,500 variants" in rows.stderr
    assert "--max-variants 2500 if that many variants are wanted" in rows.stderr
    assert not any((tmp_path / "out").glob("*.sce")) if (tmp_path / "out").exists() else True


def test_pairwise_over_many_values_covers_every_pair(tmp_path):
    """10 dimensions of 50 values: IPOG, a few seconds (before: not done after 300 s)."""
    _many_values(tmp_path / "pw.osc", 10, 50)
    done = _variation(tmp_path, "pw.osc", "--strategy", "pairwise", "--list")
    assert done.returncode == 0, done.stderr
    assert "112500 of 112500 coverable 2-tuples covered" in done.stdout
    rows = [line for line in done.stdout.splitlines() if line.count("=") == 10]
    seen = {(a, b, row[a], row[b]) for row in (dict(enumerate(part.split(" = ")[1] for part in line.split(", ")))
                                               for line in rows) for a in range(10) for b in range(a + 1, 10)}
    assert len(seen) == 45 * 2500 and 2500 <= len(rows) < 5000


def test_a_results_folder_side_file_is_read_only_when_small_regular_and_not_a_link(tmp_path):
    """declared.json, history.json and search.json are read through one bounded reader: a link is not
    followed, a FIFO is not waited on, a file over the limit is not read."""
    from coverage_engine.limits import read_bounded

    (tmp_path / "small.json").write_bytes(b"{}")
    (tmp_path / "big.json").write_bytes(b"x" * 11)
    (tmp_path / "link.json").symlink_to(tmp_path / "small.json")
    os.mkfifo(tmp_path / "fifo.json")
    assert read_bounded(tmp_path / "small.json", 10) == b"{}"
    assert read_bounded(tmp_path / "big.json", 10) is None
    assert read_bounded(tmp_path / "link.json", 10) is None
    assert read_bounded(tmp_path / "fifo.json", 10) is None
    assert read_bounded(tmp_path / "missing.json", 10) is None
    assert read_bounded(tmp_path, 10) is None
