#!/usr/bin/env python3
"""Writes the example scenes' assets: gobos/dots.png (the dotted gobo of the stage
scene, after the paper's Fig. 7), gobos/spokes.png (the turning gobo of the show),
meshes/knot.obj (a trefoil-knot sculpture) and the
photometric files of scenes/photometric.toml (photometry/: an ellipsoidal spot and an
oval wash as IES LM-63 files, a PAR can as EULUMDAT) and fixtures/atmo-spot.gdtf (a
moving spot as GDTF), made up, shaped like real ones.
Pure standard library, so it runs anywhere: `python3 scenes/make_assets.py`."""

import math
import os
import struct
import zipfile
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


def spokes(size=256, count=6, width=0.22):
    """A breakup gobo of `count` spokes from the centre, each `width` radians wide at
    its edge, inside the unit disc; edges anti-aliased over one texel. Turning, it
    shows which way a gobo rotates."""
    rows = []
    texel = 2.0 / size
    for j in range(size):
        row = bytearray(size)
        y = 1.0 - (j + 0.5) * texel
        for i in range(size):
            x = (i + 0.5) * texel - 1.0
            r = math.hypot(x, y)
            a = math.atan2(y, x) % (2 * math.pi / count)
            off = min(a, 2 * math.pi / count - a) * max(r, 1e-6)  # distance to a spoke
            inside = min(1.0, max(0.0, (width * 0.5 * r - off) / texel + 0.5))
            disc = min(1.0, max(0.0, (0.97 - r) / texel + 0.5))
            row[i] = int(round(255 * inside * disc))
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


def write_lines(path, lines):
    with open(path, "w", newline="\r\n") as f:
        f.write("\n".join(lines) + "\n")


def values(numbers, per_line=10):
    """Numbers, `per_line` a line, as LM-63 writers wrap them."""
    out = []
    for k in range(0, len(numbers), per_line):
        out.append(" ".join("%g" % round(x, 1) for x in numbers[k:k + per_line]))
    return out


def ies_spot(path):
    """An ellipsoidal spot, LM-63-2002, rotationally symmetric: a flat top of 20,000 cd
    falling to half at 11 degrees off the axis and cut at 30 by the shutter."""
    vertical = list(range(0, 41))
    candela = [0.0 if g >= 30 else 20000.0 / (1.0 + (g / 11.0) ** 8) for g in vertical]
    write_lines(path, [
        "IESNA:LM-63-2002",
        "[TEST] atmo example, made up",
        "[MANUFAC] atmo",
        "[LUMINAIRE] ellipsoidal spot, 19 degree lens",
        "TILT=NONE",
        "1 -1 1.0 %d 1 1 2 0.2 0.2 0.5" % len(vertical),
        "1.0 1.0 750",
        *values(vertical),
        "0",
        *values(candela),
    ])


def ies_oval(path):
    """An oval wash, LM-63-2019, symmetric in each quadrant: 8,000 cd on the axis, the
    beam 48 degrees wide along the light's x (C = 0) and 24 along its y (C = 90)."""
    vertical = [2.5 * k for k in range(25)]
    horizontal = [5 * k for k in range(19)]
    candela = []
    for c in horizontal:
        a = math.radians(c)
        width = 1.0 / math.hypot(math.cos(a) / 24.0, math.sin(a) / 12.0)
        candela += [8000.0 * max(0.0, 1.0 - (g / width) ** 2) ** 2 for g in vertical]
    write_lines(path, [
        "IES:LM-63-2019",
        "[TEST] atmo example, made up",
        "[ISSUEDATE] 2026-12-02",
        "[MANUFAC] atmo",
        "[LUMINAIRE] oval wash",
        "TILT=NONE",
        "1 -1 1.0 %d %d 1 2 0.3 0.3 0.2" % (len(vertical), len(horizontal)),
        "1.0 1.00001 400",
        *values(vertical),
        *values(horizontal),
        *values(candela),
    ])


def ldt_par(path):
    """A PAR can as EULUMDAT: rotationally symmetric (Isym 1), a 1,500 lm lamp,
    900 cd/klm on the axis falling as a Gaussian, nothing past 45 degrees."""
    gammas = [5 * k for k in range(19)]
    intensity = [0.0 if g > 45 else 900.0 * math.exp(-(g / 14.0) ** 2) for g in gammas]
    lines = ["atmo", "1", "1", "1", "0", str(len(gammas)), "5", "example",
             "PAR can, made up", "PAR-1", "par.ldt", "2026-12-02"]
    lines += ["200", "200", "250", "180", "180", "0", "0", "0", "0"]
    lines += ["100", "85", "1.0", "0", "1"]
    lines += ["1", "PAR64", "1500", "3200", "100", "100"]
    lines += ["0"] * 10
    lines += ["0"] + [str(g) for g in gammas] + ["%.1f" % i for i in intensity]
    write_lines(path, lines)


