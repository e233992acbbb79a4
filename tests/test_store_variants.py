"""The variants store on real SQLite files: row counts, idempotence, lookup by assignment and by file."""

from __future__ import annotations

import time

from store.database import open_engine
from store.variants import (
    VariantRecord,
    content_hash,
    count_rows,
    find_variants,
    record_variation,
    variant_for_file,
)


def _records(out: str, n: int = 6, tag: str = ""):
    for i in range(n):
        assignment = {"test.log[0].msg": f"A{i // 3 + 1}", "test.log[1].msg": f"B{i % 3 + 1}", "test.n": i}
        text = f"# variant {i}{tag}\nformat_version: 1\n"
        yield VariantRecord(index=i, scenario="test", assignment=assignment, sce_text=text,
                            file_path=f"{out}/main{i}.sce")


def _record(engine, out: str, n: int = 6, tag: str = "", source_text: str = "scenario test:\n"):
    return record_variation(engine, source_path="/src/main.osc", source_sha256=content_hash(source_text),
                            source_text=source_text, options={"output_dir": out}, output_dir=out,
                            records=_records(out, n, tag))


def test_counts_and_idempotence(tmp_path):
    engine = open_engine(f"sqlite:///{tmp_path / 'store.db'}")
    _record(engine, "/o")
    assert count_rows(engine) == {"source_files": 1, "variation_runs": 1, "variants": 6}
    _record(engine, "/o")
    assert count_rows(engine) == {"source_files": 1, "variation_runs": 2, "variants": 6}
    # a new store object on the same file sees the same rows
    assert count_rows(open_engine(f"sqlite:///{tmp_path / 'store.db'}"))["variants"] == 6


def test_regeneration_after_a_change_supersedes_file_paths(tmp_path):
    engine = open_engine(f"sqlite:///{tmp_path / 'store.db'}")
    _record(engine, "/o")
    run = _record(engine, "/o", n=4, tag=" changed", source_text="scenario test: # changed\n")
    rows = count_rows(engine)
    assert rows["variants"] == 10 and rows["source_files"] == 2
    current = find_variants(engine, current_only=True)
    assert len(current) == 4 and all(v.run_id == run for v in current)
    found = variant_for_file(engine, "/o/main2.sce")
    assert found is not None and "changed" in found.sce_text
    assert variant_for_file(engine, "/o/main5.sce") is None


def test_lookup_by_assignment(tmp_path):
    engine = open_engine(f"sqlite:///{tmp_path / 'store.db'}")
    _record(engine, "/o")
    assert [v.index for v in find_variants(engine, {"test.log[0].msg": "A2"})] == [3, 4, 5]
    assert [v.index for v in find_variants(engine, {"test.log[0].msg": "A1", "test.log[1].msg": "B3"})] == [2]
    assert [v.index for v in find_variants(engine, n=1)] == [1]
    assert [v.index for v in find_variants(engine, n=1.0)] == [1]
    assert find_variants(engine, n=True) == []
    assert find_variants(engine, {"test.n": 10}) == []
    assert find_variants(engine, {"msg": "A1"}) == []  # mapping keys match exactly
    assert len(find_variants(engine, msg="A1")) == 3  # a keyword matches the key's last part
    assert len(find_variants(engine, scenario="test", source_path="/src/main.osc")) == 6
    found = find_variants(engine, {"test.log[1].msg": "B2"})[0]
    assert found.assignment["test.log[1].msg"] == "B2" and found.file_path == "/o/main1.sce"


def test_like_wildcards_in_values_are_literal(tmp_path):
    engine = open_engine(f"sqlite:///{tmp_path / 'store.db'}")
    records = [VariantRecord(index=i, scenario="s", assignment={"s.v": v}, sce_text=f"t{i}")
               for i, v in enumerate(["a%b", "axb", "a_b"])]
    record_variation(engine, source_path="/s.osc", source_sha256="0" * 64, source_text="", options={},
                     output_dir=None, records=records)
    assert [v.index for v in find_variants(engine, {"s.v": "a%b"})] == [0]
    assert [v.index for v in find_variants(engine, {"s.v": "a_b"})] == [2]


def test_many_rows_are_fast_and_streamed(tmp_path):
    engine = open_engine(f"sqlite:///{tmp_path / 'store.db'}")
    n = 20000

    def records():
        for i in range(n):
            yield VariantRecord(index=i, scenario="s", assignment=f'{{"s.v": {i}}}',
                                sce_text=f"variant {i}\n" + "x" * 400, file_path=f"/o/s{i}.sce")

    started = time.perf_counter()
    record_variation(engine, source_path="/s.osc", source_sha256="0" * 64, source_text="", options={},
                     output_dir="/o", records=records())
    assert time.perf_counter() - started < 5
    assert count_rows(engine)["variants"] == n
    assert [v.index for v in find_variants(engine, {"s.v": 12345})] == [12345]


def test_a_new_store_packs_variant_rows_in_8k_pages_and_an_old_one_keeps_its_pages(tmp_path):
    import sqlite3

    engine = open_engine(f"sqlite:///{tmp_path / 'new.db'}")
    _record(engine, "/o")
    engine.dispose()
    with sqlite3.connect(tmp_path / "new.db") as conn:
        assert conn.execute("PRAGMA page_size").fetchone()[0] == 8192
    old = tmp_path / "old.db"                       # a store made before (4 KiB pages, WAL)
    with sqlite3.connect(old) as conn:
        conn.execute("PRAGMA journal_mode=WAL")
        conn.execute("CREATE TABLE store_meta (key VARCHAR(64) PRIMARY KEY, value VARCHAR(255) NOT NULL, "
                     "schema_version INTEGER NOT NULL)")
        conn.execute("INSERT INTO store_meta VALUES ('schema', 'scenario-coverage', 2)")
    engine = open_engine(f"sqlite:///{old}")
    _record(engine, "/o")
    assert count_rows(engine)["variants"] == 6
    engine.dispose()
    with sqlite3.connect(old) as conn:
        assert conn.execute("PRAGMA page_size").fetchone()[0] == 4096
