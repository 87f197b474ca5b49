#!/usr/bin/python3
"""path_mode.py - zdenoise's modes side by side, whole frame, sunlit region and 8x8 tiles.

For each noisy render SCENE_sppN_sS.exr (the layout of shared/data and of
bench/scenes/render_set.sh) under each --data folder, runs `zdenoise --mode M` for every
mode of --modes and prints, against SCENE_ref.exr (Combined RGB):

* relMSE of the whole frame, and each mode's ratio to the first mode;
* relMSE over the sunlit region: the brightest 15 % of the reference's direct diffuse light
  (DiffDir x DiffCol);
* "tiles worse": the number of 8x8 tiles whose relMSE is above the noisy input's by more
  than 1e-4, and the largest such excess (issue 44's count of regions made worse).

Two optional columns per run (issue 45's targets): `--materials 20,21,22` adds the relMSE over
the pixels whose reference `IndexMA` is one of these material indices (bench/scenes/metal_tiles'
metal spheres); `--box 31` adds the relMSE of 31x31 box means (the image and the reference both
averaged over every 31x31 window: the low-frequency error, the blotches a per-pixel relMSE
hides under the noise).

A mode named `default` runs zdenoise with no flags; `LABEL=FLAGS` runs it with FLAGS
(`--modes "default,r24=--energy-radius 24"`). `--baseline BIN` adds a first column,
`today`: another build's zdenoise with no flags (the default before a change). `--oidn DIR`
adds a last column: Intel OIDN 2.4 (--hdr, the file's own albedo and normal, as
bench/peers.py runs it), and each column's relMSE ratio to it. With `--oidn`, `--targets`
then prints issue 45's targets per scene (the first mode against OIDN, and against the
second mode) and how many cases are within each limit.

    bench/path_mode.py --data ../shared/data --data /renders           # every case found
    bench/path_mode.py --data ../shared/data --spp 16 --seeds 1 --scenes zigzag_steps
    bench/path_mode.py --data RENDERS --modes default --baseline OLD/zdenoise --oidn OIDN_DIR
    bench/path_mode.py --data ../shared/data --data RENDERS --modes default,beauty \
        --oidn OIDN_DIR --box 31 --materials 20,21,22 --targets      # issue 45's table

Runs with Debian's /usr/bin/python3 (OpenImageIO, numpy). Exit 0, or 2 on a setup error.
"""
import argparse
import glob
import os
import re
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def channels(path, names):
    buf = oiio.ImageBuf(path)
    spec = buf.spec()
    pixels = buf.get_pixels(oiio.FLOAT)
    missing = [n for n in names if n not in spec.channelnames]
    if missing:
        return None
    return np.stack([pixels[..., spec.channelnames.index(n)] for n in names], -1)


def rgb(path, layer):
    return channels(path, [f"ViewLayer.{layer}.{c}" for c in "RGB"])


def rel_error(img, ref):
    return ((img - ref) ** 2 / (ref * ref + 1e-2)).mean(-1)


