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
            for single-frame and temporal. For the pan the same quantity of
            the two 1024-spp references ("a perfect output") is the floor:
            the scene's own change and the nearest pixel's misregistration
            of texture are in every output's flicker;
  error flicker
            the same of the output's error e = output - reference, the
            residue that changes from frame to frame (on the static sequence
            it equals the flicker: the reference is one image). Also of the
            error's means over 5x5 and 11x11 boxes, the low-frequency residue
            that a viewer sees as boiling;
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


def box_mean(img, r):
    """The mean over the (2r+1)^2 box around each pixel (edges clamped)."""
    if r == 0:
        return img
    p = np.pad(img, ((r, r), (r, r), (0, 0)), mode='edge')
    c = np.cumsum(np.cumsum(p, axis=0), axis=1)
    c = np.pad(c, ((1, 0), (1, 0), (0, 0)))
    n = 2 * r + 1
    return (c[n:, n:] - c[:-n, n:] - c[n:, :-n] + c[:-n, :-n]) / (n * n)


SCALES = (0, 2, 5)  # error flicker of pixels, 5x5 and 11x11 box means


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
    print('| sequence | flicker single | K=%d | ratio | a perfect output\'s ratio '
          '| error flicker single | K=%d | ratio: pixels, 5x5, 11x11 '
          '| relMSE frame 4 single | K=%d | ghost relMSE single | K=%d |'
          % (a.k, a.k, a.k, a.k))
    print('|---|---|---|---|---|---|---|---|---|---|---|---|')
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
        r4 = rgb(ref4)
        if seq == 'static':
            # Consecutive pairs; the reference is the same image for all.
            pairs = [(f, f + 1) for f in range(first, last)]
            refs = {f: r4 for f in range(first, last + 1)}
            qy, qx = np.mgrid[0:r4.shape[0], 0:r4.shape[1]]
            same = np.ones(r4.shape[:2], bool)
            ghost_mask = None
        else:
            pairs = [(4, 5)]
            refs = {4: r4, 5: rgb(ref5)}
            ids4 = load(ref4, ['IndexOB.X'])[:, :, 0]
            ids5 = load(ref5, ['IndexOB.X'])[:, :, 0]
            dep4 = load(ref4, ['Denoising Depth.Z'])[:, :, 0]
            dep5 = load(ref5, ['Denoising Depth.Z'])[:, :, 0]
            qy, qx, same = correspondence(to_next(ref4), ids4, ids5, dep4, dep5)
            # Disoccluded: frame 4's pixels not seen in frame 3 or 5 (frame
            # 3's own vectors and ids: the references have only 4 and 5).
            f3 = frame(pattern, 3)
            ids3 = load(f3, ['IndexOB.X'])[:, :, 0]
            dep3 = load(f3, ['Denoising Depth.Z'])[:, :, 0]
            _, _, seen3 = correspondence(to_previous(ref4), ids4, ids3, dep4, dep3)
            ghost_mask = ~(seen3 & same)

        def flicker(img):
            """Mean squared change from frame f to f+1 at the reprojected
            place, over the pairs."""
            return float(np.mean([np.mean(((img(g)[qy, qx] - img(f)) ** 2)[same])
                                  for f, g in pairs]))

        row = {}
        if seq == 'pan':
            row['perfect'] = flicker(lambda f: refs[f])
        for name, p in (('single', single), ('k', temporal)):
            outs = {f: rgb(frame(p, f)) for f in range(first, last + 1)}
            row[name] = flicker(lambda f: outs[f])
            row[name + '_error'] = [
                flicker(lambda f: box_mean(outs[f] - refs[f], r)) for r in SCALES]
            row[name + '_rel'] = rel_mse(outs[4], r4)
            row[name + '_ghost'] = (rel_mse(outs[4], r4, ghost_mask)
                                    if ghost_mask is not None else float('nan'))
        fmt = lambda v: '-' if v != v else '%.5f' % v
        print('| %s | %.3g | %.3g | %.2f | %s | %.3g | %.3g | %s | %.5f | %.5f | %s | %s |' % (
            seq, row['single'], row['k'], row['k'] / row['single'],
            '%.2f' % (row['perfect'] / row['single']) if 'perfect' in row else '0',
            row['single_error'][0], row['k_error'][0],
            ', '.join('%.2f' % (k / s) for k, s in zip(row['k_error'], row['single_error'])),
            row['single_rel'], row['k_rel'],
            fmt(row['single_ghost']), fmt(row['k_ghost'])))
    print('outputs in', out)


if __name__ == '__main__':
    main()
