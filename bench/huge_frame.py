#!/usr/bin/python3
"""huge_frame.py - denoise a huge synthetic frame in bounded memory.

Writes a SIZE x SIZE (default 16384 x 16384) Blender Cycles style EXR with
Combined RGBA, Denoising Albedo, Denoising Normal and Denoising Depth, a band
of rows at a time (never whole in memory), then runs

    zdenoise --in huge.exr -o huge_denoised.exr -v [ARGS...]

with default settings and reports its wall time and peak resident memory
(ru_maxrss of that child), which must stay under --max-rss (default 2 GiB):
zdenoise streams the frame in strips of rows (docs/PERFORMANCE.md, "Memory").

The scene has real surfaces: a back wall, a floor, boxes and spheres, each
with its own normal, depth and texture, lit by a sun and a sky, with
multiplicative noise; above them, sky (no surface), which keeps the run
shorter. Run with Debian's /usr/bin/python3 (OpenImageIO, numpy).

    bench/huge_frame.py                          # 16384 x 16384, ~GBs of disk
    bench/huge_frame.py --size 4096 --keep /tmp/h  # smaller; keep the files
    nice bench/huge_frame.py -- --threads 2      # extra zdenoise arguments

Exit status: 0 ok, 1 zdenoise failed or went over --max-rss, 2 setup error.
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BAND = 128  # rows generated and written at a time


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--size", type=int, default=16384, help="width and height")
    p.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    p.add_argument("--dir", help="folder for the files (default: a temporary one)")
    p.add_argument("--keep", action="store_true", help="keep the files")
    p.add_argument("--max-rss", type=float, default=2048.0, help="MiB (default 2048)")
    p.add_argument("args", nargs="*", help="extra zdenoise arguments (after --)")
    return p.parse_args()


def run_measured(cmd):
    """Run cmd; return (status, wall seconds, peak RSS MiB, stdout).

    The child is started before this script imports numpy or OpenImageIO:
    Linux carries the parent's memory high-water mark over fork and exec
    into the child's ru_maxrss (see bench/README.md)."""
    t0 = time.time()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    out = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, time.time() - t0, usage.ru_maxrss / 1024.0, out


