#!/usr/bin/python3
"""aux.py - what an auxiliary image (--aux) buys, per public case (docs/AUX.md).

For every case (scene x spp x seed) it denoises the noisy render with no flags, then with
`--aux AUX` for each auxiliary image asked for, under each demodulation (the internal switch
ZDENOISE_AUX_DEMODULATE: 'render' divides by the render's own albedo, 'aux' by the auxiliary
one; the auxiliary albedo remodulates either way), and prints the relMSE of each against
<scene>_ref.exr (Combined RGB, as tools/zmetrics.py computes it).

  --aux NAME=PATTERN   an auxiliary image per scene ({scene} is replaced); repeatable.
                       Default: ref={data}/{scene}/{scene}_albedo.exr (the reference's
                       clean Denoising Albedo).
  --demod render,aux   the demodulations to run (default both)
  --mode beauty|layers passed to zdenoise (default: zdenoise's own)

Usage: bench/aux.py [--zdenoise BIN] [--scenes ..] [--spp 4,16,64] [--seeds 1,2]
                    [--aux NAME=PATTERN ...] [--demod render,aux] [--mode M] [--json FILE]
                    [--lock FILE]
Runs with Debian's /usr/bin/python3 (OpenImageIO, numpy). Exit status 0; 2 on a setup error.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DATA = os.path.join(os.path.dirname(REPO), "shared", "data")
SCENES = ["cornell_textured", "newspaper", "zigzag_steps"]


def channels(path, layer=None):
    """R,G,B of a file (plain R,G,B, else <layer>.Combined), or of `layer`'s R,G,B."""
    # ImageInput, not ImageBuf: OIIO's ImageCache would serve an output
    # rewritten under the same name from its stale entry.
    inp = oiio.ImageInput.open(path)
    if inp is None:
        sys.exit(f"cannot read '{path}': {oiio.geterror()}")
    spec = inp.spec()
    names = list(spec.channelnames)
    if layer is None and all(c in names for c in "RGB"):
        idx = [names.index(c) for c in "RGB"]
    else:
        want = layer or "Combined"
        hits = [n for n in names if n.endswith("." + want + ".R")]
        if len(hits) != 1:
            sys.exit(f"no {want} RGB in '{path}'")
        idx = [names.index(hits[0][:-1] + c) for c in "RGB"]
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
    inp.close()
    px = px.reshape(spec.height, spec.width, spec.nchannels)
    return np.nan_to_num(px[:, :, idx].astype(np.float64))


def relmse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + 1e-2)))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    p.add_argument("--data", default=DATA)
    p.add_argument("--scenes", nargs="+", default=SCENES)
    p.add_argument("--spp", default="4,16,64")
    p.add_argument("--seeds", default="1,2")
    p.add_argument("--aux", action="append", default=[])
    p.add_argument("--demod", default="render,aux")
    p.add_argument("--mode", default="")
    p.add_argument("--threads", default="2")
    p.add_argument("--json", default="")
    p.add_argument("--lock", default="", help="run each zdenoise under flock LOCK")
    a = p.parse_args()
    auxes = [x.split("=", 1) for x in (a.aux or ["ref={data}/{scene}/{scene}_albedo.exr"])]
    demods = [d for d in a.demod.split(",") if d]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")

        def run(noisy, extra, env=None):
            cmd = (["flock", a.lock] if a.lock else []) + [
                a.zdenoise, "--in", noisy, "-o", out, "--threads", a.threads]
            if a.mode:
                cmd += ["--mode", a.mode]
            r = subprocess.run(cmd + extra, env=env, capture_output=True, text=True)
            if r.returncode:
                sys.exit(f"aux.py: {' '.join(cmd + extra)}: {r.stderr.strip()}")
            return channels(out)

        for scene in a.scenes:
            ref = channels(os.path.join(a.data, scene, f"{scene}_ref.exr"))
            for spp in a.spp.split(","):
                for seed in a.seeds.split(","):
                    noisy = os.path.join(a.data, scene, f"{scene}_spp{spp}_s{seed}.exr")
                    row = {"scene": scene, "spp": int(spp), "seed": int(seed),
                           "none": relmse(run(noisy, []), ref)}
                    for name, pattern in auxes:
                        path = pattern.format(scene=scene, data=a.data)
                        for d in demods:
                            env = dict(os.environ, ZDENOISE_AUX_DEMODULATE=d)
                            row[f"{name}/{d}"] = relmse(run(noisy, ["--aux", path], env), ref)
                    rows.append(row)
                    print(" ".join(f"{k}={v:.5f}" if isinstance(v, float) else f"{k}={v}"
                                   for k, v in row.items()), flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
