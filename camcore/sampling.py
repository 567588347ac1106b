"""The cam as it is made: the profile polyline sampled to a chordal tolerance.

The analysis grid serves the curves and the checks; the profile that is exported,
drawn and checked geometrically is sampled separately so that no chord strays from
the exact cam by more than the tolerance (``limits.export_tolerance_mm``, default
1 um), whatever the analysis resolution.

A chord of length c on a curve of radius rho deviates from it by the sagitta
c^2 / (8 rho). The contact point moves along the cam at ds/dtheta = |C'| |sigma - r
kappa_p| (the pitch-curve speed |C'| = sqrt(Y^2 + (x_c + V)^2) scaled to the parallel
curve at signed distance r), so a spacing dtheta <= sqrt(8 |rho| tol) / (ds/dtheta)
meets the tolerance. The cam angles are placed at that density (integrated over the
analysis grid, with a margin), the profile is assembled from the contact points at
those angles, and the deviation is then *measured*: exactly on the dwell arcs
(R (1 - cos(delta / 2))), and on the rise and fall curves at three points inside every
chord. A piece that still misses the tolerance is sampled again, denser.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import profile
from .motion import MOTIONS

MARGIN = 1.25  # samples per unit of the integrated density
MIN_PIECE_STEPS = 8  # chords per rise/fall piece at least (dwell pieces: 2)
MAX_VERTICES = 50_000  # cost bound over the whole profile: a cusped (invalid) cam would
# ask for millions; a valid one needs ~1,000 at 1 um and ~10,000 at the finest 0.01 um
PASSES = 3  # re-sampling passes for pieces that miss the tolerance


@dataclass(frozen=True)
class Sampled:
    """The profile at the tolerance, and the largest chord deviation measured [m]."""

    polyline: profile.Polyline
    chord_error: float


def contact_travel(a, geo: profile.Geometry) -> np.ndarray:
    """ds/dtheta [m/rad]: how fast each face's contact point moves along the cam surface
    per radian of cam angle, (F, N), for a camcore.analysis.Local ``a``.

    The face centre C runs along the pitch curve at |C'| = sqrt(Y^2 + (x_c + V)^2); the
    contact is on the parallel curve at signed distance r, so ds = |C'| |sigma - r
    kappa_p| dtheta. A flat face's contact turns with the cam's tangent: ds = rho dtheta."""
    Y = geo.y0 + a.prog.S
    rows = []
    for i, f in enumerate(geo.faces):
        if geo.flat:
            rows.append(np.abs(a.rho[i]))
        else:
            rows.append(np.hypot(Y, f.x_c + a.prog.V) * np.abs(geo.sigma - f.r * a.kappa_pitch[i]))
    return np.stack(rows)


def density(a, geo: profile.Geometry, tol: float) -> np.ndarray:
    """Samples per radian of cam angle needed on the grid of ``a`` (a
    camcore.analysis.Local) for chords within ``tol`` [m]: max over touching faces."""
    g = np.zeros(a.prog.theta.size)
    travel = contact_travel(a, geo)
    for i in range(len(geo.faces)):
        rho = np.abs(a.rho[i])
        speed = travel[i]
        with np.errstate(divide="ignore", invalid="ignore"):
            need = np.where(np.isfinite(rho) & (rho > 0), speed / np.sqrt(8 * rho * tol), 0.0)
        need = np.where(np.isfinite(need), need, 1e12)
        g = np.maximum(g, np.where(a.in_contact[i], need, 0.0))
    return g


def _angles(
    theta: np.ndarray, g: np.ndarray, cuts: np.ndarray, motion: np.ndarray, boost: np.ndarray
) -> np.ndarray:
    """Cam angles [rad] at density g (samples/rad on the grid ``theta``) between each
    pair of consecutive ``cuts`` (grid indices), times ``boost`` per piece."""
    ends = np.append(theta, 2 * math.pi)
    gg = np.append(g, g[0])
    G = np.concatenate([[0.0], np.cumsum(0.5 * (gg[1:] + gg[:-1]) * np.diff(ends))])
    floor = np.where(motion, MIN_PIECE_STEPS, 2)
    want = MARGIN * boost * (G[cuts[1:]] - G[cuts[:-1]])
    if want.sum() > MAX_VERTICES:  # over budget: every piece scaled down alike
        want *= MAX_VERTICES / want.sum()
    counts = np.maximum(floor, np.ceil(np.nan_to_num(want, posinf=MAX_VERTICES))).astype(int)
    out = []
    for p, (i, j) in enumerate(zip(cuts[:-1], cuts[1:], strict=True)):
        n = int(counts[p])
        levels = np.linspace(G[i], G[j], n, endpoint=False)
        seg_G, seg_th = G[i : j + 1], ends[i : j + 1]
        if seg_G[-1] > seg_G[0]:
            out.append(np.interp(levels, seg_G, seg_th))
        else:  # nothing to resolve (a straight piece): evenly in angle
            out.append(np.linspace(ends[i], ends[j], n, endpoint=False))
    return np.concatenate(out)


def chord_errors(poly: profile.Polyline, local) -> np.ndarray:
    """Deviation [m] of every chord of ``poly`` from the exact cam.

    Arc chords (either end on a dwell arc): the sagitta R (1 - cos(delta/2)), exact.
    Curve chords (both ends on one rise or fall, consecutive cam angles): the largest
    distance from the chord of the exact contact point at three angles inside it, found
    with ``local`` (angles -> camcore.analysis.contacts).
    """
    P, th, part = poly.points, poly.theta, poly.part
    Q = np.roll(P, -1, axis=0)
    err = np.zeros(P.shape[0])
    arc = ~np.isin(part, MOTIONS) | ~np.isin(np.roll(part, -1), MOTIONS)
    R = np.hypot(*P.T)
    delta = np.abs(
        np.angle(np.exp(1j * (np.arctan2(Q[:, 1], Q[:, 0]) - np.arctan2(P[:, 1], P[:, 0]))))
    )
    err[arc] = (R * (1 - np.cos(delta / 2)))[arc]
    curve = np.flatnonzero(~arc & (part == np.roll(part, -1)))
    if curve.size:  # (a chord across theta = 0, two rises meeting there: the short way)
        t0 = th[curve]
        t1 = t0 + np.mod(np.roll(th, -1)[curve] - t0, 2 * math.pi)
        fr = np.array([0.25, 0.5, 0.75])
        mid = (t0[:, None] + (t1 - t0)[:, None] * fr).ravel()
        loc = local(mid)
        face = np.where(loc.in_contact[0], 0, loc.in_contact.shape[0] - 1)
        X = loc.point_body[face, np.arange(mid.size)].reshape(curve.size, 3, 2)
        p0, d = P[curve][:, None, :], (Q - P)[curve][:, None, :]
        cross = np.abs(d[..., 0] * (X[..., 1] - p0[..., 1]) - d[..., 1] * (X[..., 0] - p0[..., 0]))
        with np.errstate(invalid="ignore", divide="ignore"):
            dist = cross / np.hypot(d[..., 0], d[..., 1])
        err[curve] = np.nan_to_num(dist, nan=0.0).max(axis=1)
    return err


def fill_arcs(poly: profile.Polyline, tol: float) -> profile.Polyline:
    """Vertices added on the dwell arcs so that no arc chord has a sagitta over ``tol``.

    A dwell arc (Eq. 20) is a circle about the cam axis. The contact points trace it
    only where a face rests on it; between the traces of two faces (a dwell shorter
    than the faces' spread, 2 psi, Eqs. 24/26) the assembled profile would jump across
    the arc with one long chord. A chord with an end on a dwell arc and both ends at the
    same radius lies on that arc: it gets evenly spaced vertices on the circle."""
    P, part, th = poly.points, poly.part, poly.theta
    Q = np.roll(P, -1, axis=0)
    R, RQ = np.hypot(*P.T), np.hypot(*Q.T)
    dwell = ~np.isin(part, MOTIONS) | ~np.isin(np.roll(part, -1), MOTIONS)
    a0 = np.arctan2(P[:, 1], P[:, 0])
    delta = np.mod(np.arctan2(Q[:, 1], Q[:, 0]) - a0, 2 * math.pi)
    on_arc = dwell & (np.abs(R - RQ) <= 1e-9 * R) & (delta < math.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        step = 2 * np.arccos(np.clip(1 - tol / R, -1.0, 1.0))  # sagitta = tol
        extra = np.where(on_arc, np.ceil(delta / step) - 1, 0)
    extra = np.nan_to_num(extra, nan=0.0).clip(0, MAX_VERTICES)
    room = max(0, 2 * MAX_VERTICES - P.shape[0])  # the profile's bound: two faces' points
    if extra.sum() > room:  # (only a crossed, invalid profile asks for more)
        extra *= room / extra.sum()
    extra = extra.astype(int)
    if not extra.any():
        return poly
    src = np.repeat(np.arange(P.shape[0]), extra + 1)  # each vertex then its new ones
    k = np.arange(src.size) - np.repeat(np.cumsum(extra + 1) - (extra + 1), extra + 1)
    f = k / (extra[src] + 1.0)  # 0 for the original vertex
    ang = a0[src] + f * delta[src]
    pts = np.where(
        (k == 0)[:, None], P[src], R[src, None] * np.column_stack([np.cos(ang), np.sin(ang)])
    )
    th_next = np.roll(th, -1)
    dth = np.mod(th_next - th, 2 * math.pi)
    # the new vertices lie on the dwell arc: its part, whichever end of the chord is on
    # it (a curve's last point can start the chord: the empty dwell of a fall into a rise)
    arc_part = np.where(np.isin(part, MOTIONS), np.roll(part, -1), part)
    new_part = np.where(k == 0, part[src], arc_part[src])
    return profile.Polyline(pts, new_part, np.mod(th[src] + f * dth[src], 2 * math.pi))


def sample_profile(a, geo: profile.Geometry, segs, local, cuts: np.ndarray, tol: float) -> Sampled:
    """The profile sampled to the chordal tolerance ``tol`` [m].

    a : camcore.analysis.Local on the analysis grid; geo, segs : its geometry and
    segments; local : cam angles -> contact geometry (camcore.analysis.contacts);
    cuts : grid indices that start a piece (0, segment boundaries, stations: where the
    faces in contact change); they stay exact vertex angles.
    """
    theta = a.prog.theta
    cuts = np.append(cuts, theta.size)
    motion = np.array([segs[s].is_motion for s in a.prog.index[cuts[:-1]]])
    g = density(a, geo, tol)
    boost = np.ones(cuts.size - 1)
    for _ in range(PASSES):
        th = _angles(theta, g, cuts, motion, boost)
        loc = local(th)
        poly = profile.assemble(loc.prog, segs, loc.point_body, loc.in_contact, loc.part, geo)
        poly = fill_arcs(poly, tol)
        err = chord_errors(poly, local)
        worst = float(err.max()) if err.size else 0.0
        if worst <= tol or th.size >= MAX_VERTICES - boost.size * MIN_PIECE_STEPS:
            break
        # pieces with a chord over the tolerance: sqrt(err/tol) more samples, plus margin
        piece = np.clip(
            np.searchsorted(theta[cuts[:-1]], poly.theta, "right") - 1, 0, boost.size - 1
        )
        over = np.zeros(boost.size)
        np.maximum.at(over, piece, err / tol)
        boost = np.where(over > 1, boost * np.sqrt(over) * 1.2, boost)
    return Sampled(poly, worst)
