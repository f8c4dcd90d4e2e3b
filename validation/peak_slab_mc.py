#!/usr/bin/env python3
"""docs/derivations.md D15, hypothesis (a): is peak_eff (D3 at the beam grid's mean-cosine depth) the
angular factor of peak-only light in an infinite medium? A half-space Monte Carlo of peak-only photons
(HG 0.85 split at f = g^2, sigma_s 9.9, sigma_a 0.1: the backlit r = 10 sphere's medium), normal
incidence, track-length tallies per depth layer, against D3 by its Legendre series.

    nice validation/peak_slab_mc.py [ANGLE_DEG=17.8] [PHOTONS=200000]   # 1e5 photons: ~25 min wall on the loaded 2-core machine
"""
import numpy as np, sys
g, ss, sa = 0.85, 9.9, 0.1
rng = np.random.default_rng(1)
def hg(mu): return (1 - g*g) / (4*np.pi*(1 + g*g - 2*g*mu)**1.5)
th = np.linspace(0, np.pi, 200001); mu_t = np.cos(th)
def mass(tc):
    m = th < tc; lev = hg(np.cos(tc))
    return np.trapz(np.where(m, np.maximum(hg(mu_t) - lev, 0), 0) * np.sin(th), th) * 2*np.pi
f_req = g*g; lo, hi = 0.0, np.pi
for _ in range(60):
    mid = 0.5*(lo+hi); (lo, hi) = (mid, hi) if mass(mid) < f_req else (lo, mid)
tc = hi; f = mass(tc); lev = hg(np.cos(tc))
print(f"theta_c {np.degrees(tc):.2f} deg, f {f:.4f}, level {lev:.4f}")
def ppeak(mu):
    return np.where(mu > np.cos(tc), np.maximum(hg(mu) - lev, 0) / f, 0.0)
# Legendre moments of P_peak
L = 3000
thp = np.linspace(0, tc, 400001); mp = np.cos(thp); wq = ppeak(mp) * np.sin(thp) * 2*np.pi
chi = np.zeros(L); p0 = np.ones_like(mp); p1 = mp.copy()
chi[0] = np.trapz(wq * p0, thp); chi[1] = np.trapz(wq * p1, thp)
for l in range(1, L-1):
    p2 = ((2*l+1)*mp*p1 - l*p0)/(l+1); p0, p1 = p1, p2; chi[l+1] = np.trapz(wq*p1, thp)
print("chi1 %.5f chi2 %.5f" % (chi[1], chi[2]))
def d3(tau, mu):  # peak_eff(tau, mu): e^-tau P_peak + series
    s = 0.0; p0, p1 = 1.0, mu
    for l in range(L):
        pl = 1.0 if l == 0 else p1
        s += (2*l+1)/(4*np.pi) * chi[l] * (np.exp(-tau*(1-chi[l])) - np.exp(-tau)) * pl
        if l >= 1: p2 = ((2*l+1)*mu*p1 - l*p0)/(l+1); p0, p1 = p1, p2
    return np.exp(-tau)*ppeak(mu) + s
def sample_peak(w, n):
    out = np.empty(n); todo = np.arange(n)
    while todo.size:
        u = rng.random(todo.size)
        c = (1 + g*g - ((1 - g*g)/(1 - g + 2*g*u))**2)/(2*g)
        acc = rng.random(todo.size) * hg(c) < f * ppeak(c)
        out[todo[acc]] = c[acc]; todo = todo[~acc]
    return out
def rotate(w, c):
    n = len(c); phi = 2*np.pi*rng.random(n); s = np.sqrt(np.maximum(0, 1 - c*c))
    a = np.where(np.abs(w[:, 2:3]) < 0.9, [[0, 0, 1.0]], [[1.0, 0, 0]])
    t1 = np.cross(w, a); t1 /= np.linalg.norm(t1, axis=1)[:, None]; t2 = np.cross(w, t1)
    return w*c[:, None] + t1*(s*np.cos(phi))[:, None] + t2*(s*np.sin(phi))[:, None]
sp = f*ss; sr = sa + (1-f)*ss
mu_o = np.cos(np.radians(float(sys.argv[1]) if len(sys.argv) > 1 else 17.8))
wo = np.array([np.sqrt(1 - mu_o**2), 0, mu_o])
N = int(sys.argv[2]) if len(sys.argv) > 2 else 200000
zs = np.array([0.05, 0.1, 0.2, 0.3, 0.5, 0.8, 1.2, 1.6, 2.0])
dz = 0.02
# tallies: per depth layer [z, z+dz]: sum len*w, sum len*w*ppeak, sum len*w*cos
T0 = np.zeros(len(zs)); T1 = np.zeros(len(zs)); Tc = np.zeros(len(zs))
# angle-only at path length s = z (tau = sp z): direction at that path length
A1 = np.zeros(len(zs)); A0 = np.zeros(len(zs))
x = np.zeros((N, 3)); w = np.tile([0, 0, 1.0], (N, 1)); s = np.zeros(N); alive = np.ones(N, bool)
wa = w.copy(); sa_len = np.zeros(N)  # angle-only photons (same sequence not needed)
while alive.any():
    idx = np.nonzero(alive)[0]
    l = rng.exponential(1/sp, idx.size)
    z0 = x[idx, 2]; wz = w[idx, 2]; z1 = z0 + wz*l
    for k, z in enumerate(zs):
        # overlap of segment with layer [z, z+dz] in path length
        with np.errstate(divide='ignore', invalid='ignore'):
            ta = (z - z0)/wz; tb = (z + dz - z0)/wz
        t_lo = np.clip(np.minimum(ta, tb), 0, l); t_hi = np.clip(np.maximum(ta, tb), 0, l)
        seg = np.where(np.abs(wz) > 1e-12, t_hi - t_lo, np.where((z0 >= z) & (z0 < z+dz), l, 0))
        # weight at midpoint of overlap
        wt = np.exp(-sr*(s[idx] + 0.5*(t_lo + t_hi))) * seg
        m = seg > 0
        if m.any():
            T0[k] += wt[m].sum(); T1[k] += (wt[m]*ppeak(w[idx[m]] @ wo)).sum(); Tc[k] += (wt[m]*w[idx[m], 2]).sum()
    x[idx] += w[idx]*l[:, None]; s[idx] += l
    out = (x[idx, 2] < 0) | (s[idx]*sr > 12) | (x[idx, 2] > zs[-1] + dz)
    alive[idx[out]] = False
    keep = idx[~out]
    if keep.size: w[keep] = rotate(w[keep], sample_peak(w[keep], keep.size))
# angle-only: direction after Poisson(sp z) deflections, then E[ppeak(w . wo)]
print(" z    tau   C_slab   C_D3(tau)  mc_slab  tau_mc  C_D3(tau_mc)  slab/D3(tau_mc)")
for k, z in enumerate(zs):
    z_mid = z + dz/2; tau = sp*z_mid
    C = T1[k]/T0[k]; mc = Tc[k]/T0[k]; tau_mc = -np.log(mc)/(1 - chi[1])
    print(f"{z_mid:.2f} {tau:6.2f} {C:.4f}  {d3(tau, mu_o):.4f}  {mc:.4f}  {tau_mc:6.2f}  {d3(tau_mc, mu_o):.4f}  {C/d3(tau_mc, mu_o):.3f}")
