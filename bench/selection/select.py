#!/usr/bin/python3
"""select.py - SURE selection between K0 (zdenoise) and K5 (feature_regression.py) on one public
case; prints the true and SURE image means, then the selected relMSE with the confidence rule
lambda 0/1/2 and the oracle (the true error in place of SURE). sigma^2 from the seed-1/seed-2
pair (--sigma pair) or from zdenoise's own noise map (--sigma filter: --diagnostics'
zdenoise.noise). Usage: select.py SCENE SPP PREFIX [--sigma pair|filter] [--rs 7]"""
import argparse
import os

import numpy as np
import OpenImageIO as oiio
from numpy.lib.stride_tricks import sliding_window_view as swv

SHARED = os.environ.get("ZDENOISE_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared"))
LUMA = np.array([0.2126, 0.7152, 0.0722])

ap = argparse.ArgumentParser()
ap.add_argument("scene"); ap.add_argument("spp"); ap.add_argument("prefix")
ap.add_argument("--sigma", choices=["pair", "filter"], default="pair")
ap.add_argument("--rs", type=int, default=7)
a = ap.parse_args()
scene, spp, pre, rs = a.scene, a.spp, a.prefix, a.rs


def load(p):
    b = oiio.ImageBuf(p); n = list(b.spec().channelnames); px = b.get_pixels(oiio.FLOAT)
    return {c: px[..., i] for i, c in enumerate(n)}


def rgb(d, ch="ViewLayer.Combined"):
    return np.stack([d[ch + "." + c] if ch + "." + c in d else d[c] for c in "RGB"], 2)


def box(e, r):
    if e.ndim == 3:
        return np.stack([box(e[..., c], r) for c in range(e.shape[2])], 2)
    p = np.pad(e, r, mode="edge"); return swv(p, (2 * r + 1, 2 * r + 1)).mean(axis=(2, 3))


D = os.path.join(SHARED, "data", scene) + "/"
R = load(D + scene + "_ref.exr"); ref = rgb(R)
L = rgb(load(D + scene + "_spp%s_s1.exr" % spp))
K0 = load(pre + "_k0.exr"); o0 = rgb(K0)
o0p = rgb(load(pre + "_k0p.exr")); o5 = np.load(pre + ".npy"); D5 = np.load(pre + ".npy.D.npy")[..., None]
delta = np.load(pre + "_pert.exr.delta.npy")
if a.sigma == "pair":
    var = np.load(pre + "_pert.exr.var.npy")
else:
    alb = rgb(R, "ViewLayer.Denoising Albedo") + 1e-3
    zl = (L @ LUMA) / (alb @ LUMA)
    var = (K0["zdenoise.noise"] * zl)[..., None] ** 2 * alb ** 2
D0 = np.where(np.abs(delta) > 0, (o0p - o0) / np.where(delta == 0, 1, delta), 0.0)
rho = 1.0 / (o0 ** 2 + 0.01)


def sure(o, Dk): return ((o - L) ** 2 - var + 2 * var * Dk) * rho
def err(x): return ((x - ref) ** 2 / (ref ** 2 + 0.01)).mean(2)


s0 = sure(o0, D0).mean(2); s5 = sure(o5, D5).mean(2)
e0, e5 = err(o0), err(o5)
print("%s %s sigma %s: true K0 %.5f K5 %.5f | SURE mean K0 %.5f K5 %.5f | mean D0 %.3f D5 %.3f"
      % (scene, spp, a.sigma, e0.mean(), e5.mean(), s0.mean(), s5.mean(), D0.mean(), D5.mean()))
d = s5 - s0
dl = box(d, rs); dt = box(e5 - e0, rs)
print("corr(smoothed SURE diff, true diff) %.3f" % np.corrcoef(dl.ravel(), dt.ravel())[0, 1])
se = np.sqrt(np.maximum(box(d * d, rs) - dl * dl, 0) / (2 * rs + 1) ** 2)
for name, pick in [("SURE l%d" % lam, dl < -lam * se) for lam in (0, 1, 2)] + [("oracle", dt < 0)]:
    blend = box(pick.astype(float), 3)[..., None]
    print("  %-8s frac K5 %.2f selected relMSE %.5f" % (name, pick.mean(), err(blend * o5 + (1 - blend) * o0).mean()))
