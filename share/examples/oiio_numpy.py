#!/usr/bin/env python3
# Copyright zdenoise contributors.
# SPDX-License-Identifier: BSD-3-Clause
"""Denoise a Blender Cycles render with OpenImageIO's Python ImageBuf and
zdenoise.denoise() on numpy arrays.

    python3 oiio_numpy.py render.exr denoised.exr [key=value ...]

For example, on the bundled sample:

    python3 oiio_numpy.py share/samples/cornell_textured_spp16_crop.exr out.exr eta=0.03

The render is a Cycles multilayer EXR (channels <layer>.Combined.R, ...,
<layer>.Denoising Albedo.R, ...): its pixels come out of an ImageBuf as one
H x W x C numpy array (get_pixels), the channels of each role are picked by
name, the beauty is denoised, and the result goes back into an ImageBuf
(set_pixels) with every other channel and the metadata of the input, and is
written. Its beauty is the one `zdenoise --in render.exr` writes (with the
same filter options; the command also manages colour, which a scene-linear
EXR does not need, and streams large frames in strips).

zdenoise.denoise_file("render.exr", "denoised.exr") does all of this in one
call; this example is for images that are arrays already (a compositor's,
a renderer's) or channels the conventions do not name.
"""

import sys

import numpy as np
import OpenImageIO as oiio

import zdenoise


def layer_prefix(names):
    """The view layer of a Cycles multilayer EXR: "ViewLayer." of
    "ViewLayer.Combined.R"."""
    for name in names:
        if name.endswith(".Combined.R"):
            return name[: -len("Combined.R")]
    raise SystemExit("no <layer>.Combined.R channel: not a Blender Cycles "
                     "multilayer EXR")


def pick(pixels, names, prefix, *channels, required=True):
    """The H x W x len(channels) array of the named channels (None when one
    is missing and not required)."""
    missing = [c for c in channels if prefix + c not in names]
    if missing:
        if required:
            raise SystemExit("no channel " + prefix + missing[0])
        return None
    return pixels[:, :, [names.index(prefix + c) for c in channels]]


def option_value(text):
    """"0.03" -> 0.03, "8" -> 8, "spec" -> "spec"."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def main(argv):
    if len(argv) < 3:
        raise SystemExit(__doc__)
    source, target = argv[1], argv[2]
    options = {}
    for arg in argv[3:]:
        key, _, value = arg.partition("=")
        options[key] = option_value(value)

    image = oiio.ImageBuf(source)
    # All channels as float32, H x W x C.
    pixels = image.get_pixels(oiio.FLOAT)
    if image.has_error or pixels is None:
        raise SystemExit(image.geterror() or "cannot read " + source)
    spec = image.spec()
    names = list(spec.channelnames)
    prefix = layer_prefix(names)

    # The beauty with its alpha (copied; 0 marks "no surface").
    beauty = ["Combined.R", "Combined.G", "Combined.B", "Combined.A"]
    if prefix + "Combined.A" not in names:
        beauty = beauty[:3]
    radiance = pick(pixels, names, prefix, *beauty)
    albedo = pick(pixels, names, prefix, "Denoising Albedo.R",
                  "Denoising Albedo.G", "Denoising Albedo.B")
    normal = pick(pixels, names, prefix, "Denoising Normal.X",
                  "Denoising Normal.Y", "Denoising Normal.Z", required=False)
    depth = pick(pixels, names, prefix, "Denoising Depth.Z", required=False)
    # Object ids: the Cryptomatte ranks, (id, coverage) pairs, else IndexOB.
    ranks = sorted({n[len(prefix):-2] for n in names
                    if n.startswith(prefix + "CryptoObject")})
    crypto = [rank + "." + c for rank in ranks for c in "rgba"]
    ids = (pick(pixels, names, prefix, *crypto, required=False) if crypto
           else pick(pixels, names, prefix, "IndexOB.X", required=False))

    # The render's albedo AOV is noisy where its samples anti-alias texture
    # and edges: prefiltered given its samples per pixel, which Cycles
    # records as cycles.<view layer>.samples (as the command reads it).
    samples = spec.get_string_attribute("cycles." + prefix + "samples")
    if samples.isdigit() and "albedo_samples" not in options:
        options["albedo_samples"] = int(samples)

    denoised = zdenoise.denoise(radiance, albedo, normal=normal, depth=depth,
                                ids=ids, **options)

    pixels[:, :, [names.index(prefix + c) for c in beauty]] = denoised
    # The input's channels and metadata, in float.
    out_spec = oiio.ImageSpec(spec)
    out_spec.set_format(oiio.FLOAT)
    out = oiio.ImageBuf(out_spec)
    if not out.set_pixels(oiio.ROI.All, pixels) or not out.write(target):
        raise SystemExit(out.geterror())
    print("denoised %s (%dx%d, %d channels) -> %s"
          % (source, spec.width, spec.height, spec.nchannels, target))


if __name__ == "__main__":
    main(sys.argv)
