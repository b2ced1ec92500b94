#!/usr/bin/env python3
"""pfm_strip.py -- lays PFM images side by side into one PNG (sRGB, one exposure for all), each
with a caption, for docs/experiments.md's figures.

    /usr/bin/python3 tools/pfm_strip.py OUT.png [--exposure STOPS] IMAGE.pfm=CAPTION ...
"""
import argparse
import sys

import numpy as np
from PIL import Image, ImageDraw


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            sys.exit(f"pfm_strip: {path}: not a PFM file")
        w, h = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    ch = 3 if kind == b"PF" else 1
    img = data.reshape(h, w, ch)[::-1]  # PFM rows run bottom to top
    return np.repeat(img, 3, axis=2) if ch == 1 else img


def to_srgb(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("images", nargs="+", help="IMAGE.pfm=CAPTION")
    ap.add_argument("--exposure", type=float, default=0.0)
    a = ap.parse_args()
    tiles = []
    for spec in a.images:
        path, sep, caption = spec.partition(".pfm=")
        path = path + ".pfm" if sep else spec
        rgb = to_srgb(read_pfm(path) * 2.0**a.exposure)
        tile = Image.fromarray((rgb * 255 + 0.5).astype(np.uint8), "RGB")
        canvas = Image.new("RGB", (tile.width, tile.height + 18), "white")
        canvas.paste(tile, (0, 18))
        ImageDraw.Draw(canvas).text((4, 3), caption or path, fill="black")
        tiles.append(canvas)
    strip = Image.new("RGB", (sum(t.width for t in tiles), max(t.height for t in tiles)), "white")
    x = 0
    for t in tiles:
        strip.paste(t, (x, 0))
        x += t.width
    strip.save(a.out)
    print(f"pfm_strip: wrote {a.out} ({strip.width}x{strip.height})")


if __name__ == "__main__":
    main()
