"""Independent geometric check of a synthesized cam.

It does not use the synthesis equations. It takes the finished profile as a closed
polyline in the cam frame, turns it to each cam angle theta (the cam turns
clockwise: a cam-fixed point p appears at R(-theta) p, Eq. 11 inverted), and
lowers the follower onto it: for every follower circle (signed radius r, centre
abscissa x_c) it finds the lowest centre height at which no profile vertex is
inside the follower,

    Y_C = max_j [ Y_j + sign(r) sqrt(r^2 - (X_j - x_c)^2) ]   over |X_j - x_c| <= |r|

(a roller rests on top of the points, a concave face's centre hangs below them).
The follower's lift is the highest of its faces' Y_C minus the height at which it
rests on the base circle, sigma sqrt((r + r_b)^2 - e^2). Comparing with S(theta)
catches a wrong face, a wrong sign, a wrong rotation sense or a wrong dwell radius.

Because the profile's vertices include the synthesized contact point of every
analysed angle, and the cam is convex, the check is exact to round-off on a
correct design (a chord of a convex cam never reaches further than its vertices).

Speed: the maximum above is over all M vertices at each of N angles, O(N M). Most
vertices cannot matter: any vertex's value is a lower bound L of Y_C, and only
vertices in a wedge of directions (seen from the cam axis) can reach above L:

* roller (r > 0): a vertex counts only if Y_j >= L - r and |X_j| <= |x_c| + r, so if
  L - r > 0 it lies within atan((|x_c| + r) / (L - r)) of straight up;
* concave face (r < 0): a vertex counts only if it is at least |r| from the point
  (x_c, L) (it lies on or outside the face circle through L); as every vertex is
  within rho_max of the axis, this confines its direction psi to
  cos(psi - psi_C) <= (rho_max^2 + |C|^2 - r^2) / (2 rho_max |C|), psi_C the
  direction of (x_c, L).

L comes from a strided sample of the vertices at the same angle; the vertices are
sorted once by polar angle, so each wedge is a contiguous run. The pruned maximum is
over a superset of the vertices that can attain it, with the same arithmetic, so it
equals the full maximum exactly; angles where no bound applies (a follower narrower
than the vertex spacing, a wedge of everything) use the full maximum.
"""

from __future__ import annotations

import math

import numpy as np

CHUNK = 192  # cam angles per block of the full maximum: memory CHUNK x vertices x 8 bytes
BLOCK = 32  # consecutive cam angles per block of the pruned maximum
SAMPLE = 64  # vertices in the strided sample that gives the lower bound L
_SLACK = 1e-9  # [rad] widening of every wedge against round-off in its bounds


def _face_full(px, py, c, s, r, x_c) -> np.ndarray:
    """max_j Y_C for one face over all vertices (c, s: (n, 1) cos/sin of the angles)."""
    out = np.empty(c.shape[0])
    for start in range(0, c.shape[0], CHUNK):
        cc, ss = c[start:start + CHUNK], s[start:start + CHUNK]
        out[start:start + CHUNK] = _face_max(cc * px + ss * py, -ss * px + cc * py, r, x_c)
    return out


def _face_max(X, Y, r, x_c, valid=None) -> np.ndarray:
    dx2 = (X - x_c) ** 2
    reach = dx2 <= r * r
    if valid is not None:
        reach &= valid
    yc = Y + math.copysign(1.0, r) * np.sqrt(np.where(reach, r * r - dx2, 0.0))
    return np.max(np.where(reach, yc, -np.inf), axis=1)


def _wedge(L, r, x_c, rho_max):
    """(centre, half-width) [rad] of the world directions where a vertex can beat L;
    half-width >= pi where nothing can be pruned."""
    hw = np.full(L.shape, 4.0)
    ctr = np.full(L.shape, math.pi / 2)
    fin = np.isfinite(L)
    if r > 0:
        ymin = L - r
        ok = fin & (ymin > 0)
        hw[ok] = np.arctan2(abs(x_c) + r, ymin[ok])
    else:
        cnorm = np.hypot(x_c, np.where(fin, L, 0.0))
        ok = fin & (cnorm < -r) & (cnorm > 0)
        with np.errstate(divide="ignore", invalid="ignore"):
            k = (rho_max**2 + cnorm**2 - r * r) / (2.0 * rho_max * cnorm)
        ok &= k < 1.0
        k = np.clip(k, -1.0, 1.0)
        hw[ok] = math.pi - np.arccos(k[ok])
        ctr[ok] = np.arctan2(L[ok], x_c) + math.pi
    return ctr, np.where(hw < math.pi, hw + _SLACK, 4.0)


