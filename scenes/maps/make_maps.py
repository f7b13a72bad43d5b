#!/usr/bin/env python3
"""Writes the example Universal VTT maps beside this script: a tavern with
doors and windows (tavern.dd2vtt) and a dungeon corridor lit by torches
(corridor.uvtt). Their geometry is in grid cells, their pictures are drawn
here pixel by pixel, and nothing but the standard library is used, so the
same script writes the same bytes on every machine:

    python3 scenes/maps/make_maps.py
"""

import base64
import json
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def png(width, height, rgb):
    """A PNG of 8-bit RGB rows (a bytearray of width * height * 3)."""
    raw = bytearray()
    stride = width * 3
    for y in range(height):
        raw.append(0)
        raw.extend(rgb[y * stride:(y + 1) * stride])

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(bytes(raw), 9)) + chunk(b"IEND", b""))


class Canvas:
    """A picture in grid cells: shapes are filled where a test of the
    cell coordinates of a pixel's centre holds."""

    def __init__(self, cells_x, cells_y, ppg, background):
        self.w, self.h, self.ppg = cells_x * ppg, cells_y * ppg, ppg
        self.rgb = bytearray(bytes(background) * (self.w * self.h))

    def fill(self, x0, y0, x1, y1, colour_at):
        """Fills the box [x0, x1] x [y0, y1] (cells); `colour_at(x, y)`
        gives each pixel's colour, or None to leave it."""
        p = self.ppg
        for py in range(max(0, int(y0 * p)), min(self.h, int(math.ceil(y1 * p)))):
            for px in range(max(0, int(x0 * p)), min(self.w, int(math.ceil(x1 * p)))):
                x, y = (px + 0.5) / p, (py + 0.5) / p
                if x0 <= x <= x1 and y0 <= y <= y1:
                    c = colour_at(x, y)
                    if c is not None:
                        k = (py * self.w + px) * 3
                        self.rgb[k:k + 3] = bytes(c)

    def box(self, x0, y0, x1, y1, colour):
        self.fill(x0, y0, x1, y1, lambda x, y: colour)

    def segment(self, a, b, width, colour):
        """A thick line from a to b (cells), `width` cells across."""
        (ax, ay), (bx, by) = a, b
        dx, dy = bx - ax, by - ay
        length2 = dx * dx + dy * dy
        half = width / 2

        def inside(x, y):
            t = ((x - ax) * dx + (y - ay) * dy) / length2
            t = min(1.0, max(0.0, t))
            ex, ey = ax + t * dx - x, ay + t * dy - y
            return colour if ex * ex + ey * ey <= half * half else None

        self.fill(min(ax, bx) - half, min(ay, by) - half,
                  max(ax, bx) + half, max(ay, by) + half, inside)

    def disk(self, c, r, colour):
        cx, cy = c
        self.fill(cx - r, cy - r, cx + r, cy + r,
                  lambda x, y: colour if (x - cx) ** 2 + (y - cy) ** 2 <= r * r else None)

    def base64(self):
        return base64.b64encode(png(self.w, self.h, self.rgb)).decode("ascii")