GDTF_DESCRIPTION = """<?xml version="1.0" encoding="UTF-8" standalone="no" ?>
<GDTF DataVersion="1.2">
  <FixtureType Name="atmo Spot 300" ShortName="Spot300" LongName="atmo example moving head spot"
      Manufacturer="atmo" Description="Made up for atmo's example scenes"
      FixtureTypeID="6C1A4A5E-5B1F-4C3E-9E2B-1D4E2F0A7B31" Thumbnail="" RefFT="">
    <AttributeDefinitions>
      <ActivationGroups><ActivationGroup Name="PanTilt"/><ActivationGroup Name="Gobo1"/><ActivationGroup Name="Prism"/></ActivationGroups>
      <FeatureGroups>
        <FeatureGroup Name="Position" Pretty="Position"><Feature Name="PanTilt"/></FeatureGroup>
        <FeatureGroup Name="Gobo" Pretty="Gobo"><Feature Name="Gobo"/></FeatureGroup>
        <FeatureGroup Name="Beam" Pretty="Beam"><Feature Name="Beam"/></FeatureGroup>
        <FeatureGroup Name="Dimmer" Pretty="Dimmer"><Feature Name="Dimmer"/></FeatureGroup>
      </FeatureGroups>
      <Attributes>
        <Attribute Name="Pan" Pretty="P" ActivationGroup="PanTilt" Feature="Position.PanTilt" PhysicalUnit="Angle"/>
        <Attribute Name="Tilt" Pretty="T" ActivationGroup="PanTilt" Feature="Position.PanTilt" PhysicalUnit="Angle"/>
        <Attribute Name="Gobo1" Pretty="G1" ActivationGroup="Gobo1" Feature="Gobo.Gobo" PhysicalUnit="None"/>
        <Attribute Name="Prism1" Pretty="Prism1" ActivationGroup="Prism" Feature="Beam.Beam" PhysicalUnit="None"/>
        <Attribute Name="Zoom" Pretty="Zoom" Feature="Beam.Beam" PhysicalUnit="Angle"/>
        <Attribute Name="Dimmer" Pretty="Dim" Feature="Dimmer.Dimmer" PhysicalUnit="LuminousIntensity"/>
      </Attributes>
    </AttributeDefinitions>
    <Wheels>
      <Wheel Name="Gobo1">
        <Slot Name="Open" Color="0.312700,0.329000,100.000000"/>
        <Slot Name="Spokes" Color="0.312700,0.329000,100.000000" MediaFileName="spokes"/>
        <Slot Name="Dots" Color="0.312700,0.329000,100.000000" MediaFileName="dots"/>
      </Wheel>
      <Wheel Name="Prism1">
        <Slot Name="Open" Color="0.312700,0.329000,100.000000"/>
        <Slot Name="3-Facet" Color="0.312700,0.329000,100.000000">
PRISM_FACETS        </Slot>
      </Wheel>
    </Wheels>
    <PhysicalDescriptions/>
    <Models>
      <Model Name="Base" Length="0.40" Width="0.30" Height="0.12" PrimitiveType="Base" File="base"/>
      <Model Name="Yoke" Length="0.40" Width="0.10" Height="0.31" PrimitiveType="Yoke" File="yoke"/>
      <Model Name="Head" Length="0.28" Width="0.28" Height="0.32" PrimitiveType="Head" File="head"/>
    </Models>
    <Geometries>
      <Geometry Name="Base" Model="Base" Position="{1,0,0,0}{0,1,0,0}{0,0,1,0}{0,0,0,1}">
        <Axis Name="Yoke" Model="Yoke" Position="{1,0,0,0}{0,1,0,0}{0,0,1,-0.06}{0,0,0,1}">
          <Axis Name="Head" Model="Head" Position="{1,0,0,0}{0,1,0,0}{0,0,1,-0.25}{0,0,0,1}">
            <Beam Name="Beam" Model="Head" Position="{1,0,0,0}{0,1,0,0}{0,0,1,-0.17}{0,0,0,1}"
                LampType="LED" PowerConsumption="300" LuminousFlux="12000" ColorTemperature="6500"
                BeamAngle="18" FieldAngle="24" BeamRadius="0.06" BeamType="Spot" ColorRenderingIndex="80"/>
          </Axis>
        </Axis>
      </Geometry>
    </Geometries>
    <DMXModes>
      <DMXMode Name="Standard" Geometry="Base">
        <DMXChannels>
          <DMXChannel DMXBreak="1" Offset="1,2" InitialFunction="Yoke_Pan.Pan.Pan 1" Highlight="None" Geometry="Yoke">
            <LogicalChannel Attribute="Pan" Snap="No" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Pan 1" Attribute="Pan" DMXFrom="0/2" Default="32768/2" PhysicalFrom="-270" PhysicalTo="270"/>
            </LogicalChannel>
          </DMXChannel>
          <DMXChannel DMXBreak="1" Offset="3,4" InitialFunction="Head_Tilt.Tilt.Tilt 1" Highlight="None" Geometry="Head">
            <LogicalChannel Attribute="Tilt" Snap="No" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Tilt 1" Attribute="Tilt" DMXFrom="0/2" Default="32768/2" PhysicalFrom="-135" PhysicalTo="135"/>
            </LogicalChannel>
          </DMXChannel>
          <DMXChannel DMXBreak="1" Offset="5" InitialFunction="Beam_Zoom.Zoom.Zoom 1" Highlight="None" Geometry="Beam">
            <LogicalChannel Attribute="Zoom" Snap="No" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Zoom 1" Attribute="Zoom" DMXFrom="0/1" Default="0/1" PhysicalFrom="8" PhysicalTo="36"/>
            </LogicalChannel>
          </DMXChannel>
          <DMXChannel DMXBreak="1" Offset="6" InitialFunction="Head_Gobo1.Gobo1.Gobo 1" Highlight="None" Geometry="Head">
            <LogicalChannel Attribute="Gobo1" Snap="Yes" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Gobo 1" Attribute="Gobo1" DMXFrom="0/1" Default="0/1" Wheel="Gobo1" PhysicalFrom="0" PhysicalTo="1"/>
            </LogicalChannel>
          </DMXChannel>
          <DMXChannel DMXBreak="1" Offset="8" InitialFunction="Head_Prism1.Prism1.Prism 1" Highlight="None" Geometry="Head">
            <LogicalChannel Attribute="Prism1" Snap="Yes" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Prism 1" Attribute="Prism1" DMXFrom="0/1" Default="0/1" Wheel="Prism1" PhysicalFrom="0" PhysicalTo="1"/>
            </LogicalChannel>
          </DMXChannel>
          <DMXChannel DMXBreak="1" Offset="7" InitialFunction="Beam_Dimmer.Dimmer.Dimmer 1" Highlight="255/1" Geometry="Beam">
            <LogicalChannel Attribute="Dimmer" Snap="No" Master="Grand" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Dimmer 1" Attribute="Dimmer" DMXFrom="0/1" Default="0/1" PhysicalFrom="0" PhysicalTo="1"/>
            </LogicalChannel>
          </DMXChannel>
        </DMXChannels>
      </DMXMode>
      <DMXMode Name="Basic" Geometry="Base">
        <DMXChannels>
          <DMXChannel DMXBreak="1" Offset="1" InitialFunction="Yoke_Pan.Pan.Pan 1" Highlight="None" Geometry="Yoke">
            <LogicalChannel Attribute="Pan" Snap="No" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Pan 1" Attribute="Pan" DMXFrom="0/1" Default="128/1" PhysicalFrom="-180" PhysicalTo="180"/>
            </LogicalChannel>
          </DMXChannel>
          <DMXChannel DMXBreak="1" Offset="2" InitialFunction="Head_Tilt.Tilt.Tilt 1" Highlight="None" Geometry="Head">
            <LogicalChannel Attribute="Tilt" Snap="No" Master="None" MibFade="0" DMXChangeTimeLimit="0">
              <ChannelFunction Name="Tilt 1" Attribute="Tilt" DMXFrom="0/1" Default="128/1" PhysicalFrom="-90" PhysicalTo="90"/>
            </LogicalChannel>
          </DMXChannel>
        </DMXChannels>
      </DMXMode>
    </DMXModes>
  </FixtureType>
</GDTF>
"""


