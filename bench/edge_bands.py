#!/usr/bin/python3
"""edge_bands.py - where a denoised image's error sits: in a band along the hard shadow edges
of the direct light, in the rest of the directly lit region, and elsewhere (issue 32, item 2).

    /usr/bin/python3 bench/edge_bands.py --ref SCENE_ref.exr IMG.exr [IMG.exr ...]

The regions come from the reference's direct diffuse light (Cycles' DiffDir pass, light
before the albedo, Rec.709 luminance L):
  lit   : L above a tenth of its 99.5th percentile (the sun patch and what the sun reaches);
  edge  : pixels whose 3x3 neighbourhood holds a lit pixel and one below a quarter of the
          neighbourhood's largest L (a hard shadow edge), dilated by BAND pixels (default 2);
  patch : lit pixels outside the band;
  rest  : the others.
For each image: relMSE (zmetrics' formula, mean over pixels and RGB of (x-ref)^2/(ref^2+1e-2))
over the whole frame and each region, and each region's share of the frame's squared error.
Images are EXRs with Combined (a Blender multilayer) or plain R,G,B.
"""
import argparse
import sys

import numpy as np
import OpenImageIO as oiio

LUMA = np.array([0.2126, 0.7152, 0.0722])


def channels(path, names):
    buf = oiio.ImageBuf(path)
    if buf.has_error:
        sys.exit(f'edge_bands.py: cannot read {path}: {buf.geterror()}')
    all_names = list(buf.spec().channelnames)
    px = buf.get_pixels(oiio.FLOAT)
    for group in names:
        idx = []
        for n in group:
            hits = [i for i, c in enumerate(all_names) if c == n or c.endswith('.' + n)]
            if not hits:
                break
            idx.append(hits[0])
        if len(idx) == len(group):
            return np.nan_to_num(px[:, :, idx].astype(np.float64), nan=0.0, posinf=0.0, neginf=0.0)
    sys.exit(f'edge_bands.py: {path} has none of {names}')


def shifted_extremes(a, r):
    """Max and min over the (2r+1)^2 neighbourhood (edges clamped)."""
    h, w = a.shape
    p = np.pad(a, r, mode='edge')
    hi = np.full_like(a, -np.inf)
    lo = np.full_like(a, np.inf)
    for dy in range(2 * r + 1):
        for dx in range(2 * r + 1):
            s = p[dy:dy + h, dx:dx + w]
            hi = np.maximum(hi, s)
            lo = np.minimum(lo, s)
    return hi, lo


def regions(ref_path, band):
    direct = channels(ref_path, [['DiffDir.R', 'DiffDir.G', 'DiffDir.B']]) @ LUMA
    bright = 0.1 * np.percentile(direct, 99.5)
    lit = direct > bright
    hi, lo = shifted_extremes(direct, 1)
    edge = (hi > bright) & (lo < 0.25 * hi)
    if band > 0:
        edge = shifted_extremes(edge.astype(np.float64), band)[0] > 0.5
    return {'edge band': edge, 'patch': lit & ~edge, 'rest': ~lit & ~edge}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--ref', required=True, help="the scene's reference (with DiffDir)")
    ap.add_argument('--band', type=int, default=2, help='dilation of the edges, pixels (2)')
    ap.add_argument('images', nargs='+')
    a = ap.parse_args()
    ref = channels(a.ref, [['Combined.R', 'Combined.G', 'Combined.B'], ['R', 'G', 'B']])
    reg = regions(a.ref, a.band)
    names = list(reg)
    print('image'.ljust(28) + ''.join(f'{n:>22}' for n in ['frame'] + names))
    print(''.ljust(28) + f'{"":>22}' + ''.join(f'{f"{reg[n].mean() * 100:.1f} % of pixels":>22}' for n in names))
    for path in a.images:
        img = channels(path, [['Combined.R', 'Combined.G', 'Combined.B'], ['R', 'G', 'B']])
        err = ((img - ref) ** 2 / (ref ** 2 + 1e-2)).mean(axis=2)
        total = err.sum()
        cells = [f'{err.mean():.5f}']
        for n in names:
            m = reg[n]
            cells.append(f'{err[m].mean() if m.any() else 0:.5f} ({err[m].sum() / total * 100:.0f} %)')
        print(path[-28:].ljust(28) + ''.join(f'{c:>22}' for c in cells))


if __name__ == '__main__':
    main()
