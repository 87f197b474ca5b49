#!/usr/bin/env python3
"""--aov NAME measured: radiance AOVs denoised against the reference's, on the public set and
bench/scenes renders. The AOVs are Cycles' Emit and Env and, as custom radiance AOVs (an LPE
would give them), the lobe passes times their colour: DiffInd x DiffCol as DiffIndLight, and
so on; they are added to a float copy of the render (and of the reference) first.

    /usr/bin/python3 bench/aovs.py ZDENOISE DATA_DIR [RENDERS_DIR] > table.md

DATA_DIR is shared/data (<scene>/<scene>_spp{4,16,64}_s1.exr, <scene>_ref.exr); RENDERS_DIR
holds bench/scenes renders as <scene>/<scene>_spp{N}_s1.exr and <scene>_ref.exr. Prints one
row per scene, spp and pass: the input's relMSE, the AOV's, their ratio and the light kept
(output mean over input mean). Passes whose reference is black are skipped.
"""
import glob
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

PASSES = ["Emit", "Env", "DiffIndLight", "GlossDirLight", "GlossIndLight", "TransIndLight",
          "VolumeDir", "VolumeInd"]
PRODUCTS = {"DiffIndLight": ("DiffInd", "DiffCol"), "GlossDirLight": ("GlossDir", "GlossCol"),
            "GlossIndLight": ("GlossInd", "GlossCol"), "TransIndLight": ("TransInd", "TransCol")}


def planes(path):
    """The file's pixels (float) and channel names, with the PRODUCTS added."""
    inp = oiio.ImageInput.open(path)
    spec = inp.spec()
    px = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT).reshape(spec.height, spec.width, -1)
    names = list(spec.channelnames)
    extra = []
    for name, (light, colour) in PRODUCTS.items():
        if f"ViewLayer.{light}.R" in names and f"ViewLayer.{colour}.R" in names:
            extra.append(rgb(px, names, light) * rgb(px, names, colour))
            names += [f"ViewLayer.{name}.{c}" for c in "RGB"]
    return (np.concatenate([px] + extra, axis=-1) if extra else px), names


def write_copy(px, names, template, path):
    """px as a float EXR with the metadata of the file `template`."""
    spec = oiio.ImageInput.open(template).spec()
    out_spec = oiio.ImageSpec(spec.width, spec.height, len(names), oiio.FLOAT)
    out_spec.channelnames = names
    for a in spec.extra_attribs:
        out_spec.attribute(a.name, a.type, a.value)
    out = oiio.ImageOutput.create(path)
    out.open(path, out_spec)
    out.write_image(np.ascontiguousarray(px))
    out.close()


def rgb(px, names, layer):
    idx = [names.index(f"ViewLayer.{layer}.{c}") for c in "RGB"] if f"ViewLayer.{layer}.R" in names else None
    return None if idx is None else px[..., idx]


def relmse(x, ref):
    return float(np.mean((x - ref) ** 2 / (ref ** 2 + 1e-2)))


def main():
    exe, dirs = sys.argv[1], sys.argv[2:]
    print("| scene | spp | pass | input relMSE | AOV relMSE | ratio | light kept |")
    print("|---|---|---|---|---|---|---|")
    for d in dirs:
        for ref_path in sorted(glob.glob(os.path.join(d, "*", "*_ref.exr"))):
            scene = os.path.basename(os.path.dirname(ref_path))
            ref_px, ref_names = planes(ref_path)
            for spp in (4, 16, 64):
                noisy = os.path.join(d, scene, f"{scene}_spp{spp}_s1.exr")
                if not os.path.exists(noisy):
                    continue
                n_px, n_names = planes(noisy)
                todo = [p for p in PASSES if rgb(n_px, n_names, p) is not None
                        and rgb(ref_px, ref_names, p) is not None
                        and rgb(ref_px, ref_names, p).max() > 0]
                if not todo:
                    continue
                with tempfile.TemporaryDirectory() as tmp:
                    out, copy = os.path.join(tmp, "out.exr"), os.path.join(tmp, "in.exr")
                    write_copy(n_px, n_names, noisy, copy)
                    cmd = [exe, "--in", copy, "-o", out]
                    for p in todo:
                        cmd += ["--aov", p]
                    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                    o_px, o_names = planes(out)
                for p in todo:
                    ref, n, o = (rgb(ref_px, ref_names, p), rgb(n_px, n_names, p),
                                 rgb(o_px, o_names, p))
                    a, b = relmse(n, ref), relmse(o, ref)
                    print(f"| {scene} | {spp} | {p} | {a:.5f} | {b:.5f} | {b / a:.2f} | "
                          f"{o.mean() / n.mean():.4f} |", flush=True)


if __name__ == "__main__":
    main()
