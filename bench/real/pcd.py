"""Reads a PCD file (ASCII or binary) into a numpy structured array: the converters' helper."""
import os, sys
import numpy as np
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


def write_generic(out, pcd_paths, T, stamps):
    """Writes kiss-odom's generic layout to `out`: each PCD's finite points as
    velodyne/NNNNNN.bin (f32 x y z intensity), the 4x4 poses `T` relative to the first as
    poses.txt (KITTI 3x4 rows), the stamps relative to the first as times.txt."""
    T0inv = np.linalg.inv(T[0])
    os.makedirs(os.path.join(out, 'velodyne'), exist_ok=True)
    with open(os.path.join(out, 'poses.txt'), 'w') as fp, \
            open(os.path.join(out, 'times.txt'), 'w') as ft:
        for k, path in enumerate(pcd_paths):
            a, _ = read_pcd(path)
            pts = np.stack([a['x'], a['y'], a['z'], a['intensity']], 1).astype('<f4')
            pts = pts[np.isfinite(pts).all(1)]
            pts.tofile(os.path.join(out, 'velodyne', '%06d.bin' % k))
            R = T0inv @ T[k]
            fp.write(' '.join('%.9e' % v for v in R[:3, :].reshape(-1)) + '\n')
            ft.write('%.6f\n' % (stamps[k] - stamps[0]))
    print(len(T), 'frames')
