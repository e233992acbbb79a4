"""scenario_variation touches only files it generated from the same source (issue 21, items 1 and 3)."""

from __future__ import annotations

import subprocess
from pathlib import Path

from cli_support import run_variation

SCENARIO = """import osc.helpers

scenario test:
    do serial:
        log() with:
            keep(it.msg in ['A1', 'A2', 'A3'])
"""


def vary(tmp_path: Path, *args: str) -> subprocess.CompletedProcess:
    return run_variation(tmp_path, *args)


def names(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))


def test_second_source_into_the_same_folder_keeps_the_first(tmp_path):
    (tmp_path / "cut.osc").write_text(SCENARIO)
    (tmp_path / "merge.osc").write_text(SCENARIO.replace("'A3'", "'A3', 'A4'"))
    assert vary(tmp_path, "cut.osc").returncode == 0
    result = vary(tmp_path, "merge.osc")
    assert result.returncode == 0, result.stderr
    assert "leaving 3 other .sce file(s) in out/ untouched" in result.stdout
    assert names(tmp_path / "out") == ["cut0.sce", "cut1.sce", "cut2.sce",
                                       "merge0.sce", "merge1.sce", "merge2.sce", "merge3.sce"]


def test_hand_written_and_other_tools_files_survive_regeneration(tmp_path):
    (tmp_path / "cut.osc").write_text(SCENARIO)
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.sce").write_text("hand-written\n")
    (out / "reference_tool.sce").write_text("model: x\n")
    assert vary(tmp_path, "cut.osc").returncode == 0
    assert vary(tmp_path, "cut.osc").returncode == 0
    assert (out / "mine.sce").read_text() == "hand-written\n"
    assert (out / "reference_tool.sce").read_text() == "model: x\n"


def test_fewer_variants_remove_only_the_stale_ones_of_the_same_source(tmp_path):
    (tmp_path / "cut.osc").write_text(SCENARIO)
    (tmp_path / "cut2.osc").write_text(SCENARIO)       # its variants cut20.sce... look like cut's
    assert vary(tmp_path, "cut2.osc").returncode == 0
    assert vary(tmp_path, "cut.osc").returncode == 0
    (tmp_path / "cut.osc").write_text(SCENARIO.replace(", 'A3'", ""))
    assert vary(tmp_path, "cut.osc").returncode == 0
    assert names(tmp_path / "out") == ["cut0.sce", "cut1.sce", "cut20.sce", "cut21.sce", "cut22.sce"]


def test_a_foreign_file_under_a_variant_name_stops_before_writing(tmp_path):
    (tmp_path / "cut.osc").write_text(SCENARIO)
    out = tmp_path / "out"
    out.mkdir()
    (out / "cut1.sce").write_text("somebody else's\n")
    result = vary(tmp_path, "cut.osc")
    assert result.returncode == 1
    assert "cut.osc: error:" in result.stderr and "cut1.sce" in result.stderr
    assert "Traceback" not in result.stderr
    assert names(out) == ["cut1.sce"]
    assert (out / "cut1.sce").read_text() == "somebody else's\n"


def test_a_planted_symbolic_link_is_never_written_through(tmp_path):
    (tmp_path / "cut.osc").write_text(SCENARIO)
    out = tmp_path / "out"
    assert vary(tmp_path, "cut.osc").returncode == 0
    victim = tmp_path / "victim"
    victim.write_text("secret\n")
    (out / "cut2.sce").unlink()
    (out / "cut2.sce").symlink_to(victim)
    result = vary(tmp_path, "cut.osc")
    assert result.returncode == 1
    assert "cut2.sce" in result.stderr
    assert victim.read_text() == "secret\n"
    assert (out / "cut2.sce").is_symlink()


def test_a_stem_too_long_for_the_variant_names_writes_and_records_nothing(tmp_path):
    """Issue 21 item 3: 'File name too long' at variant 10 used to leave rows for files never written."""
    stem = "a" * 250
    (tmp_path / f"{stem}.osc").write_text(SCENARIO.replace("['A1', 'A2', 'A3']", str([f"A{i}" for i in range(12)])))
    result = vary(tmp_path, f"{stem}.osc")
    assert result.returncode == 1
    assert "longer than the 255 bytes a file name may have" in result.stderr and "nothing was written" in result.stderr
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").glob("*.sce"))
    from store.database import open_engine
    from store.variants import count_rows

    if (tmp_path / ".scenario_store.db").exists():
        assert count_rows(open_engine(f"sqlite:///{tmp_path / '.scenario_store.db'}")).get("variants", 0) == 0
