#!/usr/bin/python3
"""light.py - what the filtering does to the light, per public case (docs/FILTER.md, "Light").

For every case (scene x spp x seed) it runs `zdenoise --in NOISY -o OUT [ARGS]` (or reads
OUT from --outputs DIR, named <scene>_<spp>_<seed>_<tag>.exr) and prints:

  relMSE        against <scene>_ref.exr (Combined RGB), as tools/zmetrics.py computes it
  mean/ref      the output's mean over pixels and RGB divided by the reference's (energy)
  noisy/ref     the same for the noisy input (what an unbiased filter keeps)
  invented      pixels with a channel above 1.05x the brightest noisy value of that channel
                within 16 px (a 33x33 window)
  max x         the largest such ratio
  negative      pixels with a channel below 0 where the noisy input's is >= 0

Usage:
  bench/light.py [--zdenoise BIN] [--args "..."] [--input PATTERN] [--tag T] [--scenes ..] [--spp 4,16,64]
                 [--seeds 1,2] [--outputs DIR] [--keep DIR] [--json FILE]
Runs with Debian's /usr/bin/python3 (OpenImageIO, numpy). Exit status 0; 2 on a setup error.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
SCENES = ["cornell_textured", "newspaper", "zigzag_steps"]


def combined(path):
    buf = oiio.ImageBuf(path)
    spec = buf.spec()
    names = list(spec.channelnames)
    if all(c in names for c in "RGB"):
        idx = [names.index(c) for c in "RGB"]
    else:
        idx = [names.index(n) for n in names if n.endswith(".Combined.R")]
        if len(idx) != 1:
            sys.exit(f"light.py: no Combined RGB in '{path}'")
        i = idx[0]
        idx = [i, names.index(names[i][:-1] + "G"), names.index(names[i][:-1] + "B")]
    px = buf.get_pixels(oiio.FLOAT).reshape(spec.height, spec.width, spec.nchannels)
    return px[:, :, idx].astype(np.float64)


def local_max(img, radius):
    """Max over the (2r+1)^2 window of each pixel, per channel (edges: the window clipped)."""
    out = img.copy()
    for axis in (0, 1):
        pad = [(0, 0)] * img.ndim
        pad[axis] = (radius, radius)
        p = np.pad(out, pad, mode="constant", constant_values=-np.inf)
        n = out.shape[axis]
        acc = np.full_like(out, -np.inf)
        for k in range(2 * radius + 1):
            sl = [slice(None)] * img.ndim
            sl[axis] = slice(k, k + n)
            acc = np.maximum(acc, p[tuple(sl)])
        out = acc
    return out


def rel_mse(img, ref):
    return float(np.mean((img - ref) ** 2 / (ref ** 2 + 1e-2)))


def light_metrics(out, noisy, ref):
    finite = np.where(np.isfinite(noisy), noisy, -np.inf)
    bound = 1.05 * local_max(finite, 16)
    over = out > np.maximum(bound, 0.0) + 1e-6
    ratio = np.where(over, out / np.maximum(bound / 1.05, 1e-12), 0.0)
    negative = (out < 0) & (np.nan_to_num(noisy, nan=0.0) >= 0)
    noisy_mean = float(np.mean(np.nan_to_num(noisy, nan=0.0, posinf=0.0, neginf=0.0)))
    return {
        "relmse": rel_mse(out, ref),
        "mean_ratio": float(np.mean(out) / np.mean(ref)),
        "noisy_ratio": noisy_mean / float(np.mean(ref)),
        "invented": int(np.count_nonzero(over.any(axis=2))),
        "max_ratio": float(ratio.max()) if over.any() else 0.0,
        "negative": int(np.count_nonzero(negative.any(axis=2))),
        "min": float(out.min()),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    ap.add_argument("--shared", default=os.path.join(os.path.dirname(REPO), "shared"))
    ap.add_argument("--args", default="")
    ap.add_argument("--input", default="{data}/{scene}/{scene}_spp{spp}_s{seed}.exr",
                    help="the noisy input; {data} {scene} {spp} {seed} are replaced (also in --args)")
    ap.add_argument("--tag", default="beauty")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--spp", default="4,16,64")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--outputs", help="read <scene>_<spp>_<seed>_<tag>.exr from DIR, run nothing")
    ap.add_argument("--keep", help="write outputs to DIR")
    ap.add_argument("--json")
    a = ap.parse_args()
    data = os.path.join(a.shared, "data")
    if not os.path.isdir(data):
        print(f"light.py: no data folder '{data}'", file=sys.stderr)
        return 2
    work = a.outputs or a.keep or tempfile.mkdtemp(prefix="zd_light_")
    os.makedirs(work, exist_ok=True)
    rows = []
    print(f"{'case':<28} {'relMSE':>9} {'mean/ref':>9} {'noisy/ref':>9} {'invented':>8} "
          f"{'max x':>6} {'negative':>8} {'min':>9}")
    for scene in a.scenes.split(","):
        ref = combined(os.path.join(data, scene, f"{scene}_ref.exr"))
        for spp in a.spp.split(","):
            for seed in a.seeds.split(","):
                def fill(t):
                    return (t.replace("{scene}", scene).replace("{spp}", spp)
                            .replace("{seed}", seed).replace("{data}", data))
                noisy_path = fill(a.input)
                out_path = os.path.join(work, f"{scene}_{spp}_{seed}_{a.tag}.exr")
                if not a.outputs:
                    cmd = [a.zdenoise, "--in", noisy_path, "-o", out_path] + shlex.split(fill(a.args))
                    r = subprocess.run(cmd, capture_output=True, text=True)
                    if r.returncode != 0:
                        print(f"light.py: {' '.join(cmd)}: {r.stderr.strip()}", file=sys.stderr)
                        return 1
                m = light_metrics(combined(out_path), combined(noisy_path), ref)
                m["case"] = f"{scene} {spp} s{seed}"
                rows.append(m)
                print(f"{m['case']:<28} {m['relmse']:9.5f} {m['mean_ratio']:9.4f} "
                      f"{m['noisy_ratio']:9.4f} {m['invented']:8d} {m['max_ratio']:6.2f} "
                      f"{m['negative']:8d} {m['min']:9.3g}", flush=True)
    worst = max(abs(r["mean_ratio"] - 1) for r in rows)
    print(f"worst energy error {100 * worst:.2f} %, invented {sum(r['invented'] for r in rows)}, "
          f"negative {sum(r['negative'] for r in rows)}")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