def planks(x, y):
    """Wooden boards half a cell wide, each its own shade, joints dark."""
    row = int(y * 2)
    shade = (row * 37 % 5) * 6
    if (y * 2) % 1 < 0.06 or ((x + row * 0.7) % 3) < 0.03:
        return (92, 60, 34)
    return (150 + shade, 104 + shade, 62 + shade // 2)


def flagstones(x, y):
    """Grey flagstones a cell wide, grout lines between."""
    if x % 1 < 0.05 or y % 1 < 0.05:
        return (70, 70, 72)
    shade = (int(x) * 7 + int(y) * 13) % 4 * 8
    return (128 + shade, 126 + shade, 120 + shade)


def grass(x, y):
    shade = (int(x * 4) * 11 + int(y * 4) * 7) % 5 * 5
    return (70 + shade, 112 + shade, 52)


def pt(p):
    return {"x": p[0], "y": p[1]}


def portal(a, b, closed):
    return {
        "position": pt(((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)),
        "bounds": [pt(a), pt(b)],
        "rotation": math.atan2(b[1] - a[1], b[0] - a[0]),
        "closed": closed,
        "freestanding": False,
    }


def light(p, range_, colour, intensity=1.0):
    return {"position": pt(p), "range": range_, "intensity": intensity,
            "color": colour, "shadows": True}


def draw(canvas, walls, objects, portals, lights):
    for run in walls:
        for a, b in zip(run, run[1:]):
            canvas.segment(a, b, 0.25, (52, 40, 34))
    for run in objects:
        for a, b in zip(run, run[1:]):
            canvas.segment(a, b, 0.08, (60, 38, 20))
    for p in portals:
        a, b = (p["bounds"][0]["x"], p["bounds"][0]["y"]), (p["bounds"][1]["x"], p["bounds"][1]["y"])
        if p["closed"]:
            canvas.segment(a, b, 0.18, (120, 76, 36))
        else:
            canvas.segment(a, b, 0.12, (170, 210, 235))
    for l in lights:
        c = l["color"]
        rgb = (int(c[2:4], 16), int(c[4:6], 16), int(c[6:8], 16))
        canvas.disk((l["position"]["x"], l["position"]["y"]), 0.18, rgb)


def uvtt(size, ppg, walls, objects, portals, lights, canvas, ambient):
    return {
        "format": 0.3,
        "resolution": {"map_origin": pt((0, 0)), "map_size": pt(size), "pixels_per_grid": ppg},
        "line_of_sight": [[pt(p) for p in run] for run in walls],
        "objects_line_of_sight": [[pt(p) for p in run] for run in objects],
        "portals": portals,
        "environment": {"baked_lighting": False, "ambient_light": ambient},
        "lights": lights,
        "image": canvas.base64(),
    }


def tavern():
    """A tavern of 12 x 8 cells on a lawn: the hall with its hearth, two
    lanterns, a bar and three windows; a kitchen behind a shut door, with
    no window and no lamp; the front door shut."""
    size, ppg = (14, 10), 64
    # Runs of wall that meet only at their ends.
    walls = [
        [(6, 9), (1, 9), (1, 6)],          # front wall, left of the door; left wall to its window
        [(1, 4), (1, 1), (3, 1)],          # left wall above the window; back wall to the first window
        [(5, 1), (6, 1)],                  # between the back windows
        [(8, 1), (9, 1)],                  # back wall to the kitchen's wall
        [(9, 1), (13, 1), (13, 9), (9, 9)],  # the kitchen's outer walls
        [(9, 9), (7, 9)],                  # front wall, right of the door
        [(9, 1), (9, 4)],                  # the kitchen's wall, above its door
        [(9, 5), (9, 9)],                  # and below it
    ]
    bar = [(3, 4.2), (6, 4.2), (6, 4.8), (3, 4.8), (3, 4.2)]
    table = [(11, 3), (12, 3), (12, 4), (11, 4), (11, 3)]
    objects = [bar, table]
    portals = [
        portal((6, 9), (7, 9), True),    # the front door
        portal((9, 4), (9, 5), True),    # the kitchen's door
        portal((3, 1), (5, 1), False),   # windows
        portal((6, 1), (8, 1), False),
        portal((1, 4), (1, 6), False),
    ]
    lights = [
        light((2.5, 7.5), 6, "ffff9a3c", 1.5),   # the hearth
        light((4.5, 2.5), 5, "ffffd9a0"),        # lanterns
        light((7.5, 6.5), 5, "ffffd9a0"),
    ]
    canvas = Canvas(size[0], size[1], ppg, (70, 112, 52))
    canvas.fill(0, 0, size[0], size[1], grass)
    canvas.fill(1, 1, 9, 9, planks)
    canvas.fill(9, 1, 13, 9, flagstones)
    canvas.box(1.5, 7, 3.5, 8.7, (90, 84, 80))    # the hearth's stones
    canvas.box(3, 4.2, 6, 4.8, (112, 70, 38))    # the bar's top
    canvas.box(11, 3, 12, 4, (120, 80, 44))      # the kitchen's table
    draw(canvas, walls, objects, portals, lights)
    return uvtt(size, ppg, walls, objects, portals, lights, canvas, "ff8090a0")


def corridor():
    """A dungeon corridor 18 cells long lit by three torches, a cell behind
    a shut door below it, an archway (a gap) above it to a guard room, and
    a cave at its east end, with a fourth torch, whose rough wall is a run
    of many short walls."""
    size, ppg = (22, 9), 40
    cave = [(19, 3)]
    for k in range(1, 24):
        a = math.pi * (-0.5 + k / 24)
        r = 2.2 + 0.35 * math.sin(5 * a) + 0.2 * math.cos(11 * a)
        cave.append((round(19 + r * math.cos(a), 3), round(4 + r * math.sin(a) * 1.6, 3)))
    cave.append((19, 5))
    walls = [
        [(1, 3), (1, 5), (10, 5)],               # west end; south wall to the cell
        [(10, 5), (11, 5)],                      # the cell's wall, west of its door
        [(12, 5), (14, 5)],                      # and east of it
        [(14, 5), (19, 5)],                      # south wall past the cell
        [(19, 3), (8, 3)],                       # north wall, east of the archway
        [(6, 3), (1, 3)],                        # and west of it
        cave,                                    # the cave: many short walls, ends shared
        [(10, 5), (10, 8), (14, 8), (14, 5)],    # the cell
        [(6, 3), (6, 1), (8, 1), (8, 3)],        # the guard room above the archway
    ]
    portals = [
        portal((11, 5), (12, 5), True),          # the cell's door, shut
    ]
    lights = [
        light((3, 3.3), 4, "ffff8c28", 2.0),
        light((9, 4.7), 4, "ffff8c28", 2.0),
        light((15, 3.3), 4, "ffff8c28", 2.0),
        light((20.2, 4), 3.5, "ffff8c28", 2.0),  # in the cave
    ]
    canvas = Canvas(size[0], size[1], ppg, (24, 22, 22))
    canvas.fill(1, 3, 19, 5, flagstones)
    canvas.fill(10, 5, 14, 8, flagstones)
    canvas.fill(6, 1, 8, 3, flagstones)
    canvas.fill(16.5, 0, 22, 9, lambda x, y: flagstones(x, y) if inside(cave, (x, y)) else None)
    draw(canvas, walls, [], portals, lights)
    return uvtt(size, ppg, walls, [], portals, lights, canvas, "ff000000")


def inside(points, p):
    """Whether p lies inside the closed polygon through `points`."""
    x, y = p
    result = False
    for (ax, ay), (bx, by) in zip(points, points[1:] + points[:1]):
        if (ay > y) != (by > y) and x < ax + (y - ay) * (bx - ax) / (by - ay):
            result = not result
    return result


def main():
    for name, make in [("tavern.dd2vtt", tavern), ("corridor.uvtt", corridor)]:
        path = os.path.join(HERE, name)
        with open(path, "w", encoding="ascii") as f:
            json.dump(make(), f, indent=1)
            f.write("\n")
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
