"""``scenario_variation`` end to end: real files, a real SQLite store, the real command in a subprocess."""

from __future__ import annotations

import subprocess
from pathlib import Path

from cli_support import run_variation

from coverage_engine.files.sce import read_sce

TWO_KEEPS = """import osc.helpers

scenario test:
    do serial:
        log() with:
            keep(it.msg in ['A1', 'A2'])
        log() with:
            keep(it.msg in ['B1', 'B2', 'B3'])
"""


def run(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return run_variation(tmp_path, *args)


def _store_rows(tmp_path: Path) -> dict[str, int]:
    from store.database import open_engine
    from store.variants import count_rows

    return count_rows(open_engine(f"sqlite:///{tmp_path / '.scenario_store.db'}"))


def test_generates_the_product_in_order(tmp_path):
    (tmp_path / "main.osc").write_text(TWO_KEEPS)
    result = run(tmp_path, "main.osc")
    assert result.returncode == 0, result.stderr
    files = sorted((tmp_path / "out").glob("*.sce"))
    assert [f.name for f in files] == [f"main{i}.sce" for i in range(6)]
    doc = read_sce(tmp_path / "out" / "main2.sce")
    assert doc.assignment == {"test.log[0].msg": "A1", "test.log[1].msg": "B3"}
    assert doc.scenario == "test" and doc.source == "main.osc" and doc.index == 2
    assert Path(doc.source_dir) == tmp_path.resolve()
    assert "keep(it.msg == 'B3')" in doc.text and "import osc.helpers" in doc.text
    assert files[0].stat().st_size < 2048
    assert _store_rows(tmp_path) == {"source_files": 1, "variation_runs": 1, "variants": 6}


def test_regeneration_replaces_and_is_idempotent(tmp_path):
    (tmp_path / "main.osc").write_text(TWO_KEEPS)
    run(tmp_path, "main.osc")
    (tmp_path / "out" / "notes.txt").write_text("keep me")
    (tmp_path / "out" / "other7.sce").write_text("old")
    before = (tmp_path / "out" / "main1.sce").read_bytes()
    result = run(tmp_path, "main.osc")
    assert result.returncode == 0
    assert "replacing 6 .sce file(s) of an earlier generation" in result.stdout
    assert "leaving 1 other .sce file(s) in out/ untouched" in result.stdout
    assert (tmp_path / "out" / "main1.sce").read_bytes() == before
    assert (tmp_path / "out" / "other7.sce").read_text() == "old"
    assert (tmp_path / "out" / "notes.txt").read_text() == "keep me"
    assert _store_rows(tmp_path) == {"source_files": 1, "variation_runs": 2, "variants": 6}
    (tmp_path / "main.osc").write_text(TWO_KEEPS.replace(", 'B3'", ""))
    assert run(tmp_path, "main.osc", "-t", "out").returncode == 0
    assert len(list((tmp_path / "out").glob("main*.sce"))) == 4


def test_list_writes_nothing(tmp_path):
    (tmp_path / "main.osc").write_text(TWO_KEEPS)
    result = run(tmp_path, "main.osc", "--list")
    assert result.returncode == 0
    assert "main5: test.log[0].msg = 'A2', test.log[1].msg = 'B3'" in result.stdout
    assert not (tmp_path / "out").exists() and not (tmp_path / ".scenario_store.db").exists()


def test_no_keep_gives_one_model(tmp_path):
    (tmp_path / "quick.osc").write_text("import osc.helpers\n\nscenario quick:\n    do log('quick')\n")
    result = run(tmp_path, "quick.osc", "-o", "gen")
    assert result.returncode == 0
    assert "exactly one concrete model" in result.stdout
    assert [p.name for p in (tmp_path / "gen").glob("*.sce")] == ["quick0.sce"]


def test_syntax_error_is_one_message_and_loses_nothing(tmp_path):
    (tmp_path / "main.osc").write_text(TWO_KEEPS)
    run(tmp_path, "main.osc")
    (tmp_path / "main.osc").write_text(TWO_KEEPS.replace("scenario test:", "scenario test"))
    result = run(tmp_path, "main.osc")
    assert result.returncode != 0
    assert "main.osc:3:" in result.stderr and "error:" in result.stderr
    assert "Traceback" not in result.stderr + result.stdout
    assert len(list((tmp_path / "out").glob("*.sce"))) == 6


def test_a_bad_value_writes_nothing_and_is_quoted_as_written(tmp_path):
    """All or nothing (issue 22 item 4): a typo in one value must not leave a partial set of variants."""
    text = TWO_KEEPS.replace("keep(it.msg in ['B1', 'B2', 'B3'])", "keep(it.msg in ['B1', nope, 'B3'])")
    (tmp_path / "main.osc").write_text(text)
    result = run(tmp_path, "main.osc")
    assert result.returncode == 1
    assert "main.osc:8:35: error: test.log[1].msg = nope does not resolve: unknown name 'nope'" in result.stderr
    assert "            keep(it.msg in ['B1', nope, 'B3'])\n" in result.stderr          # the line as written
    assert "2 of 6 combination(s) hold a value that does not resolve; nothing was written" in result.stderr
    assert not list((tmp_path / "out").glob("*.sce")) if (tmp_path / "out").exists() else True
    assert _store_rows(tmp_path).get("variants", 0) == 0 if (tmp_path / ".scenario_store.db").exists() else True
    assert "Traceback" not in result.stderr


def test_parameter_documents_multiply(tmp_path):
    (tmp_path / "main.osc").write_text(TWO_KEEPS.replace("scenario test:", "scenario test:\n    v: int = 1"))
    (tmp_path / "sweep.yaml").write_text("test:\n  v: 2\n---\ntest:\n  v: 3\n")
    result = run(tmp_path, "main.osc", "--scenario-parameter-file", "sweep.yaml")
    assert result.returncode == 0, result.stderr
    files = list((tmp_path / "out").glob("*.sce"))
    assert len(files) == 12
    doc = read_sce(tmp_path / "out" / "main1.sce")
    assert doc.parameters == {"test": {"v": 3}} and doc.assignment["parameter_document"] == 1


def test_missing_file(tmp_path):
    result = run(tmp_path, "absent.osc")
    assert result.returncode == 1 and "absent.osc" in result.stderr and "Traceback" not in result.stderr


def test_a_parameter_document_placing_its_run_varies_and_runs(tmp_path):
    """``_output_dir`` in a document is the runner's key: variation keeps it in the .sce, the variant runs."""
    import subprocess
    import sys

    (tmp_path / "p.osc").write_text("import osc.helpers\nscenario p:\n    speed: float = 1.0\n"
                                    "    do serial:\n        log('x')\n")
    (tmp_path / "sweep.yaml").write_text("p:\n  speed: 2.0\n---\np:\n  speed: 3.0\n  _output_dir: fast\n")
    done = run_variation(tmp_path, "p.osc", "--scenario-parameter-file", "sweep.yaml")
    assert done.returncode == 0, done.stdout + done.stderr
    assert "wrote 2 scenario file(s)" in done.stdout
    run = subprocess.run([sys.executable, "-m", "cli.scenario_execution", "out/p1.sce", "-o", "r1"], cwd=tmp_path,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stdout + run.stderr
    assert (tmp_path / "r1" / "test.xml").exists()
