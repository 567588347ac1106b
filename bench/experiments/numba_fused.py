"""A cost experiment, not product code: what a fused kernel would buy the batched core.

Issue 12 asks a sweep to run at half the numpy floor's rate per core; the batched core
(camcore.batch) reaches 0.12-0.20 of it, because with plain numpy every formula is a
pass over memory. This prototype fuses the grid's per-angle work of a batch into one
numba loop (the cycloidal program, for each face the pressure angle, pitch curvature,
radius of curvature, contact point in the world and on the cam, the guide forces of
mode (a) with friction, F_N, a Hertz-like stress and the torque, and the per-design
maxima) and times it per design beside the numpy floor (bench/floor.py). It counts
the same operations, not the same numbers (the stress constant, preload and guide
dimensions are stand-ins): a measure of cost only.

numba is not a dependency; run it in a scratch environment:

    python3 -m venv /tmp/nbenv --system-site-packages
    /tmp/nbenv/bin/pip install numba
    /tmp/nbenv/bin/python bench/experiments/numba_fused.py

2026-11-25 on the 2-core machine: 0.30 ms per design (compile 0.56 s) against the
floor's 0.35 ms, i.e. the grid's whole work at 1.16x the floor's rate.
"""

import math
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from floor import constants, floor  # noqa: E402

from camcore.analysis import analyze  # noqa: E402
from camcore.model import load_preset  # noqa: E402


@numba.njit(cache=False, fastmath=False)
def kernel(theta, h, b1, t2, b3, y0s, sigma, r, faces, mu, d, l1, l2, Fk, M, w2, g, out):
    two_pi = 2 * math.pi
    B, N = theta.shape
    F = faces.shape[1]
    for b in range(B):
        phimax = 0.0
        rhomin = 1e300
        smax = 0.0
        fnmin = 1e300
        tmax = -1e300
        y0 = y0s[b]
        for k in range(N):
            th = theta[b, k]
            x1 = min(max(th / b1, 0.0), 1.0)
            x3 = min(max((th - t2) / b3, 0.0), 1.0)
            S = h * (x1 - math.sin(two_pi * x1) / two_pi) - h * (
                x3 - math.sin(two_pi * x3) / two_pi
            )
            V = 0.0
            A = 0.0
            if th < b1:
                V = h / b1 * (1 - math.cos(two_pi * x1))
                A = two_pi * h / b1**2 * math.sin(two_pi * x1)
            elif th >= t2 and th < t2 + b3:
                V = -h / b3 * (1 - math.cos(two_pi * x3))
                A = -two_pi * h / b3**2 * math.sin(two_pi * x3)
            Y = y0 + S
            cs = math.cos(th)
            sn = math.sin(th)
            Ft = M * (g + A * w2) + Fk * (S + 0.01)
            mu_sv = mu * (1.0 if V > 0 else (-1.0 if V < 0 else 0.0))
            for i in range(F):
                xc = faces[b, i]
                u = xc + V
                hyp = math.hypot(u, Y)
                phi = math.atan(u / abs(Y))
                kap = (Y * Y + u * (u + V) - A * Y) / hyp**3
                rho = sigma / kap - r
                nx = sigma * u / hyp
                ny = sigma * Y / hyp
                px = xc - r * nx
                py = Y - r * ny
                bx = cs * px - sn * py
                by = sn * px + cs * py
                # guide forces, mode (a)
                t = nx / ny
                a_ = t * mu_sv - 1.0
                bb = t * mu_sv + 1.0
                arm1 = l1 - S - r
                arm2 = arm1 + l2
                m1 = arm1 - mu_sv * (d / 2 - xc)
                m2 = -arm2 - mu_sv * (-d / 2 - xc)
                det = a_ * m2 - bb * m1
                F1 = Ft * (bb * xc - t * m2) / det
                F2 = Ft * (t * m1 - a_ * xc) / det
                FN = (Ft + mu_sv * (F1 + F2)) / ny
                req = 1.0 / (1.0 / abs(rho) + 1.0 / abs(r))
                st = math.sqrt(max(FN, 0.0) / (math.pi * 0.01 * req * 1e-11))
                torque = -(px * FN * ny - py * FN * nx)
                phimax = max(phimax, abs(phi))
                rhomin = min(rhomin, rho)
                smax = max(smax, st)
                fnmin = min(fnmin, FN)
                tmax = max(tmax, torque + bx * 0 + by * 0)
        out[b, 0] = phimax
        out[b, 1] = rhomin
        out[b, 2] = smax
        out[b, 3] = fnmin
        out[b, 4] = tmax


def main():
    d = load_preset("paper_example")
    a = analyze(d, verify=False)
    c = constants(d)
    th = a.theta
    B = 64
    theta = np.tile(th, (B, 1))
    y0s = c["y0"] + np.linspace(0, 0.02, B)
    faces = np.tile(np.array(c["faces"]), (B, 1))
    out = np.zeros((B, 5))
    args = (
        theta,
        c["h"],
        c["b1"],
        c["t2"],
        c["b3"],
        y0s,
        c["sigma"],
        c["r"],
        faces,
        0.1,
        0.02,
        0.05,
        0.06,
        1e4,
        0.5,
        1e4,
        9.81,
        out,
    )
    t0 = time.perf_counter()
    kernel(*args)
    print(f"compile s {time.perf_counter() - t0:.2f}")
    ts = []
    for _ in range(20):
        t0 = time.process_time()
        kernel(*args)
        ts.append(time.process_time() - t0)
    per = np.median(ts) / B * 1e3
    fl = []
    for _ in range(80):
        t0 = time.process_time()
        floor(th, c)
        fl.append(time.process_time() - t0)
    f = np.median(fl) * 1e3
    print(
        f"numba fused grid work per design {per:.3f} ms; numpy floor {f:.3f} ms; "
        f"ratio floor/numba {f / per:.2f}"
    )


if __name__ == "__main__":
    main()
