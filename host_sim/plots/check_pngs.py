#!/usr/bin/python3
"""Check that PNG files are real, non-trivial plots.

Usage: check_pngs.py FILE.png...

Each file must exist, start with the PNG signature, be at least 400 x 300 px (from its IHDR) and
larger than 20 KB, and decode (matplotlib.image.imread) to an image with at least 5 % of its pixels
differing from the background (the most frequent colour) and at least 64 distinct colours.
Prints one line per file (size, dimensions, non-background fraction, colour count, or the reason it
fails). Exit status: 0 all pass, 1 any fails, 2 bad usage.
"""
import os
import struct
import sys

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
MIN_WIDTH, MIN_HEIGHT = 400, 300
MIN_BYTES = 20 * 1024
MIN_NON_BACKGROUND = 0.05
MIN_COLOURS = 64


def check(path):
    """Returns (ok, line)."""
    if not os.path.isfile(path):
        return False, f"{path}: FAIL: missing (no such file)"
    size = os.path.getsize(path)
    with open(path, "rb") as f:
        head = f.read(33)
    if head[:8] != PNG_SIGNATURE:
        return False, f"{path}: FAIL: not a PNG (no PNG signature), {size} bytes"
    if len(head) < 33 or head[12:16] != b"IHDR":
        return False, f"{path}: FAIL: PNG without an IHDR chunk, {size} bytes"
    width, height = struct.unpack(">II", head[16:24])
    dims = f"{width}x{height} px"
    if width < MIN_WIDTH or height < MIN_HEIGHT:
        return False, f"{path}: FAIL: {dims}, smaller than {MIN_WIDTH}x{MIN_HEIGHT} px"
    if size <= MIN_BYTES:
        return False, f"{path}: FAIL: {size} bytes, not larger than {MIN_BYTES} bytes (20 KB)"
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.image as mimage
        import numpy as np
    except ImportError as e:
        return False, f"{path}: FAIL: cannot decode: {e} (install python3-matplotlib)"
    try:
        img = mimage.imread(path)
    except Exception as e:  # a corrupt file: any decoder error
        return False, f"{path}: FAIL: does not decode: {e}"
    if img.ndim == 2:
        img = img[:, :, None]
    if img.dtype != np.uint8:
        img = np.round(np.clip(img, 0.0, 1.0) * 255.0).astype(np.uint8)
    if img.shape[0] != height or img.shape[1] != width:
        return False, f"{path}: FAIL: decodes to {img.shape[1]}x{img.shape[0]} px, IHDR says {dims}"
    # one integer per pixel (up to 4 channels of 8 bits)
    packed = np.zeros(img.shape[:2], dtype=np.uint32)
    for c in range(img.shape[2]):
        packed = (packed << np.uint32(8)) | img[:, :, c].astype(np.uint32)
    values, counts = np.unique(packed, return_counts=True)
    colours = len(values)
    background_share = counts.max() / packed.size
    non_background = 1.0 - background_share
    line = (f"{path}: {size} bytes, {dims}, {100.0 * non_background:.1f} % non-background, "
            f"{colours} colours")
    if non_background < MIN_NON_BACKGROUND:
        return False, f"{line}: FAIL: fewer than {100 * MIN_NON_BACKGROUND:.0f} % non-background pixels"
    if colours < MIN_COLOURS:
        return False, f"{line}: FAIL: fewer than {MIN_COLOURS} distinct colours"
    return True, f"{line}: ok"


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        sys.stdout.write(__doc__) if len(argv) >= 2 else sys.stderr.write(__doc__)
        return 0 if len(argv) >= 2 else 2
    failed = 0
    for path in argv[1:]:
        ok, line = check(path)
        print(line)
        failed += not ok
    if failed:
        print(f"check_pngs: {failed} of {len(argv) - 1} file(s) failed", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
