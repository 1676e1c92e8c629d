"""Reads a PCD file (ASCII or binary) into a numpy structured array: the converters' helper."""
import numpy as np, sys
def read_pcd(path):
    with open(path,'rb') as f:
        hdr={}
        while True:
            line=f.readline().decode('ascii').strip()
            k,*v=line.split(' ')
            hdr[k]=v
            if k=='DATA': break
        data=f.read()
    fields=hdr['FIELDS']; sizes=list(map(int,hdr['SIZE'])); types=hdr['TYPE']; counts=list(map(int,hdr.get('COUNT',['1']*len(fields))))
    n=int(hdr['POINTS'][0])
    dt=[]
    for fn,s,t,c in zip(fields,sizes,types,counts):
        code={'F':'f','U':'u','I':'i'}[t]+str(s)
        dt.append((fn if fn!='_' else 'pad%d'%len(dt), '<'+code, (c,)) if c>1 else (fn if fn!='_' else 'pad%d'%len(dt),'<'+code))
    dt=np.dtype(dt)
    if hdr['DATA'][0]=='binary':
        return np.frombuffer(data[:n*dt.itemsize],dtype=dt), hdr
    elif hdr['DATA'][0]=='ascii':
        arr=np.loadtxt(data.decode().splitlines())
        out=np.zeros(n,dtype=dt)
        for i,fn in enumerate(dt.names): out[fn]=arr[:,i]
        return out,hdr
    else:
        raise ValueError('unsupported '+hdr['DATA'][0])
