#!/usr/bin/env python3
"""Writes the example scenes' assets: gobos/dots.png (the dotted gobo of the stage
scene, after the paper's Fig. 7) and meshes/knot.obj (a trefoil-knot sculpture).
Pure standard library, so it runs anywhere: `python3 scenes/make_assets.py`."""

import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def write_png_grey(path, width, height, rows):
    """An 8-bit greyscale PNG; rows is a list of bytes objects."""
    raw = b"".join(b"\x00" + r for r in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(png)


def dots(size=256, spacing=0.22, radius=0.07):
    """Round dots on a hexagonal grid inside the unit disc, edges anti-aliased over one
    texel; coordinates in [-1, 1]."""
    rows = []
    centres = []
    for j in range(-6, 7):
        for i in range(-6, 7):
            x = (i + 0.5 * (j % 2)) * spacing
            y = j * spacing * math.sqrt(3) / 2
            if math.hypot(x, y) + radius < 0.98:
                centres.append((x, y))
    texel = 2.0 / size
    for r in range(size):
        y = 1 - (r + 0.5) * texel
        row = bytearray(size)
        for c in range(size):
            x = -1 + (c + 0.5) * texel
            d = min(math.hypot(x - cx, y - cy) for cx, cy in centres)
            cover = min(1.0, max(0.0, (radius - d) / texel + 0.5))
            row[c] = round(255 * cover)
        rows.append(bytes(row))
    return rows


def knot(path, turns=240, sides=10, radius=0.09):
    """A tube along the trefoil knot, scaled to about 1 m across, base at y = 0."""
    def curve(t):
        x = math.sin(t) + 2 * math.sin(2 * t)
        y = math.cos(t) - 2 * math.cos(2 * t)
        z = -math.sin(3 * t)
        return (0.17 * x, 0.17 * y, 0.17 * z)

    verts = []
    for k in range(turns):
        t = 2 * math.pi * k / turns
        p, q = curve(t), curve(t + 1e-3)
        tangent = [b - a for a, b in zip(p, q)]
        n = math.sqrt(sum(v * v for v in tangent))
        tangent = [v / n for v in tangent]
        # A frame around the tangent from a fixed helper axis.
        helper = (0.0, 0.0, 1.0) if abs(tangent[2]) < 0.9 else (1.0, 0.0, 0.0)
        u = [tangent[1] * helper[2] - tangent[2] * helper[1],
             tangent[2] * helper[0] - tangent[0] * helper[2],
             tangent[0] * helper[1] - tangent[1] * helper[0]]
        n = math.sqrt(sum(v * v for v in u))
        u = [v / n for v in u]
        w = [tangent[1] * u[2] - tangent[2] * u[1],
             tangent[2] * u[0] - tangent[0] * u[2],
             tangent[0] * u[1] - tangent[1] * u[0]]
        for s in range(sides):
            a = 2 * math.pi * s / sides
            verts.append([p[i] + radius * (math.cos(a) * u[i] + math.sin(a) * w[i]) for i in range(3)])
    lift = -min(v[1] for v in verts)
    with open(path, "w") as f:
        f.write("# trefoil knot tube, made by scenes/make_assets.py\n")
        for v in verts:
            f.write("v %.5f %.5f %.5f\n" % (v[0], v[1] + lift, v[2]))
        for k in range(turns):
            for s in range(sides):
                a = k * sides + s + 1
                b = k * sides + (s + 1) % sides + 1
                c = ((k + 1) % turns) * sides + (s + 1) % sides + 1
                d = ((k + 1) % turns) * sides + s + 1
                f.write("f %d %d %d %d\n" % (a, b, c, d))


if __name__ == "__main__":
    os.makedirs(os.path.join(HERE, "gobos"), exist_ok=True)
    os.makedirs(os.path.join(HERE, "meshes"), exist_ok=True)
    write_png_grey(os.path.join(HERE, "gobos", "dots.png"), 256, 256, dots())
    knot(os.path.join(HERE, "meshes", "knot.obj"))
