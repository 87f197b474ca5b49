#!/usr/bin/python3
"""feature_regression.py - prototype of candidate K5 (bench/results/2026-12-selection-log.md section 8): NFOR-style
first-order regression of the quotient on [1, u, v, normal, depth], windows r=9 at stride 3,
same-object and spatial weights only (so exactly linear: its hat diagonal D is saved too),
splatted collaboratively. Usage: feature_regression.py SCENE SPP OUT.npy [R]"""
import os
SHARED=os.environ.get("ZDENOISE_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared"))
import OpenImageIO as oiio, numpy as np, sys
from numpy.lib.stride_tricks import sliding_window_view as swv
scene=sys.argv[1]; spp=sys.argv[2]; out=sys.argv[3]
R=int(sys.argv[4]) if len(sys.argv)>4 else 9
S=3
def load(p):
    b=oiio.ImageBuf(p); s=b.spec(); n=list(s.channelnames); a=b.get_pixels(oiio.FLOAT)
    return {c:a[...,i] for i,c in enumerate(n)}
def rgb(d,ch): return np.stack([d['ViewLayer.'+ch+'.'+c] for c in 'RGB'],2)
D=os.path.join(SHARED,'data',scene)+'/'
ref=load(D+scene+'_ref.exr'); noisy=load(D+scene+'_spp%s_s1.exr'%spp)
alb=rgb(ref,'Denoising Albedo'); eps=1e-3
L=rgb(noisy,'Combined'); z=L/(alb+eps)
nrm=np.stack([noisy['ViewLayer.Denoising Normal.'+c] for c in 'XYZ'],2)
dep=noisy['ViewLayer.Denoising Depth.Z']
oid=noisy['ViewLayer.CryptoObject00.r']
H,W,_=z.shape
# features: 1,u,v,nx,ny,nz,depth(relative)
def pad(a):
    if a.ndim==2: return np.pad(a,R,mode='constant',constant_values=np.nan)
    return np.pad(a,((R,R),(R,R),(0,0)),mode='constant',constant_values=np.nan)
zp,np_,dp,op=pad(z),pad(nrm),pad(dep),pad(oid)
cy=np.arange(0,H,S); cx=np.arange(0,W,S)
acc=np.zeros((H+2*R,W+2*R,3)); wsum=np.zeros((H+2*R,W+2*R)); hsum=np.zeros((H+2*R,W+2*R))
K=2*R+1
yy,xx=np.mgrid[-R:R+1,-R:R+1]
sp=np.exp(-(xx**2+yy**2)/(R*R)).ravel()
for y0 in cy:
    # windows for all centres in this row
    rows=slice(y0,y0+K)
    Z=swv(zp[rows],(K,K),axis=(0,1))[0][cx]      # (nc,3,K,K)
    N=swv(np_[rows],(K,K),axis=(0,1))[0][cx]
    Dd=swv(dp[rows],(K,K),axis=(0,1))[0][cx]
    O=swv(op[rows],(K,K),axis=(0,1))[0][cx]
    nc=len(cx)
    Z=Z.reshape(nc,3,-1); N=N.reshape(nc,3,-1); Dd=Dd.reshape(nc,-1); O=O.reshape(nc,-1)
    c=K*K//2
    valid=np.isfinite(Dd)&np.isfinite(Z).all(1)
    same=(O==O[:,c:c+1])&valid
    dc=Dd[:,c:c+1]
    relz=(Dd-dc)/np.maximum(np.abs(dc),1e-3)
    w=np.where(same,sp[None,:],0.0)
    u=np.broadcast_to(xx.ravel()/R,(nc,K*K)); v=np.broadcast_to(yy.ravel()/R,(nc,K*K))
    X=np.stack([np.ones((nc,K*K)),u,v,N[:,0]-N[:,0,c:c+1],N[:,1]-N[:,1,c:c+1],N[:,2]-N[:,2,c:c+1],relz],2)
    X=np.nan_to_num(X)
    Zc=np.nan_to_num(Z.transpose(0,2,1))
    M=np.einsum('nk,nki,nkj->nij',w,X,X)
    lam=1e-3*np.maximum(M[:,0,0],1e-9)
    M+=np.eye(7)[None]*lam[:,None,None]*np.array([0,1,1,1,1,1,1])[None,:,None]
    M+=np.eye(7)[None]*1e-9
    B=np.einsum('nk,nki,nkc->nic',w,X,Zc)
    beta=np.linalg.solve(M,B)
    P=np.einsum('nki,nic->nkc',X,beta)  # prediction at each window point
    Minv=np.linalg.inv(M)
    h=w*np.einsum('nki,nij,nkj->nk',X,Minv,X)
    for k,x0 in enumerate(cx):
        ww=w[k].reshape(K,K)
        acc[y0:y0+K,x0:x0+K]+=ww[...,None]*P[k].reshape(K,K,3)
        wsum[y0:y0+K,x0:x0+K]+=ww
        hsum[y0:y0+K,x0:x0+K]+=ww*h[k].reshape(K,K)
acc=acc[R:-R,R:-R]; wsum=wsum[R:-R,R:-R]; hsum=hsum[R:-R,R:-R]
np.save(out+'.D.npy',np.where(wsum>0,hsum/np.maximum(wsum,1e-20),1.0))
zf=np.where(wsum[...,None]>0,acc/np.maximum(wsum,1e-20)[...,None],z)
zf=np.clip(zf,0,None)
outimg=(zf*(alb+eps)).astype(np.float32)
np.save(out,outimg)
refc=rgb(ref,'Combined')
print(scene,spp,'K5 relMSE',((outimg-refc)**2/(refc**2+0.01)).mean())
