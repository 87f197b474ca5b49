#!/usr/bin/python3
"""aux_render.py - the cost and worth of share/blender/zdenoise_aux.py per public scene (docs/AUX.md).

For every scene (a .blend built by shared/scenes/<scene>.py --save-blend) it renders the
16-spp beauty (`blender -b SCENE.blend -f 1`) and the auxiliary image at each of --samples,
and prints per sample count:

  aux/beauty   Blender's own render time ("Time:", sync + render + save) of the auxiliary
               render over the beauty's
  albedo       relMSE of its Denoising Albedo against <scene>_albedo.exr (the reference's)
  spp S        relMSE against <scene>_ref.exr of `zdenoise --in <scene>_sppS_s1.exr` with
               no flags / with --aux <scene>_albedo.exr / with --aux the render (seed 1; and
               seed 2 with --seeds 1,2, averaged) / and with --oidn DIR (shared/peers'
               oidn-install, a yardstick run beside it) Intel OIDN given the same aux
               render's albedo and normal with its clean-aux model
  rejected     with --aux the render at the last spp, the pixels whose aux albedo zdenoise
               replaced by the render's own (its -v line)

Usage: bench/aux_render.py --blends DIR [--samples 4,8,16,32] [--spp 4,16,64] [--seeds 1]
                           [--scenes ..] [--data DIR] [--zdenoise BIN] [--blender BIN]
                           [--oidn DIR] [--lock FILE] [--json FILE]
--data DIR holds <scene>/<scene>_spp<S>_s<seed>.exr, <scene>_ref.exr and <scene>_albedo.exr
(shared/data, or the renders of bench/scenes/render_set.sh).
Runs with Debian's /usr/bin/python3 (OpenImageIO, numpy). Exit status 0; 2 on a setup error.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from aux import DATA, REPO, SCENES, channels, relmse  # noqa: E402
import peers  # noqa: E402  (OIDN, run as bench/peers.py runs it)

SCRIPT = os.path.join(REPO, "share", "blender", "zdenoise_aux.py")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--blends", required=True)
    p.add_argument("--samples", default="4,8,16,32")
    p.add_argument("--spp", default="4,16,64")
    p.add_argument("--seeds", default="1")
    p.add_argument("--scenes", nargs="+", default=SCENES)
    p.add_argument("--zdenoise", default=os.path.join(REPO, "build", "bin", "zdenoise"))
    p.add_argument("--blender", default="blender")
    p.add_argument("--data", default=DATA)
    p.add_argument("--oidn", default="", help="oidn-install directory (a yardstick)")
    p.add_argument("--lock", default="")
    p.add_argument("--json", default="")
    a = p.parse_args()
    lock = ["flock", a.lock] if a.lock else []

    def blender_time(cmd):
        r = subprocess.run(lock + cmd, capture_output=True, text=True)
        m = re.findall(r"^ Time: (\d+):(\d+\.\d+)", r.stdout, re.M)
        if r.returncode or not m:
            sys.exit(f"aux_render.py: {' '.join(cmd)} failed: {r.stderr.strip()[-400:]}")
        return int(m[-1][0]) * 60 + float(m[-1][1])

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.exr")

        last_log = [""]

        def denoised(noisy, extra):
            cmd = lock + [a.zdenoise, "--in", noisy, "-o", out, "--threads", "2", "-v"] + extra
            r = subprocess.run(cmd, capture_output=True, text=True)
            if r.returncode:
                sys.exit(f"aux_render.py: {' '.join(cmd)}: {r.stderr.strip()}")
            last_log[0] = r.stdout + r.stderr
            return channels(out, None)

        yardstick = peers.Peers(argparse.Namespace(oidn=a.oidn, shared=os.path.join(REPO, "..", "shared")),
                                tmp, lock)

        def oidn(noisy, aux):
            yardstick.oidn(noisy, aux, out, True)
            return channels(out, None)

        def rejected():
            m = re.search(r"the render's own used at (\d+) pixels \(([\d.]+) %\)", last_log[0])
            return float(m.group(2)) if m else None

        for scene in a.scenes:
            blend = os.path.join(a.blends, f"{scene}.blend")
            d = os.path.join(a.data, scene)
            ref = channels(os.path.join(d, f"{scene}_ref.exr"), None)
            ref_albedo_path = os.path.join(d, f"{scene}_albedo.exr")
            ref_albedo = channels(ref_albedo_path, None)
            beauty = blender_time([a.blender, "-b", "-noaudio", blend, "-o",
                                   os.path.join(tmp, "beauty_#"), "-F", "OPEN_EXR_MULTILAYER",
                                   "-f", "1"])
            base = {}
            for spp in a.spp.split(","):
                for seed in a.seeds.split(","):
                    noisy = os.path.join(d, f"{scene}_spp{spp}_s{seed}.exr")
                    base[(spp, seed)] = (relmse(denoised(noisy, []), ref),
                                         relmse(denoised(noisy, ["--aux", ref_albedo_path]), ref))
            for samples in a.samples.split(","):
                aux = os.path.join(tmp, f"aux_{samples}.exr")
                t = blender_time([a.blender, "-b", "-noaudio", blend, "--python-exit-code", "1",
                                  "-P", SCRIPT, "--", "-o", aux, "--samples", samples])
                row = {"scene": scene, "samples": int(samples), "aux_s": t, "beauty_s": beauty,
                       "aux/beauty": t / beauty,
                       "albedo": relmse(channels(aux, "Denoising Albedo"), ref_albedo)}
                for spp in a.spp.split(","):
                    none = refa = mine = peer = 0.0
                    seeds = a.seeds.split(",")
                    for seed in seeds:
                        noisy = os.path.join(d, f"{scene}_spp{spp}_s{seed}.exr")
                        none += base[(spp, seed)][0] / len(seeds)
                        refa += base[(spp, seed)][1] / len(seeds)
                        mine += relmse(denoised(noisy, ["--aux", aux]), ref) / len(seeds)
                        row["rejected %"] = rejected()
                        if a.oidn:
                            peer += relmse(oidn(noisy, aux), ref) / len(seeds)
                    row[f"spp{spp}"] = [none, refa, mine] + ([peer] if a.oidn else [])
                rows.append(row)
                print(json.dumps(row), flush=True)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
