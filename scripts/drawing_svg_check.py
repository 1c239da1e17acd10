#!/usr/bin/env python3
"""A drawing's SVG against its PNG (render --style, docs/results.md 2026-12-02).

Renders MODEL with `linesurf render --style STYLE` to PNG and SVG, rasterises the SVG in headless
Chromium at the same size, and prints the SSIM of the two after a Gaussian blur of 1 pixel, their
PSNR and mean absolute difference, and the overlap of their inked pixels (grey < 50 %, as
intersection over union).

usage: PYTHONPATH=build/python drawing_svg_check.py LINESURF_CLI MODEL [SIZE [STYLE [RENDER ARGS...]]]
"""
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import linesurf


def blur(img, sigma=1.0):
    r = 3
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    out = img.astype(np.float64)
    for axis in (0, 1):
        out = np.apply_along_axis(lambda v: np.convolve(np.pad(v, r, mode="edge"), k, mode="valid"), axis, out)
    return out


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    cli, model = sys.argv[1], sys.argv[2]
    size = int(sys.argv[3]) if len(sys.argv) > 3 else 512
    style = sys.argv[4] if len(sys.argv) > 4 else "hatch"
    extra = sys.argv[5:]
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        for out in ("a.png", "a.svg"):
            subprocess.run([cli, "-q", "render", model, "--style", style, "--size", f"{size}x{size}", "-o", str(d / out),
                            *extra], check=True)
        subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                        "--force-device-scale-factor=1", f"--window-size={size},{size}", f"--screenshot={d / 'b.png'}",
                        (d / "a.svg").as_uri()], check=True, capture_output=True, timeout=120)
        a = linesurf.read_image(str(d / "a.png"))[..., :3].astype(np.float64).mean(axis=2)
        b = linesurf.read_image(str(d / "b.png"))[..., :3].astype(np.float64).mean(axis=2)
    ink_a, ink_b = a < 128, b < 128
    overlap = (ink_a & ink_b).sum() / max(1, (ink_a | ink_b).sum())
    grey = lambda g: np.concatenate([np.repeat(blur(g)[..., None], 3, axis=2).clip(0, 255).astype(np.uint8),
                                     np.full(g.shape + (1,), 255, np.uint8)], axis=2)
    c = linesurf.compare(grey(a), grey(b))
    print(f"{Path(model).name} {size}² {style}: SSIM after a 1 px blur {c['ssim']:.4f}, PSNR {c['psnr']:.2f} dB, "
          f"mean |difference| {np.abs(a - b).mean() / 255:.4f}, inked pixels overlap (IoU) {overlap:.3f}")


if __name__ == "__main__":
    main()
