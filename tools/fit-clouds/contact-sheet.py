"""A contact sheet of views of `fit-clouds`: per row, the path tracer's picture, the
transfer solve's and the transfer table's, each row scaled alike (its path-traced
picture's 99th percentile to white, gamma 2.2), 5 times enlarged, pixels kept.

    cargo run --release -p atmo-fit-clouds -- --paths 64 --clouds c60134 --dump DIR
    python tools/fit-clouds/contact-sheet.py DIR 64 c60134-level-front,c60134-level-side OUT.png

Needs numpy and Pillow; reads the path-traced pictures `fit-clouds` keeps in the
system's temporary folder.
"""

import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

W, H = 48, 28
SCALE = 5


def main() -> None:
    dump, paths, views, out = Path(sys.argv[1]), sys.argv[2], sys.argv[3].split(","), sys.argv[4]
    kept = Path(tempfile.gettempdir()) / "atmo-fit-clouds"
    rows = []
    for view in views:
        traced = np.loadtxt(kept / f"{view}-{paths}.txt").reshape(H, W)
        solve = np.loadtxt(dump / f"{view}-solve.txt").reshape(H, W)
        table = np.loadtxt(dump / f"{view}-table.txt").reshape(H, W)
        white = np.percentile(traced[traced > 0], 99)
        tone = lambda x: (np.clip(x / white, 0, 1) ** (1 / 2.2) * 255).astype(np.uint8)
        gap = np.full((H, 1), 40, np.uint8)
        rows.append(np.concatenate([tone(traced), gap, tone(solve), gap, tone(table)], 1))
        rows.append(np.full((1, rows[-1].shape[1]), 40, np.uint8))
    sheet = np.concatenate(rows[:-1], 0)
    size = (sheet.shape[1] * SCALE, sheet.shape[0] * SCALE)
    Image.fromarray(sheet).resize(size, Image.NEAREST).convert("RGB").save(out)


if __name__ == "__main__":
    main()
