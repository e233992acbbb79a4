"""Draw map.pgm, the occupancy map of the navigation examples (12 m x 12 m, 0.1 m cells).

Run ``python3 make_map.py`` here to redraw it after changing the walls below. White is free,
black occupied (map_server's trinary mode, see map.yaml).
"""

from __future__ import annotations

from pathlib import Path

RESOLUTION = 0.1
ORIGIN = (-6.0, -6.0)
SIZE = 120  # cells per side

# walls as (x_min, y_min, x_max, y_max) in metres
WALLS = [
    (-6.0, -6.0, 6.0, -5.8), (-6.0, 5.8, 6.0, 6.0), (-6.0, -6.0, -5.8, 6.0), (5.8, -6.0, 6.0, 6.0),  # border
    (-6.0, -0.9, -0.2, -0.7),   # the south room's north wall, west part
    (1.8, -0.9, 6.0, -0.7),     # ... and east part: a 2 m door between x = -0.2 and x = 1.8
    (1.0, 2.0, 6.0, 2.2),       # shelf wall: the goal (3, 3) lies behind it
    (-3.8, 3.2, -3.2, 3.8),     # pillar in the north room
    (-3.5, -4.0, -2.5, -3.0),   # crate in the south room
]


def main() -> None:
    free, occupied = 254, 0
    cells = [[free] * SIZE for _ in range(SIZE)]
    for x0, y0, x1, y1 in WALLS:
        for row in range(SIZE):
            for col in range(SIZE):
                x = ORIGIN[0] + (col + 0.5) * RESOLUTION
                y = ORIGIN[1] + (row + 0.5) * RESOLUTION
                if x0 <= x <= x1 and y0 <= y <= y1:
                    cells[row][col] = occupied
    image = b"".join(bytes(cells[row]) for row in reversed(range(SIZE)))  # top row first
    header = f"P5\n# navigation example map\n{SIZE} {SIZE}\n255\n".encode()
    (Path(__file__).resolve().parent / "map.pgm").write_bytes(header + image)


if __name__ == "__main__":
    main()