def prism_facet(off_deg, around_deg):
    """A GDTF PrismFacet turning the beam (along -z) off_deg off its axis toward
    around_deg (from +x toward +y): Rodrigues' rotation about the axis
    -z x d (d the facet's beam), its rows written {a,b,c}{d,e,f}{g,h,i} with six decimals."""
    t, p = math.radians(off_deg), math.radians(around_deg)
    # The axis: perpendicular to -z and to the facet's beam, in the xy plane.
    k = (math.sin(p), -math.cos(p), 0.0)
    c, s = math.cos(t), math.sin(t)
    # The cross-product matrix of k, added by hand: [k]x = [[0,-kz,ky],[kz,0,-kx],[-ky,kx,0]].
    cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]]
    m = [[(c if i == j else 0.0) + (1 - c) * k[i] * k[j] + s * cross[i][j] for j in range(3)]
         for i in range(3)]
    rows = "".join("{%s}" % ",".join("%.6f" % (round(v, 6) + 0.0) for v in row) for row in m)
    return '          <PrismFacet Color="0.312700,0.329000,100.000000" Rotation="%s"/>\n' % rows


# The example fixture's prism: three facets 8 degrees off the beam, 120 degrees apart.
GDTF_DESCRIPTION = GDTF_DESCRIPTION.replace(
    "PRISM_FACETS", "".join(prism_facet(8.0, a) for a in (90.0, 210.0, 330.0)))


