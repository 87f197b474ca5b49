#!/usr/bin/python3
"""temporal.py - flicker, middle-frame error and ghosting of --temporal K (issue 19,
docs/TEMPORAL.md) against single-frame zdenoise, on the sequences that
bench/temporal/render_sequences.sh renders.

    /usr/bin/python3 bench/temporal.py [--dir /tmp/zdenoise_temporal] [--k 2]

Per sequence (static: a fixed camera, a new seed per frame; pan: a panning
camera and a moving sphere):
  flicker   mean over pixels and RGB of the squared difference of consecutive
            output frames (the pan: frame 4 against frame 5 at the place the
            reference's vectors take each pixel, on pixels visible in both),
            for single-frame and temporal; the pan's also divided by the same
            for the 1024-spp references of frames 4 and 5, and the same on
            the light (radiance over the references' albedo), where the
            nearest pixel's misregistration of texture cancels;
  relMSE    of the middle frame (4) against its high-sample reference;
  ghost     relMSE of frame 4 on the pixels disoccluded since frame 3 or
            until frame 5 (by the reference's vectors and object ids).
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

HERE = os.path.dirname(os.path.abspath(__file__))
LAYER = 'ViewLayer.'


def load(path, names):
    buf = oiio.ImageBuf(path)
    spec = buf.spec()
    idx = [spec.channelnames.index(LAYER + n) for n in names]
    px = buf.get_pixels(oiio.FLOAT)
    return px[:, :, idx]


def rgb(path):
    return load(path, ['Combined.R', 'Combined.G', 'Combined.B'])


def rel_mse(img, ref, mask=None):
    e = (img - ref) ** 2 / (ref * ref + 1e-2)
    if mask is not None:
        e = e[mask]
    return float(np.mean(e))


def to_next(path):
    """Where each pixel of the frame shows in the next frame (x right, y
    down), from Cycles' Vector pass; the convention of
    src/job/neighbour_frames.cpp (vector_flow)."""
    v = load(path, ['Vector.X', 'Vector.Y', 'Vector.Z', 'Vector.W'])
    return np.stack([-v[:, :, 2], v[:, :, 3]], axis=-1)


def to_previous(path):
    v = load(path, ['Vector.X', 'Vector.Y', 'Vector.Z', 'Vector.W'])
    return np.stack([v[:, :, 0], -v[:, :, 1]], axis=-1)


def correspondence(flow, ids_from, ids_to, depth_from, depth_to):
    """For each pixel: the nearest pixel of p + flow in the other frame and
    whether it shows the same surface (the same object, depth within 5 %)."""
    h, w = ids_from.shape
    ys, xs = np.mgrid[0:h, 0:w]
    qx = np.floor(xs + 0.5 + flow[:, :, 0]).astype(np.int64)
    qy = np.floor(ys + 0.5 + flow[:, :, 1]).astype(np.int64)
    inside = (qx >= 0) & (qx < w) & (qy >= 0) & (qy < h) & np.isfinite(flow).all(-1)
    qx = np.clip(qx, 0, w - 1)
    qy = np.clip(qy, 0, h - 1)
    same = inside & (ids_to[qy, qx] == ids_from) & (
        np.abs(depth_to[qy, qx] - depth_from) <= 0.05 * depth_from)
    return qy, qx, same


def run(zdenoise, pattern, frames, out_pattern, extra):
    cmd = [zdenoise, '--in', pattern, '--frames', frames, '-o', out_pattern] + extra
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit('zdenoise failed: ' + ' '.join(cmd) + '\n' + r.stderr)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--dir', default='/tmp/zdenoise_temporal')
    ap.add_argument('--k', type=int, default=2)
    ap.add_argument('--frames', default='1-8')
    ap.add_argument('--zdenoise', default=os.path.join(HERE, '..', 'build', 'bin', 'zdenoise'))
    ap.add_argument('--args', default='', help='more zdenoise arguments for both runs')
    ap.add_argument('--aux', action='store_true',
                    help='give both runs the deterministic aux images <seq>_aux.#.exr '
                         '(share/blender/zdenoise_aux.py --frame F; docs/AUX.md)')
    a = ap.parse_args()
    first, last = (int(x) for x in a.frames.split('-'))
    out = tempfile.mkdtemp(prefix='zdenoise_temporal_bench_')
    print('| sequence | flicker single | flicker K=%d | ratio | flicker / references\' '
          '(single, K=%d) | light flicker ratio | light flicker / references\' (single, K=%d) '
          '| relMSE frame 4 single | K=%d | ghost relMSE single | K=%d |'
          % (a.k, a.k, a.k, a.k, a.k))
    print('|---|---|---|---|---|---|---|---|---|---|---|')
    for seq in ('static', 'pan'):
        pattern = os.path.join(a.dir, seq + '.#.exr')
        single = os.path.join(out, seq + '_single.#.exr')
        temporal = os.path.join(out, seq + '_k.#.exr')
        extra = ['--aux', os.path.join(a.dir, seq + '_aux.#.exr')] if a.aux else []
        extra += a.args.split()
        run(a.zdenoise, pattern, a.frames, single, extra)
        run(a.zdenoise, pattern, a.frames, temporal, extra + ['--temporal', str(a.k)])
        frame = lambda p, f: p.replace('#', '%04d' % f)
        ref4 = os.path.join(a.dir, seq + '_ref.0004.exr')
        ref5 = os.path.join(a.dir, seq + '_ref.0005.exr')
        row = {}
        for name, p in (('single', single), ('k', temporal)):
            outs = {f: rgb(frame(p, f)) for f in range(first, last + 1)}
            if seq == 'static':
                d = [np.mean((outs[f + 1] - outs[f]) ** 2) for f in range(first, last)]
                row[name + '_flicker'] = float(np.mean(d))
                row[name + '_norm'] = float('nan')
                row[name + '_light'] = row[name + '_light_norm'] = float('nan')
                ghost_mask = None
            else:
                ids4 = load(ref4, ['IndexOB.X'])[:, :, 0]
                ids5 = load(ref5, ['IndexOB.X'])[:, :, 0]
                dep4 = load(ref4, ['Denoising Depth.Z'])[:, :, 0]
                dep5 = load(ref5, ['Denoising Depth.Z'])[:, :, 0]
                qy, qx, same = correspondence(to_next(ref4), ids4, ids5, dep4, dep5)
                d = (outs[5][qy, qx] - outs[4]) ** 2
                r4, r5 = rgb(ref4), rgb(ref5)
                dref = (r5[qy, qx] - r4) ** 2
                row[name + '_flicker'] = float(np.mean(d[same]))
                row[name + '_norm'] = float(np.mean(d[same]) / np.mean(dref[same]))
                # The same on the light (divided by the references' albedo):
                # the texture's half-pixel misregistration under the nearest
                # pixel, which dominates the radiance's, cancels there.
                alb = ['Denoising Albedo.R', 'Denoising Albedo.G', 'Denoising Albedo.B']
                a4 = load(ref4, alb) + 1e-3
                a5 = load(ref5, alb)[qy, qx] + 1e-3
                dl = (outs[5][qy, qx] / a5 - outs[4] / a4) ** 2
                dlref = (r5[qy, qx] / a5 - r4 / a4) ** 2
                row[name + '_light'] = float(np.mean(dl[same]))
                row[name + '_light_norm'] = float(np.mean(dl[same]) / np.mean(dlref[same]))
                # Disoccluded: frame 4's pixels not seen in frame 3 or 5 (the
                # noisy frames' own vectors and ids: the references have
                # only frames 4 and 5).
                f3 = frame(pattern, 3)
                ids3 = load(f3, ['IndexOB.X'])[:, :, 0]
                dep3 = load(f3, ['Denoising Depth.Z'])[:, :, 0]
                _, _, seen3 = correspondence(to_previous(ref4), ids4, ids3, dep4, dep3)
                ghost_mask = ~(seen3 & same)
            row[name + '_rel'] = rel_mse(outs[4], rgb(ref4))
            row[name + '_ghost'] = (rel_mse(outs[4], rgb(ref4), ghost_mask)
                                    if ghost_mask is not None and ghost_mask.any()
                                    else float('nan'))
        print('| %s | %.3g | %.3g | %.2f | %.2f, %.2f | %.2f | %.2f, %.2f | %.5f | %.5f | %s | %s |' % (
            seq, row['single_flicker'], row['k_flicker'],
            row['k_flicker'] / row['single_flicker'], row['single_norm'], row['k_norm'],
            row['k_light'] / row['single_light'], row['single_light_norm'],
            row['k_light_norm'],
            row['single_rel'], row['k_rel'],
            '%.5f' % row['single_ghost'] if row['single_ghost'] == row['single_ghost'] else '-',
            '%.5f' % row['k_ghost'] if row['k_ghost'] == row['k_ghost'] else '-'))
    print('outputs in', out)


if __name__ == '__main__':
    main()
