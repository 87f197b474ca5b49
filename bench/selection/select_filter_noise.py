#!/usr/bin/python3
"""select_filter_noise.py - the same with sigma^2 from zdenoise's own noise map
(--diagnostics zdenoise.noise). Usage: select_filter_noise.py SCENE SPP PREFIX"""
import os
SHARED=os.environ.get("ZDENOISE_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared"))
import OpenImageIO as oiio, numpy as np, sys
from numpy.lib.stride_tricks import sliding_window_view as swv
scene,spp,pre=sys.argv[1:4]; rs=7
def load(p):
    b=oiio.ImageBuf(p); s=b.spec(); n=list(s.channelnames); a=b.get_pixels(oiio.FLOAT)
    return {c:a[...,i] for i,c in enumerate(n)}
def rgb(d,ch='ViewLayer.Combined'):
    return np.stack([d[ch+'.'+c] if ch+'.'+c in d else d[c] for c in 'RGB'],2)
D=os.path.join(SHARED,'data',scene)+'/'
R=load(D+scene+'_ref.exr'); ref=rgb(R); alb=rgb(R,'ViewLayer.Denoising Albedo')+1e-3
L=rgb(load(D+scene+'_spp%s_s1.exr'%spp))
K0=load(pre+'_k0d.exr'); o0=rgb(K0); srel=K0['zdenoise.noise']
o0p=rgb(load(pre+'_k0p.exr')); o5=np.load(pre+'.npy'); D5=np.load(pre+'.npy.D.npy')[...,None]
delta=np.load(pre+'_pert.exr.delta.npy')
lw=np.array([0.2126,0.7152,0.0722])
zl=(L@lw)/(alb@lw)
var=(srel*zl)[...,None]**2*alb**2
D0=np.where(np.abs(delta)>0,(o0p-o0)/np.where(delta==0,1,delta),0.0)
def box(e,r):
    if e.ndim==3: return np.stack([box(e[...,c],r) for c in range(e.shape[2])],2)
    p=np.pad(e,r,mode='edge'); return swv(p,(2*r+1,2*r+1)).mean(axis=(2,3))
rho=1.0/(o0**2+0.01)
def sure(o,Dk): return ((o-L)**2-var+2*var*Dk)*rho
s0=sure(o0,D0).mean(2); s5=sure(o5,D5).mean(2)
def err(x): return ((x-ref)**2/(ref**2+0.01)).mean(2)
e0,e5=err(o0),err(o5)
print('%s %s true K0 %.5f K5 %.5f | SURE K0 %.5f K5 %.5f'%(scene,spp,e0.mean(),e5.mean(),s0.mean(),s5.mean()))
d=s5-s0
dl=box(d,rs); n=(2*rs+1)**2
se=np.sqrt(np.maximum(box(d*d,rs)-dl*dl,0)/n)
for lam in [0,1,2]:
    pick=(dl< -lam*se).astype(float)
    a=box(pick,3)[...,None]
    print('  lambda %d frac K5 %.2f selected relMSE %.5f'%(lam,pick.mean(),err(a*o5+(1-a)*o0).mean()))
pick=(box(e5-e0,rs)<0).astype(float); a=box(pick,3)[...,None]
print('  oracle frac K5 %.2f selected relMSE %.5f'%(pick.mean(),err(a*o5+(1-a)*o0).mean()))