def generate(path, n):
    """The frame, written band by band in a child process (so that this
    script's memory stays small for the measured run that follows)."""
    code = r'''
import sys
import numpy as np
import OpenImageIO as oiio

path, n, band = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
P = "ViewLayer."
names = [P + "Combined." + c for c in "RGBA"]
names += [P + "Denoising Albedo." + c for c in "RGB"]
names += [P + "Denoising Normal." + c for c in "XYZ"]
names += [P + "Denoising Depth.Z"]
types = [oiio.HALF] * 7 + [oiio.FLOAT] * 4
spec = oiio.ImageSpec(n, n, len(names), oiio.HALF)
spec.channelnames = tuple(names)
spec.channelformats = tuple(oiio.TypeDesc(t) for t in types)
spec.alpha_channel = 3
spec.attribute("compression", "zip")
out = oiio.ImageOutput.create(path)
if not out or not out.open(path, spec):
    sys.exit("cannot write %s: %s" % (path, oiio.geterror()))

x = (np.arange(n, dtype=np.float32) + 0.5) / n
# Spheres (centre u, v, radius as a share of the width) and boxes
# (u0, u1, v0, v1, depth, normal) standing on the floor.
spheres = [(0.2, 0.62, 0.07), (0.5, 0.7, 0.1), (0.82, 0.6, 0.06)]
boxes = [(0.06, 0.16, 0.55, 0.78, 5.0, (0.5, 0.0, 0.866)),
         (0.62, 0.74, 0.48, 0.75, 6.0, (-0.6, 0.0, 0.8))]
sun = np.array([0.4, -0.6, 0.7], np.float32)
sun /= np.linalg.norm(sun)
for y0 in range(0, n, band):
    y1 = min(y0 + band, n)
    v = ((np.arange(y0, y1, dtype=np.float32) + 0.5) / n)[:, None]
    u = np.broadcast_to(x[None, :], (y1 - y0, n))
    v = np.broadcast_to(v, (y1 - y0, n))
    shape = (y1 - y0, n)
    nx, ny, nz = np.zeros(shape, np.float32), np.zeros(shape, np.float32), np.ones(shape, np.float32)
    depth = np.zeros(shape, np.float32)          # 0: sky, no surface
    obj = np.zeros(shape, np.int32)
    wall = (v >= 0.45) & (v < 0.6)
    depth[wall] = 12.0
    obj[wall] = 1
    floor = v >= 0.6
    depth[floor] = 3.0 + 9.0 * (1.0 - (v[floor] - 0.6) / 0.4)
    ny[floor], nz[floor] = 1.0, 0.0
    obj[floor] = 2
    for k, (u0, u1, va, vb, d, nrm) in enumerate(boxes):
        m = (u >= u0) & (u < u1) & (v >= va) & (v < vb)
        depth[m] = d + 0.5 * (u[m] - u0)
        nx[m], ny[m], nz[m] = nrm
        obj[m] = 3 + k
    for k, (cu, cv, r) in enumerate(spheres):
        dx, dy = (u - cu) / r, (v - cv) / r
        rr = dx * dx + dy * dy
        m = rr < 1.0
        zz = np.sqrt(np.maximum(1.0 - rr, 0.0))
        depth[m] = 4.0 + 2.0 * k - zz[m]
        nx[m], ny[m], nz[m] = dx[m], -dy[m], zz[m]
        obj[m] = 10 + k
    surface = depth > 0
    # Textures: a checker on the floor and boxes, stripes on the wall,
    # a plain colour per sphere.
    check = ((np.floor(u * 400) + np.floor(v * 400)) % 2).astype(np.float32)
    stripes = (np.floor(u * 150) % 2).astype(np.float32)
    alb = np.empty(shape + (3,), np.float32)
    alb[...] = 0.5
    for c, (a, b) in enumerate([(0.7, 0.3), (0.6, 0.4), (0.5, 0.45)]):
        alb[..., c] = np.where(obj == 1, a - 0.2 * stripes, a * check + b * (1 - check))
        for k in range(3):
            alb[..., c] = np.where(obj == 10 + k, 0.25 + 0.2 * ((k + c) % 3), alb[..., c])
    alb[~surface] = 0.0
    lambert = np.clip(nx * sun[0] + ny * sun[1] + nz * sun[2], 0.0, None)
    light = 0.25 + 0.9 * lambert
    rng = np.random.default_rng(y0)
    grain = 1.0 + 0.05 * rng.standard_normal(shape).astype(np.float32)
    px = np.zeros(shape + (len(names),), np.float32)
    px[..., 0:3] = np.where(surface[..., None], alb * (light * grain)[..., None], 0.08)
    px[..., 3] = 1.0
    px[..., 4:7] = alb
    px[..., 7], px[..., 8], px[..., 9] = nx * surface, ny * surface, nz * surface
    px[..., 10] = depth
    if not out.write_scanlines(y0, y1, 0, px):
        sys.exit("cannot write %s: %s" % (path, out.geterror()))
    print("\r  generating: %d%%" % (100 * y1 // n), end="", file=sys.stderr, flush=True)
print(file=sys.stderr)
out.close()
'''
    return subprocess.call(["/usr/bin/python3", "-c", code, path, str(n), str(BAND)])


def main():
    a = parse_args()
    if not os.access(a.zdenoise, os.X_OK):
        print("huge_frame.py: error: no zdenoise at '%s' (build it, or give --zdenoise)"
              % a.zdenoise, file=sys.stderr)
        return 2
    folder = a.dir or tempfile.mkdtemp(prefix="zdenoise_huge_")
    os.makedirs(folder, exist_ok=True)
    src = os.path.join(folder, "huge.exr")
    dst = os.path.join(folder, "huge_denoised.exr")
    try:
        print("huge_frame.py: %d x %d frame in '%s'" % (a.size, a.size, folder), file=sys.stderr)
        t0 = time.time()
        if generate(src, a.size) != 0:
            print("huge_frame.py: error: generating '%s' failed" % src, file=sys.stderr)
            return 2
        print("  generated in %.0f s (%.1f GiB)" % (time.time() - t0, os.path.getsize(src) / 2**30),
              file=sys.stderr)
        status, wall, peak, out = run_measured([a.zdenoise, "--in", src, "-o", dst, "-v"] + a.args)
        for line in out.splitlines():
            if "strips" in line or "whole frame" in line or line.startswith("zdenoise: read ") \
                    or line.startswith("zdenoise: windows"):
                print(line)
        print("huge frame %dx%d: zdenoise %s, wall %.1f s, peak RSS %.0f MiB (limit %.0f MiB)"
              % (a.size, a.size, "ok" if status == 0 else "FAILED (status %d)" % status,
                 wall, peak, a.max_rss))
        if status != 0 or peak >= a.max_rss:
            return 1
        return 0
    finally:
        if not a.keep and not a.dir:
            shutil.rmtree(folder, ignore_errors=True)
        elif not a.keep:
            for f in (src, dst):
                if os.path.exists(f):
                    os.remove(f)


if __name__ == "__main__":
    sys.exit(main())
