"""Plays a short look on the Capture demo rig by sACN, as a desk would, for
`atmo dmx record` to record (scenes/mvr/capture-show.dmx; docs/previz.md):

    atmo dmx record --protocol sacn --bind 127.0.0.1 --scene scenes/mvr-capture.toml \
        -o scenes/mvr/capture-show.dmx --idle 1.5 &
    python3 scenes/mvr/make_capture_show.py

Needs Python's `sacn` package. The patch is read from the MVR itself: every fixture is
driven through atmo's spot's "Standard" mode (pan, tilt 16-bit; zoom; gobo; dimmer;
prism), the mode scenes/mvr-capture.toml gives them. Over six seconds the overhead
spots fan out and sweep, the washes come up narrow, the side spots cross the stage.
"""
import math
import re
import time
import zipfile
from pathlib import Path

import sacn

HERE = Path(__file__).parent
xml = zipfile.ZipFile(HERE / "capture_demo_show.mvr").read("GeneralSceneDescription.xml").decode()
fixtures = []
for block in re.findall(r"<Fixture .*?</Fixture>", xml, re.S):
    spec = re.search(r"<GDTFSpec>(.*?)</GDTFSpec>", block).group(1)
    address = int(re.search(r'<Address break="0">(\d+)</Address>', block).group(1))
    if address:
        fixtures.append((spec, (address - 1) // 512 + 1, (address - 1) % 512 + 1))

universes = sorted({u for _, u, _ in fixtures})
sender = sacn.sACNsender(bind_address="127.0.0.1", bind_port=0, fps=44)
sender.start()
for u in universes:
    sender.activate_output(u)
    sender[u].multicast = False
    sender[u].destination = "127.0.0.1"


def sixteen(x):
    """A 0-1 value as coarse and fine bytes."""
    v = max(0, min(65535, int(round(x * 65535))))
    return [v >> 8, v & 255]


start = time.time()
while (t := time.time() - start) < 6.0:
    levels = {u: [0] * 512 for u in universes}
    for k, (spec, u, a) in enumerate(fixtures):
        phase = 0.6 * t + 0.35 * k
        if "Robin" in spec:
            # pan -270..270 over 0..1: a fan of +-25 deg sweeping; tilt 20-40 deg.
            pan = 0.5 + (25 * math.sin(phase)) / 540
            tilt = 0.5 + (20 + 10 * math.sin(1.3 * phase)) / 270
            zoom, dimmer = 40, 255
        elif "Alpha" in spec:
            pan, tilt, zoom, dimmer = 0.5, 0.5 + (35 + 15 * math.sin(phase)) / 270, 10, 255
        elif "leda" in spec:
            pan, tilt, zoom, dimmer = 0.5, 0.5, 120, min(255, int(80 * t))
        else:
            pan, tilt, zoom, dimmer = 0.5, 0.5 + 10 / 270, 0, 90
        block = sixteen(pan) + sixteen(tilt) + [zoom, 0, dimmer, 0]
        levels[u][a - 1 : a - 1 + 8] = block
    for u in universes:
        sender[u].dmx_data = tuple(levels[u])
    time.sleep(1 / 30)
sender.stop()
