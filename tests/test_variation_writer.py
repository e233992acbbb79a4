"""The file writer: in process and in a forked helper, and failures reported as OSError."""

from __future__ import annotations

import os

import pytest

from coverage_engine.variation.writer import FileWriter


@pytest.mark.parametrize("background", [False, True])
def test_writes_every_file(tmp_path, background):
    with FileWriter(background=background) as writer:
        for i in range(300):
            writer.write(str(tmp_path / f"f{i}.sce"), f"content {i}\n".encode() * (i % 7 + 1))
    assert len(list(tmp_path.iterdir())) == 300
    assert (tmp_path / "f13.sce").read_bytes() == b"content 13\n" * 7


@pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")
def test_child_failure_is_an_os_error(tmp_path):
    writer = FileWriter(background=True)
    writer.write(str(tmp_path / "missing" / "f.sce"), b"x")
    with pytest.raises(OSError, match="No such file"):
        writer.close()