def tiles_worse(out, noisy, ref):
    e, e0 = rel_error(out, ref), rel_error(noisy, ref)
    h, w = (e.shape[0] // 8) * 8, (e.shape[1] // 8) * 8
    t = e[:h, :w].reshape(h // 8, 8, w // 8, 8).mean((1, 3))
    t0 = e0[:h, :w].reshape(h // 8, 8, w // 8, 8).mean((1, 3))
    excess = t - t0
    return int((excess > 1e-4).sum()), float(max(excess.max(), 0.0))


def box_means(img, size):
    """Mean over every size x size window that fits (a summed-area table)."""
    s = np.pad(img.astype(np.float64).cumsum(0).cumsum(1), ((1, 0), (1, 0), (0, 0)))
    return (s[size:, size:] - s[:-size, size:] - s[size:, :-size] + s[:-size, :-size]) / (size * size)


def cases(args):
    pattern = re.compile(r"(.+)_spp(\d+)_s(\d+)\.exr$")
    for data in args.data:
        for path in sorted(glob.glob(os.path.join(data, "*", "*_spp*_s*.exr"))):
            m = pattern.match(os.path.basename(path))
            if not m:
                continue
            scene, spp, seed = m.group(1), int(m.group(2)), int(m.group(3))
            ref = os.path.join(os.path.dirname(path), f"{scene}_ref.exr")
            if (args.scenes and scene not in args.scenes) or spp not in args.spp \
                    or seed not in args.seeds or not os.path.exists(ref):
                continue
            yield scene, spp, seed, path, ref


def print_targets(records, labels, args):
    """Issue 45's targets, from the rows above: per scene the first run's relMSE over
    OIDN's (seed 1 / seed 2) at each spp, its 31x31 box means' over OIDN's at the lowest
    spp, its region's (--materials) over OIDN's, and its worst ratio to the second run
    (beauty mode in `--modes default,beauty`); then how many cases pass each limit."""
    first, second = labels[0], labels[1] if len(labels) > 1 else None
    spps, seeds = sorted({r[1] for r in records}), sorted({r[2] for r in records})
    head = ["scene"] + [f"{first} / OIDN, {n} spp" for n in spps]
    head += [f"box{args.box} / OIDN, {spps[0]} spp"] if args.box else []
    head += [f"region / OIDN, {n} spp" for n in spps] if args.materials else []
    head += [f"{first} / {second}, worst"] if second else []
    print()
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    by = {(r[0], r[1], r[2]): r[3] for r in records}
    nan = float("nan")
    ratio = lambda n, key: n[0].get(key, nan) / n[-1].get(key, nan)
    count = {"frame": [0, 0], "box": [0, 0], "region": [0, 0], "second": [0, 0]}

    def tally(name, value, limit):
        if value == value:  # NaN: no such column for this case
            count[name][0] += value <= limit
            count[name][1] += 1

    def cell(scene, spp, key):
        values = [ratio(by[scene, spp, s], key) if (scene, spp, s) in by else nan for s in seeds]
        return "/".join(f"{v:.2f}" if v == v else "-" for v in values)

    for scene in dict.fromkeys(r[0] for r in records):
        cols = [scene] + [cell(scene, n, "whole") for n in spps]
        cols += [cell(scene, spps[0], "box")] if args.box else []
        cols += [cell(scene, n, "region") for n in spps] if args.materials else []
        worst = [n[0]["whole"] / n[1]["whole"] for (sc, _, _), n in by.items() if sc == scene]
        cols += [f"{max(worst):.3f}"] if second else []
        print("| " + " | ".join(cols) + " |")
    for (scene, spp, seed), n in by.items():
        tally("frame", ratio(n, "whole"), 2.0 if spp == spps[0] else 1.25)
        if args.box and spp == spps[0]:
            tally("box", ratio(n, "box"), 1.25)
        if args.materials and spp != spps[0]:
            tally("region", ratio(n, "region"), 1.5)
        if second:
            tally("second", n[0]["whole"] / n[1]["whole"], 1.02)
    print()
    parts = [f"frame (2x at {spps[0]} spp, 1.25x above) {count['frame'][0]} of {count['frame'][1]} cases"]
    if args.box:
        parts.append(f"box means at {spps[0]} spp (1.25x) {count['box'][0]} of {count['box'][1]}")
    if args.materials:
        parts.append(f"region above {spps[0]} spp (1.5x) {count['region'][0]} of {count['region'][1]}")
    if second:
        parts.append(f"{first} at most 1.02x {second} {count['second'][0]} of {count['second'][1]}")
    print("Within the limits: " + "; ".join(parts) + ".")

def run(args, mode):
    """(label, command) of one --modes entry: `M` is `--mode M` (`default`: no flags);
    `LABEL=FLAGS` is zdenoise with FLAGS, split at spaces."""
    if "=" in mode:
        label, flags = mode.split("=", 1)
        return label, [args.zdenoise] + flags.split()
    return mode, [args.zdenoise] + ([] if mode == "default" else ["--mode", mode])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", action="append", default=[])
    ap.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    ap.add_argument("--modes", default="beauty,path")
    ap.add_argument("--spp", default="4,16,64")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--scenes", default="")
    ap.add_argument("--baseline", help="another zdenoise: its no-flags output is the first column")
    ap.add_argument("--oidn", help="extracted oidn-install directory: adds OIDN's column")
    ap.add_argument("--materials", default="", help="IndexMA values: adds their region's relMSE")
    ap.add_argument("--box", type=int, default=0, help="N: adds the relMSE of NxN box means")
    ap.add_argument("--targets", action="store_true",
                    help="with --oidn: then print issue 45's targets per scene (print_targets)")
    args = ap.parse_args()
    args.data = args.data or [os.path.join(REPO, "..", "shared", "data")]
    args.spp = [int(s) for s in args.spp.split(",")]
    args.seeds = [int(s) for s in args.seeds.split(",")]
    args.scenes = [s for s in args.scenes.split(",") if s]
    args.materials = [float(s) for s in args.materials.split(",") if s]
    extra = (["materials"] if args.materials else []) + ([f"box{args.box}"] if args.box else [])
    modes = args.modes.split(",")
    if not os.access(args.zdenoise, os.X_OK):
        print(f"path_mode.py: no zdenoise at {args.zdenoise}", file=sys.stderr)
        return 2
    runs = ([("today", [args.baseline])] if args.baseline else []) + [run(args, m) for m in modes]
    head = ["scene", "spp", "seed"]
    for label, _ in runs:
        head += [f"{label} relMSE", "ratio", "sunlit", "tiles worse (max)"] + extra
    if args.oidn:
        head += ["OIDN relMSE", "sunlit", "tiles worse (max)"] + extra + [
            f"{label} / OIDN" for label, _ in runs]
    print(" | ".join(head))
    tmp = tempfile.mkdtemp(prefix="zd_path_mode_")
    peers = None
    if args.oidn:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        import peers as peers_module
        peers = peers_module.Peers(argparse.Namespace(
            oidn=args.oidn, shared=os.path.join(REPO, "..", "shared")), tmp)
    records = []
    for scene, spp, seed, path, ref_path in cases(args):
        ref = rgb(ref_path, "Combined")
        noisy = rgb(path, "Combined")
        direct = rgb(ref_path, "DiffDir")
        colour = rgb(ref_path, "DiffCol")
        lum = lambda x: x @ np.array([0.2126, 0.7152, 0.0722], np.float32)
        sun = None
        if direct is not None and colour is not None:
            y = lum(direct * colour)
            sun = y > np.percentile(y, 85)
        ref_box = box_means(ref, args.box) if args.box else None
        region = None
        if args.materials:
            index = channels(ref_path, ["ViewLayer.IndexMA.X"])
            region = np.isin(np.rint(index[..., 0]), args.materials) if index is not None else None

        def scores(img):
            """relMSE, the sunlit region's, tiles worse, and the optional columns
            (as text, and as numbers in `record`, NaN where there is none)."""
            e = rel_error(img, ref)
            sunlit = float(e[sun].mean()) if sun is not None else float("nan")
            extras, numbers = [], {"whole": float(e.mean())}
            if args.materials:
                has = region is not None and region.any()
                numbers["region"] = float(e[region].mean()) if has else float("nan")
                extras.append(f"{numbers['region']:.5f}" if has else "-")
            if args.box:
                numbers["box"] = float(rel_error(box_means(img, args.box), ref_box).mean())
                extras.append(f"{numbers['box']:.6f}")
            record[-1].append(numbers)
            return float(e.mean()), sunlit, tiles_worse(img, noisy, ref), extras

        row, first, wholes = [scene, str(spp), str(seed)], None, []
        records.append((scene, spp, seed, []))
        record = records[-1]
        for label, cmd in runs:
            out = os.path.join(tmp, f"{label}.exr")
            subprocess.run(cmd + ["--in", path, "-o", out], check=True,
                           stdout=subprocess.DEVNULL)
            img = rgb(out, "Combined")
            whole, sunlit, (worse, excess), extras = scores(img)
            first = first or whole
            wholes.append(whole)
            row += [f"{whole:.5f}", f"{whole / first:.3f}", f"{sunlit:.5f}",
                    f"{worse} ({excess:.3f})"] + extras
        if peers:
            out = os.path.join(tmp, "oidn.exr")
            peers.oidn(path, path, out, False)
            buf = oiio.ImageBuf(out)
            img = buf.get_pixels(oiio.FLOAT)[..., :3]
            whole, sunlit, (worse, excess), extras = scores(img)
            row += [f"{whole:.5f}", f"{sunlit:.5f}", f"{worse} ({excess:.3f})"] + extras
            row += [f"{w / whole:.2f}" for w in wholes]
        print(" | ".join(row), flush=True)
    if args.targets and peers:
        print_targets(records, [label for label, _ in runs], args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
