#!/usr/bin/python3
"""perturb.py - the Monte-Carlo SURE probe (Ramani, Blu & Unser 2008): a copy of the noisy
seed-1 file with Combined + eps*b*sigma, b = +-1 per pixel, sigma from the seed pair.
Usage: perturb.py SCENE SPP OUT.exr EPS"""
import os
SHARED=os.environ.get("ZDENOISE_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared"))
import OpenImageIO as oiio, numpy as np, sys
from numpy.lib.stride_tricks import sliding_window_view as swv
scene,spp,out,eps=sys.argv[1],sys.argv[2],sys.argv[3],float(sys.argv[4])
D=os.path.join(SHARED,'data',scene)+'/'
b1=oiio.ImageBuf(D+scene+'_spp%s_s1.exr'%spp); b2=oiio.ImageBuf(D+scene+'_spp%s_s2.exr'%spp)
s=b1.spec(); n=list(s.channelnames); a1=b1.get_pixels(oiio.FLOAT); a2=b2.get_pixels(oiio.FLOAT)
idx=[n.index('ViewLayer.Combined.'+c) for c in 'RGB']
v=(a1[...,idx]-a2[...,idx])**2/2
p=np.pad(v,((2,2),(2,2),(0,0)),mode='edge'); v=swv(p,(5,5),axis=(0,1)).mean(axis=(-1,-2))
rng=np.random.default_rng(7); bb=rng.choice([-1.0,1.0],size=v.shape[:2])
delta=eps*bb[...,None]*np.sqrt(v)
a=a1.copy(); a[...,idx]+=delta
np.save(out+'.delta.npy',delta); np.save(out+'.var.npy',v)
spec=oiio.ImageSpec(s); spec.set_format(oiio.FLOAT)
o=oiio.ImageBuf(spec); o.set_pixels(oiio.ROI(0,s.width,0,s.height,0,1,0,s.nchannels),a)
for att in s.extra_attribs: o.specmod().attribute(att.name, att.type, att.value)
print(o.write(out), o.geterror())
