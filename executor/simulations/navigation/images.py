"""Read the grey-level images occupancy maps are drawn in: PGM (``P5``/``P2``) and PNG.

Only what map images need: 8-bit (or 16-bit PGM) grey, PNG grey, grey+alpha, RGB or RGBA without
interlacing; colour is reduced to its mean. The result is a numpy array of grey values 0..255,
row 0 at the top of the picture. Sizes are bounded (:data:`MAX_PIXELS`), so a hostile file cannot
make us allocate without limit.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path
from typing import TYPE_CHECKING

from executor.simulations import engines

if TYPE_CHECKING:
    from executor.simulations.engines import IntArray

MAX_PIXELS = 16_000_000
MAX_FILE_BYTES = 64 * 1024 * 1024


class ImageError(ValueError):
    """The file is not an image we can read (the message says why)."""


def read_grey_image(path: Path) -> IntArray:
    """The image at ``path`` as a 2-D ``uint8`` array (rows top to bottom)."""
    if path.stat().st_size > MAX_FILE_BYTES:
        raise ImageError(f"{path}: larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB")
    data = path.read_bytes()
    if data[:2] in (b"P5", b"P2"):
        return _read_pgm(data, path)
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        return _read_png(data, path)
    raise ImageError(f"{path}: not a PGM (P5/P2) or PNG image")


def _check_size(width: int, height: int, path: Path) -> None:
    if width <= 0 or height <= 0 or width * height > MAX_PIXELS:
        raise ImageError(f"{path}: image size {width}x{height} is empty or above {MAX_PIXELS} pixels")


def _read_pgm(data: bytes, path: Path) -> IntArray:
    np = engines.numpy()
    fields: list[bytes] = []
    position = 2
    while len(fields) < 3:  # width, height, maxval; '#' starts a comment up to the end of the line
        while position < len(data) and data[position:position + 1].isspace():
            position += 1
        if data[position:position + 1] == b"#":
            end = data.find(b"\n", position)
            position = len(data) if end < 0 else end + 1
            continue
        start = position
        while position < len(data) and not data[position:position + 1].isspace():
            position += 1
        if start == position:
            raise ImageError(f"{path}: truncated PGM header")
        fields.append(data[start:position])
    try:
        width, height, maxval = (int(f) for f in fields)
    except ValueError:
        raise ImageError(f"{path}: bad PGM header {fields!r}") from None
    _check_size(width, height, path)
    if not 0 < maxval < 65536:
        raise ImageError(f"{path}: PGM maxval {maxval} out of range")
    if data[:2] == b"P2":
        values = data[position:].split()
        if len(values) < width * height:
            raise ImageError(f"{path}: {len(values)} pixel values, expected {width * height}")
        pixels = np.array([int(v) for v in values[:width * height]], dtype=np.float64)
    else:
        position += 1  # one whitespace byte ends the header
        depth = 1 if maxval < 256 else 2
        raw = data[position:position + width * height * depth]
        if len(raw) < width * height * depth:
            raise ImageError(f"{path}: truncated PGM pixel data")
        pixels = np.frombuffer(raw, dtype=np.uint8 if depth == 1 else ">u2").astype(np.float64)
    grey = np.clip(np.rint(pixels * (255.0 / maxval)), 0, 255).astype(np.uint8)
    return grey.reshape(height, width)


_CHANNELS = {0: 1, 4: 2, 2: 3, 6: 4}  # PNG colour type -> samples per pixel


def _read_png(data: bytes, path: Path) -> IntArray:
    np = engines.numpy()
    position = 8
    idat: list[bytes] = []
    header: tuple[int, ...] | None = None
    while position + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[position:position + 8])
        body = data[position + 8:position + 8 + length]
        position += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            break
    if header is None:
        raise ImageError(f"{path}: PNG without IHDR")
    width, height, bit_depth, colour, _, _, interlace = header
    _check_size(width, height, path)
    if bit_depth != 8 or colour not in _CHANNELS or interlace:
        raise ImageError(f"{path}: only 8-bit, non-interlaced grey/RGB(A) PNG maps are supported")
    channels = _CHANNELS[colour]
    stride = width * channels
    decompressor = zlib.decompressobj()
    raw = decompressor.decompress(b"".join(idat), height * (stride + 1))
    if len(raw) < height * (stride + 1):
        raise ImageError(f"{path}: truncated PNG pixel data")
    rows = np.zeros((height, stride), dtype=np.int32)
    previous = np.zeros(stride, dtype=np.int32)
    for y in range(height):
        line = np.frombuffer(raw, dtype=np.uint8, count=stride, offset=y * (stride + 1) + 1).astype(np.int32)
        rows[y] = previous = _unfilter(raw[y * (stride + 1)], line, previous, channels, path)
    pixels = rows.reshape(height, width, channels)
    colour_part = pixels[:, :, :3] if channels >= 3 else pixels[:, :, :1]
    return np.rint(colour_part.mean(axis=2)).astype(np.uint8)


def _unfilter(kind: int, line: IntArray, previous: IntArray, bpp: int, path: Path) -> IntArray:
    """Undo one PNG scanline filter (None, Sub, Up, Average, Paeth)."""
    if kind == 0:
        return line
    if kind == 2:
        return (line + previous) & 0xFF
    out = line.copy()
    for i in range(len(out)):
        left = int(out[i - bpp]) if i >= bpp else 0
        up = int(previous[i])
        if kind == 1:
            out[i] = (out[i] + left) & 0xFF
        elif kind == 3:
            out[i] = (out[i] + (left + up) // 2) & 0xFF
        elif kind == 4:
            up_left = int(previous[i - bpp]) if i >= bpp else 0
            estimate = left + up - up_left
            pa, pb, pc = abs(estimate - left), abs(estimate - up), abs(estimate - up_left)
            predictor = left if pa <= pb and pa <= pc else up if pb <= pc else up_left
            out[i] = (out[i] + predictor) & 0xFF
        else:
            raise ImageError(f"{path}: unknown PNG filter type {kind}")
    return out
