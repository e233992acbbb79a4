"""Occupancy maps: map_server YAML, PGM and PNG images, walls as boxes, and refused files."""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import pytest


def _paeth(a: int, b: int, c: int) -> int:
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    return a if pa <= pb and pa <= pc else b if pb <= pc else c


def write_png(path: Path, rows: list[list[int]]) -> None:
    """An 8-bit grey PNG using every scanline filter in turn (so reading has to undo each)."""
    raw, previous = b"", [0] * len(rows[0])
    for y, row in enumerate(rows):
        kind = y % 5
        out = []
        for i, value in enumerate(row):
            left, up, up_left = (row[i - 1] if i else 0), previous[i], (previous[i - 1] if i else 0)
            predictor = [0, left, up, (left + up) // 2, _paeth(left, up, up_left)][kind]
            out.append((value - predictor) & 0xFF)
        raw += bytes([kind, *out])
        previous = row

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    header = struct.pack(">IIBBBBB", len(rows[0]), len(rows), 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw))
                     + chunk(b"IEND", b""))


PICTURE = [  # top row first, as drawn: 0 occupied, 254 free, 205 unknown
    [0, 0, 0, 0, 0, 0],
    [0, 254, 254, 205, 254, 0],
    [0, 254, 0, 0, 254, 0],
    [0, 0, 0, 0, 0, 0],
]


def write_map(folder: Path, image: str, extra: str = "") -> Path:
    path = folder / "map.yaml"
    path.write_text(f"image: {image}\nresolution: 0.5\norigin: [-1.0, -2.0, 0.0]\n{extra}", encoding="utf-8")
    return path


@pytest.mark.parametrize("kind", ["pgm", "pgm-ascii", "png"])
def test_map_images_read_alike(tmp_path, kind):
    from executor.simulations.navigation.maps import load_map

    if kind == "png":
        write_png(tmp_path / "m.png", PICTURE)
        name = "m.png"
    elif kind == "pgm":
        header = b"P5\n# a comment\n6 4\n255\n"
        (tmp_path / "m.pgm").write_bytes(header + bytes(v for row in PICTURE for v in row))
        name = "m.pgm"
    else:
        (tmp_path / "m.pgm").write_text("P2 6 4 255\n" + "\n".join(" ".join(map(str, r)) for r in PICTURE))
        name = "m.pgm"
    grid = load_map(write_map(tmp_path, name))
    assert grid.shape == (4, 6)
    assert grid.occupied[0].all() and grid.occupied[3].all()      # row 0 is the picture's bottom row
    assert grid.occupied[1].tolist() == [True, False, True, True, False, True]
    assert grid.known[2].tolist() == [True, True, True, False, True, True]  # 205 is unknown
    assert grid.cell(-1.0, -2.0) == (0, 0) and grid.centre(1, 1) == (-0.25, -1.25)
    boxes = grid.rectangles()
    assert (-1.0, -2.0, 2.0, -1.5) in boxes          # the bottom wall is one box
    covered = sum((x1 - x0) * (y1 - y0) for x0, y0, x1, y1 in boxes) / 0.25
    assert covered == grid.occupied.sum()


def test_negate_and_thresholds(tmp_path):
    from executor.simulations.navigation.maps import load_map

    (tmp_path / "m.pgm").write_bytes(b"P5 6 4 255 " + bytes(v for row in PICTURE for v in row))
    grid = load_map(write_map(tmp_path, "m.pgm", "negate: 1\n"))
    assert not grid.occupied[0].any() and grid.occupied[1, 1]


@pytest.mark.parametrize("setup, message", [
    (lambda d: write_map(d, "../outside.pgm"), "outside the map's folder"),
    (lambda d: write_map(d, "missing.pgm"), "'missing.pgm' not found"),
    (lambda d: (d / "m.pgm").write_bytes(b"P5 6 4 255 \x00") and write_map(d, "m.pgm"), "truncated PGM pixel data"),
    (lambda d: (d / "m.pgm").write_bytes(b"GIF89a") and write_map(d, "m.pgm"), "not a PGM (P5/P2) or PNG image"),
    (lambda d: (d / "m.pgm").write_bytes(b"P5 100000 100000 255 ") and write_map(d, "m.pgm"), "above 16000000 pixels"),
    (lambda d: (d / "map.yaml").write_text("image: m.pgm\nresolution: -1\n"), "'resolution' must be above 0"),
    (lambda d: (d / "map.yaml").write_text("image: m.pgm\nresolution: 0.1\norigin: [0, 0, 1.57]\n"),
     "rotated map origin"),
])
def test_bad_maps_are_refused_with_a_reason(tmp_path, setup, message):
    from executor.simulations.navigation.maps import MapError, load_map

    (tmp_path / "sub").mkdir()
    (tmp_path / "outside.pgm").write_bytes(b"P5 1 1 255 \x00")
    setup(tmp_path / "sub")
    with pytest.raises(MapError, match=message.replace("(", r"\(").replace(")", r"\)")):
        load_map(tmp_path / "sub" / "map.yaml")


def test_a_bad_map_fails_the_scenario_with_its_reason(tmp_path):
    from sim_support import EXAMPLES, PYBULLET_SIM, execute

    (tmp_path / "map.yaml").write_text("image: nowhere.png\nresolution: 0.1\norigin: [0, 0, 0]\n", encoding="utf-8")
    scenario = tmp_path / "nav.osc"
    scenario.write_text((EXAMPLES / "navigation" / "example_nav2.osc").read_text(encoding="utf-8"), encoding="utf-8")
    done = execute(str(scenario), "--simulation", PYBULLET_SIM, cwd=tmp_path)
    assert done.returncode == 1
    assert "nav.osc:9:9: error: action 'differential_drive_robot.init_nav2': cannot use the map:" in done.stdout
    assert "image 'nowhere.png' not found" in done.stdout