def _face_lift(px, py, theta, c, s, r, x_c, phi3, idx3, rho_max) -> np.ndarray:
    M = px.size
    # lower bound from a strided sample (any vertex's value is one)
    stride = max(1, M // SAMPLE)
    L = _face_max(c * px[::stride] + s * py[::stride], -s * px[::stride] + c * py[::stride],
                  r, x_c)
    ctr, hw = _wedge(L, r, x_c, rho_max)
    # world direction psi = body angle phi - theta: the body window starts at lo
    lo = ctr - hw + theta
    full = hw >= math.pi
    best = L.copy()
    part = np.flatnonzero(~full)
    if part.size:
        # blocks of consecutive angles share one contiguous run of the polar-sorted
        # vertices (a view, no gather); extra vertices in the run are harmless
        px3, py3 = px[idx3], py[idx3]
        for i in range(0, part.size, BLOCK):
            rows = part[i:i + BLOCK]
            lo_r = lo[rows]
            lo_r = lo_r - 2 * math.pi * math.floor((lo_r.min() + math.pi) / (2 * math.pi))
            s0 = int(np.searchsorted(phi3, lo_r.min(), "left"))
            e0 = int(np.searchsorted(phi3, (lo_r + 2 * hw[rows]).max(), "right"))
            if e0 - s0 >= M:
                full[rows] = True
                continue
            qx, qy = px3[s0:e0], py3[s0:e0]
            cc, ss = c[rows], s[rows]
            m = _face_max(cc * qx + ss * qy, -ss * qx + cc * qy, r, x_c)
            best[rows] = np.maximum(best[rows], m)
    if full.any():
        best[full] = np.maximum(best[full], _face_full(px, py, c[full], s[full], r, x_c))
    return best


def follower_lift(
    points: np.ndarray, theta: np.ndarray, faces: list[tuple[float, float]], r_b: float,
    prune: bool = True,
) -> np.ndarray:
    """Lift [m] at which a follower with ``faces`` [(r, x_c), ...] just touches the cam.

    points : (M, 2) closed profile in the cam frame [m].
    theta : (N,) cam angles [rad].
    r_b : base radius [m], which fixes the zero of the lift.
    prune : skip vertices that provably cannot touch (exact); False gives the plain
        O(N M) maximum, the reference the tests compare against.

    -inf where no vertex lies under any face (the follower would drop through).
    """
    r0, x0 = faces[0]
    sigma = 1.0 if r0 + r_b > 0 else -1.0
    rest = sigma * math.sqrt((r0 + r_b) ** 2 - x0**2)
    px, py = points[:, 0], points[:, 1]
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    if prune:
        phi = np.arctan2(py, px)
        order = np.argsort(phi, kind="stable")
        phi_s = phi[order]
        phi3 = np.concatenate([phi_s - 2 * math.pi, phi_s, phi_s + 2 * math.pi])
        idx3 = np.tile(order, 3)
        rho_max = float(np.hypot(px, py).max())
    best = np.full(theta.size, -np.inf)
    for r, x_c in faces:
        face = (_face_lift(px, py, theta, c, s, r, x_c, phi3, idx3, rho_max) if prune
                else _face_full(px, py, c, s, r, x_c))
        best = np.maximum(best, face)
    return best - rest


def max_lift_error(a) -> float:
    """Largest |lift - S(theta)| [m] over the analysis grid of ``a`` (an Analysis).

    Angles where no face touches the cam (a broken dwell, reported as contact_lost)
    are skipped; if the follower finds no vertex to rest on where a face should touch,
    the error there counts as the profile's diameter, a finite value far above any
    tolerance.
    """
    faces = [(f.r, f.x_c) for f in a.geo.faces]
    lift = follower_lift(a.profile.points, a.theta, faces, a.geo.r_b)
    err = np.abs(lift - a.prog.S)
    touching = a.in_contact.any(axis=0)
    err = np.where(np.isfinite(err), err, 2.0 * float(np.abs(a.profile.points).max()))
    err = err[touching]
    return float(err.max()) if err.size else 0.0
