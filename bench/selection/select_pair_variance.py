#!/usr/bin/python3
"""select_pair_variance.py - SURE selection between K0 (zdenoise) and K5 with sigma^2 from the
seed-1/seed-2 pair; prints true and selected relMSE, with the confidence rule lambda 0/1/2
and the oracle. Usage: select_pair_variance.py SCENE SPP PREFIX"""
import os
SHARED=os.environ.get("ZDENOISE_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared"))
import OpenImageIO as oiio, numpy as np, sys
from numpy.lib.stride_tricks import sliding_window_view as swv
scene,spp=sys.argv[1],sys.argv[2]; pre=sys.argv[3]  # pre: e.g. zz4
rs=int(sys.argv[4]) if len(sys.argv)>4 else 7
def load(p):
    b=oiio.ImageBuf(p); s=b.spec(); n=list(s.channelnames); a=b.get_pixels(oiio.FLOAT)
    return {c:a[...,i] for i,c in enumerate(n)}
def rgb(d,ch='ViewLayer.Combined'):
    return np.stack([d[ch+'.'+c] if ch+'.'+c in d else d[c] for c in 'RGB'],2)
D=os.path.join(SHARED,'data',scene)+'/'
ref=rgb(load(D+scene+'_ref.exr')); L=rgb(load(D+scene+'_spp%s_s1.exr'%spp))
o0=rgb(load(pre+'_k0.exr')); o0p=rgb(load(pre+'_k0p.exr')); o5=np.load(pre+'.npy'); D5=np.load(pre+'.npy.D.npy')[...,None]
delta=np.load(pre+'_pert.exr.delta.npy'); var=np.load(pre+'_pert.exr.var.npy')
D0=np.where(np.abs(delta)>0,(o0p-o0)/np.where(delta==0,1,delta),0.0)
def box(e,r):
    if e.ndim==3: return np.stack([box(e[...,c],r) for c in range(e.shape[2])],2)
    p=np.pad(e,r,mode='edge'); return swv(p,(2*r+1,2*r+1)).mean(axis=(2,3))
rho=1.0/(o0**2+0.01)
def sure(o,Dk): return ((o-L)**2-var+2*var*Dk)*rho
s0=sure(o0,D0).mean(2); s5=sure(o5,D5).mean(2)
def err(x): return ((x-ref)**2/(ref**2+0.01)).mean(2)
e0,e5=err(o0),err(o5)
print('true K0 %.5f K5 %.5f | SURE mean K0 %.5f K5 %.5f'%(e0.mean(),e5.mean(),s0.mean(),s5.mean()))
print('mean D0 %.3f D5 %.3f'%(D0.mean(),D5.mean()))
dl=box(s5-s0,rs); dt=box(e5-e0,rs)
print('corr(smoothed SURE diff, true diff) %.3f'%np.corrcoef(dl.ravel(),dt.ravel())[0,1])
dd=s5-s0; n=(2*rs+1)**2
se=np.sqrt(np.maximum(box(dd*dd,rs)-dl*dl,0)/n)
for name,d,lam in [('SURE l0',dl,0),('SURE l1',dl,1),('SURE l2',dl,2),('oracle',dt,0)]:
    pick=(d< -lam*(se if name!='oracle' else 0)).astype(float)
    a=box(pick,3)[...,None]
    print('  %-8s frac K5 %.2f selected relMSE %.5f'%(name,pick.mean(),err(a*o5+(1-a)*o0).mean()))
