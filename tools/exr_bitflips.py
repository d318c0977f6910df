"""How much damage to a frame file the Python reader finds: every single-bit flip of one
egogen frame file, read back with `egogen.read_exr`; counts the flips that raise (found), that
read as other pixels without an error (not found), and that change nothing read.

    python tools/exr_bitflips.py FRAME.exr      # with the reader installed (pip install ./python)

Prints one line of counts. Every flip is written to a scratch copy; FRAME.exr is only read.
"""

import os
import sys
import tempfile

import numpy as np

import arguments
import egogen


def read(path):
    """The frame's arrays by group, or None when the reader refuses the file."""
    try:
        return egogen.read_exr(path)
    except (egogen.FormatError, FileNotFoundError):
        return None


def same(a, b):
    return a.keys() == b.keys() and all(np.array_equal(a[k], b[k], equal_nan=True) for k in a)


def main():
    ap = arguments.StrictParser(description=__doc__.splitlines()[0])
    ap.add_argument("frame", help="an egogen frame file (EXR)")
    args = ap.parse_args()
    data = open(args.frame, "rb").read()
    truth = read(args.frame)
    if truth is None:
        sys.exit(f"{args.frame}: the reader refuses it undamaged")
    found = silent = harmless = 0
    with tempfile.TemporaryDirectory() as tmp:
        copy = os.path.join(tmp, "flipped.exr")
        # OpenEXR prints why it fails (stdout and stderr): keep the one line of counts readable.
        sys.stdout.flush()
        devnull = os.open(os.devnull, os.O_WRONLY)
        saved = (os.dup(1), os.dup(2))
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        try:
            for i in range(len(data) * 8):
                flipped = bytearray(data)
                flipped[i // 8] ^= 1 << (i % 8)
                with open(copy, "wb") as f:
                    f.write(flipped)
                got = read(copy)
                if got is None:
                    found += 1
                elif same(got, truth):
                    harmless += 1
                else:
                    silent += 1
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
    print(
        f"{args.frame}: {len(data)} bytes, {len(data) * 8} single-bit flips: "
        f"{found} refused, {silent} read as other pixels without an error, {harmless} change nothing read"
    )


if __name__ == "__main__":
    main()
