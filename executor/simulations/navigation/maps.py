"""Occupancy maps: the ROS ``map_server`` YAML + image format, and grid geometry.

A scenario folder may hold ``map.yaml`` (``image``, ``resolution``, ``origin``, ``negate``,
``occupied_thresh``, ``free_thresh``, as ``map_server`` reads them); its image is a PGM or PNG file
in the same folder. Without one, navigation runs on an empty plane (:func:`empty_map`).

Grids are numpy arrays indexed ``[row, col]`` with row 0 at the *lowest* y (the image's bottom
row), so ``row = (y - origin_y) / resolution`` like ``col = (x - origin_x) / resolution``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import yaml

from coverage_engine.yaml_bounds import YamlLimitError, load_bounded
from executor.simulations import engines
from executor.simulations.navigation.images import ImageError, read_grey_image

if TYPE_CHECKING:
    from executor.simulations.engines import BoolArray

MAP_FILE = "map.yaml"
MAX_MAP_YAML_BYTES = 64 * 1024


class MapError(ValueError):
    """A map file cannot be used (the message names the file and the reason)."""


@dataclass
class OccupancyMap:
    """A grid of occupied / free / unknown cells in the world's x-y plane."""

    resolution: float
    origin_x: float
    origin_y: float
    occupied: BoolArray  # [rows, cols]
    known: BoolArray  # [rows, cols]: False where the map says "unknown"
    source: str

    @property
    def shape(self) -> tuple[int, int]:
        rows, cols = self.occupied.shape
        return rows, cols

    def cell(self, x: float, y: float) -> tuple[int, int]:
        """``(row, col)`` of the cell holding world point ``(x, y)`` (may be outside the grid)."""
        return (math.floor((y - self.origin_y) / self.resolution),
                math.floor((x - self.origin_x) / self.resolution))

    def centre(self, row: int, col: int) -> tuple[float, float]:
        """World ``(x, y)`` of a cell's centre."""
        return (self.origin_x + (col + 0.5) * self.resolution, self.origin_y + (row + 0.5) * self.resolution)

    def inside(self, row: int, col: int) -> bool:
        rows, cols = self.shape
        return 0 <= row < rows and 0 <= col < cols

    @property
    def has_obstacles(self) -> bool:
        return bool(self.occupied.any())

    def rectangles(self) -> list[tuple[float, float, float, float]]:
        """The occupied cells as few axis-aligned rectangles ``(x_min, y_min, x_max, y_max)``.

        Runs of occupied cells in a row are merged, then equal runs in consecutive rows: walls
        drawn as lines become one box each.
        """
        open_runs: dict[tuple[int, int], int] = {}  # (col_start, col_end) -> first row
        boxes: list[tuple[int, int, int, int]] = []
        rows, _ = self.shape
        for row in range(rows + 1):
            runs = set(_runs(self.occupied[row])) if row < rows else set()
            for run in [r for r in open_runs if r not in runs]:
                boxes.append((open_runs.pop(run), run[0], row, run[1]))
            for run in runs:
                open_runs.setdefault(run, row)
        res = self.resolution
        return [(self.origin_x + c0 * res, self.origin_y + r0 * res, self.origin_x + c1 * res, self.origin_y + r1 * res)
                for r0, c0, r1, c1 in boxes]


def _runs(line: BoolArray) -> list[tuple[int, int]]:
    """``(first, end)`` columns of each run of True cells in a grid row."""
    np = engines.numpy()
    padded = np.concatenate(([False], line, [False]))
    edges = np.flatnonzero(padded[1:] != padded[:-1])
    return [(int(edges[i]), int(edges[i + 1])) for i in range(0, len(edges), 2)]


def empty_map(size: float = 30.0, resolution: float = 0.1) -> OccupancyMap:
    """A free square of ``size`` metres centred on the origin: navigation on an empty plane."""
    np = engines.numpy()
    cells = int(round(size / resolution))
    return OccupancyMap(resolution, -size / 2, -size / 2, np.zeros((cells, cells), dtype=bool),
                        np.ones((cells, cells), dtype=bool), "empty plane")


def find_map(folders: Iterable[str | None]) -> Path | None:
    """The first ``map.yaml`` in ``folders``."""
    for folder in folders:
        if folder and (Path(folder) / MAP_FILE).is_file():
            return Path(folder) / MAP_FILE
    return None


def load_map(path: Path) -> OccupancyMap:
    """Read a ``map_server`` YAML file and its image; :class:`MapError` for anything unusable."""
    if path.stat().st_size > MAX_MAP_YAML_BYTES:
        raise MapError(f"{path}: larger than {MAX_MAP_YAML_BYTES} bytes")
    try:
        spec = load_bounded(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, YamlLimitError) as exc:
        raise MapError(f"{path}: not YAML: {exc}") from None
    if not isinstance(spec, dict):
        raise MapError(f"{path}: expected a mapping with image, resolution and origin")

    def number(key: str, default: float | None = None) -> float:
        value = spec.get(key, default)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise MapError(f"{path}: '{key}' must be a number, got {value!r}")
        return float(value)

    resolution = number("resolution")
    if resolution <= 0:
        raise MapError(f"{path}: 'resolution' must be above 0")
    origin = spec.get("origin", [0.0, 0.0, 0.0])
    if (not isinstance(origin, list) or len(origin) != 3
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in origin)):
        raise MapError(f"{path}: 'origin' must be [x, y, yaw]")
    if origin[2] != 0:
        raise MapError(f"{path}: a rotated map origin (yaw {origin[2]}) is not supported")
    occupied_thresh, free_thresh = number("occupied_thresh", 0.65), number("free_thresh", 0.196)
    negate = spec.get("negate", 0) in (1, True)
    image = _image_path(path, spec.get("image"))
    try:
        grey = read_grey_image(image)
    except (OSError, ImageError) as exc:
        raise MapError(f"{path}: image '{spec.get('image')}': {exc}") from None
    np = engines.numpy()
    occupancy = grey.astype(np.float64) / 255.0 if negate else (255.0 - grey.astype(np.float64)) / 255.0
    occupancy = occupancy[::-1]  # the image's top row is the map's highest y
    occupied = occupancy > occupied_thresh
    known = occupied | (occupancy < free_thresh)
    return OccupancyMap(resolution, float(origin[0]), float(origin[1]), np.ascontiguousarray(occupied),
                        np.ascontiguousarray(known), str(path))


def _image_path(map_file: Path, image: object) -> Path:
    """The map image, which must be a file inside the map's own folder (links resolved)."""
    if not isinstance(image, str) or not image:
        raise MapError(f"{map_file}: 'image' must name the map's image file")
    folder = map_file.parent.resolve()
    candidate = (folder / image).resolve()
    if not candidate.is_relative_to(folder):
        raise MapError(f"{map_file}: image '{image}' is outside the map's folder")
    if not candidate.is_file():
        raise MapError(f"{map_file}: image '{image}' not found")
    return candidate
