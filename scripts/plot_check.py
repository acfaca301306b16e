#!/usr/bin/env python3
"""Runs a plot command and checks the PNGs it must write: each exists, starts with the PNG
signature, its IHDR header gives the expected width x height, and it is not blank (decoded, its
pixels are not all one colour). Stale copies are removed before the command runs.

Usage: plot_check.py --png OUT.png=WIDTHxHEIGHT [--png ...] [--file OUT] -- COMMAND [ARGS...]
       plot_check.py --expect-error TEXT [--png OUT.png] -- COMMAND [ARGS...]
(--file: any other output that must be written and non-empty. --expect-error: the command must
exit with status 2 and one line on stderr containing TEXT, no traceback, and write no --png.)
Exit status 0 when the command succeeds and every PNG passes; otherwise one line per failure.
Used by the tests in tests/plots/.
"""
import argparse
import os
import struct
import subprocess
import sys

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(path):
    """(width, height) from the IHDR chunk, the first chunk after the signature."""
    with open(path, "rb") as f:
        head = f.read(24)
    if len(head) < 24 or head[:8] != PNG_SIGNATURE:
        raise ValueError("not a PNG (no PNG signature)")
    length, kind = struct.unpack(">I4s", head[8:16])
    if kind != b"IHDR" or length != 13:
        raise ValueError("no IHDR chunk first")
    return struct.unpack(">II", head[16:24])


def not_blank(path):
    import matplotlib.image
    pixels = matplotlib.image.imread(path)
    return float(pixels.max() - pixels.min()) > 0.0


def expect_error(command, text, outputs):
    for path in outputs:
        if os.path.exists(path):
            os.remove(path)
    done = subprocess.run(command, capture_output=True, text=True)
    lines = done.stderr.strip().splitlines()
    problems = []
    if done.returncode != 2:
        problems.append(f"exit status {done.returncode}, expected 2")
    if len(lines) != 1:
        problems.append(f"{len(lines)} lines on stderr, expected 1")
    if text not in done.stderr:
        problems.append(f"stderr does not name '{text}'")
    problems += [f"{p}: written despite the error" for p in outputs if os.path.exists(p)]
    if problems:
        print("plot_check: " + "; ".join(problems) + "\n" + done.stderr, file=sys.stderr)
        return 1
    print(f"plot_check: refused as expected: {lines[0]}")
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--png", action="append", default=[], metavar="FILE=WxH")
    ap.add_argument("--file", action="append", default=[], metavar="FILE")
    ap.add_argument("--expect-error", metavar="TEXT")
    ap.add_argument("command", nargs=argparse.REMAINDER)
    args = ap.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        ap.error("no command after --")
    if args.expect_error is not None:
        return expect_error(command, args.expect_error, [p.rpartition("=")[0] or p
                                                         for p in args.png])
    if not args.png and not args.file:
        ap.error("nothing to check: give --png or --file")
    for path in args.file:
        if os.path.exists(path):
            os.remove(path)
    expected = []
    for spec in args.png:
        path, _, size = spec.rpartition("=")
        try:
            w, h = (int(x) for x in size.lower().split("x"))
        except ValueError:
            ap.error(f"--png {spec}: expected FILE=WIDTHxHEIGHT")
        expected.append((path, w, h))
        if os.path.exists(path):
            os.remove(path)
    done = subprocess.run(command)
    if done.returncode != 0:
        print(f"plot_check: {' '.join(command[:2])} exited with {done.returncode}",
              file=sys.stderr)
        return 1
    failures = 0
    for path in args.file:
        if not os.path.isfile(path) or os.path.getsize(path) == 0:
            print(f"plot_check: {path}: not written or empty", file=sys.stderr)
            failures += 1
        else:
            print(f"plot_check: {path}: {os.path.getsize(path)} bytes, ok")
    for path, w, h in expected:
        if not os.path.isfile(path) or os.path.getsize(path) == 0:
            print(f"plot_check: {path}: not written", file=sys.stderr)
            failures += 1
            continue
        try:
            size = png_size(path)
        except ValueError as e:
            print(f"plot_check: {path}: {e}", file=sys.stderr)
            failures += 1
            continue
        if size != (w, h):
            print(f"plot_check: {path}: {size[0]}x{size[1]} px, expected {w}x{h}",
                  file=sys.stderr)
            failures += 1
        elif not not_blank(path):
            print(f"plot_check: {path}: blank (one colour)", file=sys.stderr)
            failures += 1
        else:
            print(f"plot_check: {path}: {w}x{h} px, {os.path.getsize(path)} bytes, ok")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
