#!/usr/bin/python3
"""peers.py - zdenoise beside Intel OIDN and NFOR on the same inputs (issue 32's targets table).

For every scene x spp x seed of a data directory laid out as shared/data
(<scene>/<scene>_spp<N>_s<S>.exr, <scene>_ref.exr, <scene>_albedo.exr) it runs, like with like:

  no flags     zdenoise --in NOISY                          | OIDN --hdr, the file's albedo and normal
  clean        zdenoise --in NOISY --albedo <scene>_albedo  | OIDN --clean_aux, the reference's albedo
                                                              and normal
  halves       zdenoise --in (S1+S2)/2 --halves S1 S2       | NFOR (tungsten) on the same two files
               (seeds 1 and 2; the mean file keeps S1's object ids)

and prints relMSE (zmetrics' formula) and the ratio zdenoise / peer. Where the reference has
Cycles' DiffDir (the scenes of bench/scenes/ with a sun), it also prints the sunlit region
(bench/edge_bands.py's band along hard edges of the direct light plus the lit patch) and the
band alone. The last table lists each target of issue 32 and the worst ratio found.

Usage:
  bench/peers.py --oidn DIR [--nfor DIR] [--data DIR] [--scenes a,b] [--spp 4,16,64] [--seeds 1,2]
                 [--zdenoise BIN] [--keep DIR] [--json FILE]
  DIR for --oidn: ../shared/peers/oidn-install.tar.zst extracted (holds bin/oidnDenoise);
  for --nfor: ../shared/peers/nfor/nfor-install.tar.zst extracted (holds nfor_cycles.sh).
The peers are yardsticks run beside zdenoise, never part of it. Runs with Debian's
/usr/bin/python3 (OpenImageIO, numpy); a few minutes for the public set.
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
SHARED = os.path.normpath(os.path.join(REPO, '..', 'shared'))
sys.path.insert(0, HERE)
import edge_bands  # noqa: E402  (regions of the direct light)

# Issue 32, item 5: the largest ratio to the peer allowed, per comparison and spp.
TARGETS = [('no flags / OIDN', 'noflags', {4: 1.5, 16: 1.2, 64: 1.2}),
           ('clean albedo / OIDN clean aux', 'clean', {16: 1.2, 64: 1.2}),
           ('halves / NFOR', 'halves', {4: 1.0, 16: 1.0, 64: 1.0}),
           ('sunlit region / OIDN (interiors)', 'sunlit', {16: 1.5, 64: 1.5})]


def run(cmd, env=None):
    r = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if r.returncode != 0:
        sys.exit(f'peers.py: {cmd[0]} failed ({r.returncode}): {(r.stderr or r.stdout).strip()[-400:]}')


def rgb(path):
    return edge_bands.channels(path, [['Combined.R', 'Combined.G', 'Combined.B'], ['R', 'G', 'B']])


def mean_of_halves(a_path, b_path, out):
    """(A+B)/2 as one Cycles file: every channel averaged but the object ids (hashes and
    indices, taken from A), and the samples count doubled (the albedo prefilter reads it)."""
    a, b = oiio.ImageBuf(a_path), oiio.ImageBuf(b_path)
    spec = a.spec()
    pa, pb = a.get_pixels(oiio.FLOAT), b.get_pixels(oiio.FLOAT)
    ids = [i for i, n in enumerate(spec.channelnames) if 'Crypto' in n or 'Index' in n]
    m = 0.5 * (pa + pb)
    m[..., ids] = pa[..., ids]
    for attr in spec.extra_attribs:
        if attr.name.endswith('.samples'):
            spec.attribute(attr.name, str(2 * int(attr.value)))
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), m)
    if not buf.write(out):
        sys.exit(f'peers.py: cannot write {out}: {buf.geterror()}')


def rel_err(img, ref):
    return ((img - ref) ** 2 / (ref ** 2 + 1e-2)).mean(axis=2)


class Peers:
    def __init__(self, a, tmp, lock=()):
        """a: .oidn, .shared (and .nfor for nfor()); lock: a prefix for OIDN's run (flock FILE)."""
        self.a, self.tmp, self.lock = a, tmp, list(lock)
        self.conv = os.path.join(a.shared, 'peers', 'exr2pfm.py')

    def oidn(self, noisy, aux, out, clean):
        p = os.path.join(self.tmp, 'oidn')
        run(['/usr/bin/python3', self.conv, noisy, p, 'beauty'])
        run(['/usr/bin/python3', self.conv, aux, p, 'alb', 'nrm'])
        cmd = [os.path.join(self.a.oidn, 'bin', 'oidnDenoise'), '--hdr', p + '_beauty.pfm',
               '--alb', p + '_alb.pfm', '--nrm', p + '_nrm.pfm', '--threads', '2', '-o', p + '_out.pfm']
        env = dict(os.environ, LD_LIBRARY_PATH=os.path.join(self.a.oidn, 'lib'))
        run(self.lock + cmd + (['--clean_aux'] if clean else []), env)
        run(['oiiotool', p + '_out.pfm', '-o', out])

    def nfor(self, a, b, out):
        run(['bash', os.path.join(self.a.nfor, 'nfor_cycles.sh'), a, b, out])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--oidn', required=True, help='extracted oidn-install directory')
    ap.add_argument('--nfor', help='extracted nfor directory (halves rows need it)')
    ap.add_argument('--shared', default=SHARED, help='shared dir with peers/exr2pfm.py (default ../shared)')
    ap.add_argument('--data', help='data dir (default: SHARED/data)')
    ap.add_argument('--scenes', default='cornell_textured,newspaper,zigzag_steps')
    ap.add_argument('--spp', default='4,16,64')
    ap.add_argument('--seeds', default='1,2')
    ap.add_argument('--zdenoise', default=os.path.join(REPO, 'build', 'bin', 'zdenoise'))
    ap.add_argument('--keep', help='keep the outputs in this directory')
    ap.add_argument('--json', help='write the numbers as JSON')
    a = ap.parse_args()
    a.data = a.data or os.path.join(a.shared, 'data')
    spps = [int(s) for s in a.spp.split(',')]
    seeds = [int(s) for s in a.seeds.split(',')]
    for tool in [a.zdenoise, os.path.join(a.oidn, 'bin', 'oidnDenoise')]:
        if not os.access(tool, os.X_OK):
            sys.exit(f'peers.py: not executable: {tool}')
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out_dir = a.keep or tmp
        os.makedirs(out_dir, exist_ok=True)
        peers = Peers(a, tmp)
        for scene in a.scenes.split(','):
            d = os.path.join(a.data, scene)
            ref_path = os.path.join(d, f'{scene}_ref.exr')
            ref = rgb(ref_path)
            try:
                reg = edge_bands.regions(ref_path, 2)
                regions = {'sunlit': reg['edge band'] | reg['patch'], 'band': reg['edge band']}
            except SystemExit:
                regions = {}
            for spp in spps:
                noisy = {s: os.path.join(d, f'{scene}_spp{spp}_s{s}.exr') for s in seeds}
                runs = []  # (kind, seed, zdenoise output, peer output)
                for s in seeds:
                    o = lambda tag: os.path.join(out_dir, f'{scene}_{spp}_{s}_{tag}.exr')
                    run([a.zdenoise, '--in', noisy[s], '-o', o('z')])
                    peers.oidn(noisy[s], noisy[s], o('oidn'), False)
                    runs.append(('noflags', s, o('z'), o('oidn')))
                    if spp in (16, 64):
                        run([a.zdenoise, '--in', noisy[s], '--albedo', os.path.join(d, f'{scene}_albedo.exr'),
                             '-o', o('zclean')])
                        peers.oidn(noisy[s], ref_path, o('oidnclean'), True)
                        runs.append(('clean', s, o('zclean'), o('oidnclean')))
                if a.nfor and 1 in seeds and 2 in seeds:
                    o = lambda tag: os.path.join(out_dir, f'{scene}_{spp}_halves_{tag}.exr')
                    mean_of_halves(noisy[1], noisy[2], o('mean'))
                    run([a.zdenoise, '--in', o('mean'), '--halves', noisy[1], noisy[2], '-o', o('z')])
                    peers.nfor(noisy[1], noisy[2], o('nfor'))
                    runs.append(('halves', 'h', o('z'), o('nfor')))
                for kind, s, zp, pp in runs:
                    ez, ep = rel_err(rgb(zp), ref), rel_err(rgb(pp), ref)
                    row = {'scene': scene, 'spp': spp, 'seed': s, 'kind': kind,
                           'zdenoise': float(ez.mean()), 'peer': float(ep.mean())}
                    if kind == 'noflags':
                        for name, m in regions.items():
                            row[name] = [float(ez[m].mean()), float(ep[m].mean())]
                    rows.append(row)
                    print(f"{scene:18} {spp:3} {s!s:2} {kind:8} zdenoise {row['zdenoise']:.5f}  peer "
                          f"{row['peer']:.5f}  {row['zdenoise'] / row['peer']:.2f}x" +
                          ''.join(f'  {n} {v[0]:.5f}/{v[1]:.5f} {v[0] / v[1]:.2f}x'
                                  for n, v in row.items() if n in regions), flush=True)
    print('\ntarget (issue 32, item 5)              spp  limit  worst ratio  case')
    for label, kind, limits in TARGETS:
        for spp, limit in limits.items():
            cand = []
            for r in rows:
                if r['spp'] != spp:
                    continue
                if kind == 'sunlit' and 'sunlit' in r and r['scene'].startswith('interior'):
                    cand.append((r['sunlit'][0] / r['sunlit'][1], r))
                elif r['kind'] == kind:
                    cand.append((r['zdenoise'] / r['peer'], r))
            if cand:
                worst, r = max(cand, key=lambda c: c[0])
                print(f"{label:38} {spp:4} {limit:6.1f}  {worst:10.2f}  {r['scene']} seed {r['seed']}"
                      f"{'' if worst <= limit else '  (not met)'}")
    if a.json:
        with open(a.json, 'w') as f:
            json.dump(rows, f, indent=1)


if __name__ == '__main__':
    main()