def boxes_3ds(boxes):
    """A 3DS file (main, editor, one object, its mesh) of axis-aligned boxes given as
    ((x0, y0, z0), (x1, y1, z1)), metres: the models of the spot's geometries."""
    def chunk(kind, body):
        return struct.pack("<HI", kind, len(body) + 6) + body
    vertices, faces = [], []
    for lo, hi in boxes:
        base = len(vertices)
        for i in range(8):
            vertices.append(tuple(hi[k] if i >> k & 1 else lo[k] for k in range(3)))
        for a, b, c, d in [(0, 2, 6, 4), (1, 5, 7, 3), (0, 4, 5, 1), (2, 3, 7, 6), (0, 1, 3, 2), (4, 6, 7, 5)]:
            faces += [(base + a, base + b, base + c), (base + a, base + c, base + d)]
    v = struct.pack("<H", len(vertices)) + b"".join(struct.pack("<3f", *p) for p in vertices)
    f = struct.pack("<H", len(faces)) + b"".join(struct.pack("<4H", *t, 0) for t in faces)
    mesh = chunk(0x4110, v) + chunk(0x4120, f)
    return chunk(0x4D4D, chunk(0x3D3D, chunk(0x4000, b"body\0" + chunk(0x4100, mesh))))


# The spot's models, each in its geometry's frame (z up; the fixture hangs, its beam
# along -z): the base around its origin; the yoke from under the base (its origin, the
# pan pivot) down past the head's tilt pivot 0.25 m below; the head around that pivot,
# its lens 3 cm past the lamp (the Beam geometry, 0.17 m below the pivot).
SPOT_MODELS = {
    "base": [((-0.20, -0.15, -0.06), (0.20, 0.15, 0.06))],
    "yoke": [
        ((-0.20, -0.05, -0.03), (0.20, 0.05, 0.0)),
        ((-0.20, -0.05, -0.31), (-0.17, 0.05, -0.03)),
        ((0.17, -0.05, -0.31), (0.20, 0.05, -0.03)),
    ],
    "head": [((-0.14, -0.14, -0.20), (0.14, 0.14, 0.12))],
}


def gdtf_spot(path):
    """A GDTF fixture of a moving spot: description.xml (a beam of 12,000 lm at 6500 K,
    18 degrees to half and 24 to a tenth, a zoom of 8-36 degrees, pan -270-270, tilt
    -135-135, a gobo wheel with the spokes and the dots, a prism wheel with a
    three-facet prism; a second, basic mode), the wheel's images and the models of its
    base, yoke and head (SPOT_MODELS). Fixed timestamps, so the file is the same byte for byte."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        def put(name, data):
            info = zipfile.ZipInfo(name, date_time=(2026, 12, 2, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, data)
        put("description.xml", GDTF_DESCRIPTION)
        for name, boxes in SPOT_MODELS.items():
            put("models/3ds/%s.3ds" % name, boxes_3ds(boxes))
        for gobo in ("spokes", "dots"):
            with open(os.path.join(HERE, "gobos", gobo + ".png"), "rb") as f:
                put("wheels/%s.png" % gobo, f.read())


if __name__ == "__main__":
    os.makedirs(os.path.join(HERE, "gobos"), exist_ok=True)
    os.makedirs(os.path.join(HERE, "meshes"), exist_ok=True)
    write_png_grey(os.path.join(HERE, "gobos", "dots.png"), 256, 256, dots())
    write_png_grey(os.path.join(HERE, "gobos", "spokes.png"), 256, 256, spokes())
    knot(os.path.join(HERE, "meshes", "knot.obj"))
    os.makedirs(os.path.join(HERE, "photometry"), exist_ok=True)
    ies_spot(os.path.join(HERE, "photometry", "spot.ies"))
    ies_oval(os.path.join(HERE, "photometry", "oval-wash.ies"))
    ldt_par(os.path.join(HERE, "photometry", "par.ldt"))
    os.makedirs(os.path.join(HERE, "fixtures"), exist_ok=True)
    gdtf_spot(os.path.join(HERE, "fixtures", "atmo-spot.gdtf"))
