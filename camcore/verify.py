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

The profile is the cam as made: a polyline whose chords stray from the exact cam by
at most its measured chord error (camcore.sampling). The follower meets it as a real
body would: a concave face rests on vertices only (a disk holding both ends of a chord
holds the chord), but a roller can rest on a chord's middle, so for rollers the top of
the chord's offset line counts too (the maximum of the concave function
Y(t) + sqrt(r^2 - (X(t) - x_c)^2) along a chord is at an end or where the chord's
upward normal points at the roller's centre). The check runs at the analysis angles
and half-way between them, against S(theta) evaluated there, so it measures the
profile between the vertices and the grid: on a correct design the lift differs from
S by at most the chord error over cos(pressure angle).

Speed: the maximum above is over all M vertices at each of N angles, O(N M). Most
vertices cannot matter: any vertex's value is a lower bound L of Y_C, and only
vertices in a wedge of directions (seen from the cam axis) can reach above L:

* roller (r > 0): a vertex counts only if Y_j >= L - r and |X_j - x_c| <= r, so if
  L - r > 0 it lies between the directions of the corners of the box
  [x_c - r, x_c + r] x [L - r, rho_max] (a double roller's face: on its own side);
* concave face (r < 0): a vertex counts only if it is at least |r| from the point
  (x_c, L) (it lies on or outside the face circle through L); as every vertex is
  within rho_max of the axis, this confines its direction psi to
  cos(psi - psi_C) <= (rho_max^2 + |C|^2 - r^2) / (2 rho_max |C|), psi_C the
  direction of (x_c, L).

L is the best value of the few vertices (and chords) right under each face, over all
the faces (the faces' centres are at one height and the highest lifts the follower,
so any face's value bounds the lift from below): where a sound cam touches a face it
is exact or close, so the wedges are narrow, and a face off the cam prunes to little
or nothing. The vertices are sorted once by polar angle, so each wedge is a contiguous
run. For concave and flat faces the wedge is then tightened with the largest radius
inside it instead of the profile's (only those vertices can count, and they lie within
it). Each angle evaluates its own run (angles with runs of about one length in one
pass: a pass over a block of consecutive angles spanned the union of their runs,
twice a roller's own). The pruned maximum is over a superset of the vertices (and
chords, with the room _face_max gives a chord's ends) that can attain it, with the
same arithmetic, so it equals the full maximum exactly whatever L is (a loose L only
widens the wedge); angles where no bound applies (a follower narrower than the vertex
spacing, a wedge of everything) use the full maximum.
"""

from __future__ import annotations

import math

import numpy as np

CHUNK = 192  # cam angles per block of the full maximum: memory CHUNK x vertices x 8 bytes
RUN_ELEMENTS = 6000  # angles x vertices per pass of the pruned maximum: 48 kB
# temporaries, which glibc's malloc reuses; from ~10,000 it trimmed and refaulted its
# heap at every pass (a fresh process: a double roller's check 23 -> 31 ms, 6,000 page
# faults; where the heap is kept, as in a --fast sweep, larger passes gain ~10 %)
_SLACK = 1e-9  # [rad] widening of every wedge against round-off in its bounds
T_ROOM = 1e-9  # a chord's parameter t may pass its ends by this much (_face_max)


def _rotate(c, s, x, y):
    """Cam-frame points (x, y) seen in the world frame at the angles with cos/sin c, s
    ((n, 1) each): R(-theta) p, Eq. 11 inverted."""
    return c * x + s * y, -s * x + c * y


def _face_full(pts, nxt, length, c, s, r, x_c) -> np.ndarray:
    """max Y_C for one face over all vertices (and chords for rollers); pts, nxt:
    (x, y) of the vertices and of the next vertex of each, length: the chords'
    lengths; c, s: (n, 1)."""
    out = np.empty(c.shape[0])
    for start in range(0, c.shape[0], CHUNK):
        cc, ss = c[start : start + CHUNK], s[start : start + CHUNK]
        P, Q = _rotate(cc, ss, *pts), _rotate(cc, ss, *nxt)
        out[start : start + CHUNK] = _face_max(P, Q, length, r, x_c)
    return out


def _face_max(P, Q, length, r, x_c) -> np.ndarray:
    """Lowest centre height Y_C of a face (r, x_c) above the vertices P and, for a
    roller (r >= 0), the chords P -> Q; P, Q: (X, Y) arrays of shape (angles, m);
    length: the chords' lengths, (m,) or (angles, m) (a rotation keeps them: measured
    once in the cam frame, as np.hypot over every angle cost a third of the check)."""
    X, Y = P
    if math.isinf(r):  # a flat face (wide enough) rests on the highest vertex
        return np.max(Y, axis=1)
    dx2 = (X - x_c) ** 2
    reach = dx2 <= r * r
    yc = Y + math.copysign(1.0, r) * np.sqrt(np.where(reach, r * r - dx2, 0.0))
    best = np.where(reach, yc, -np.inf)
    if r < 0:  # a concave face holding both ends of a chord holds all of it
        return np.max(best, axis=1)
    dx, dy = Q[0] - X, Q[1] - Y
    with np.errstate(divide="ignore", invalid="ignore"):  # (a chord of length 0: masked)
        side = np.copysign(1.0 / length, dx)  # the chord's upward unit normal:
        t = (x_c - X + r * dy * side) / dx  # side * (-dy, dx); where it points at the centre
        # closed, with round-off room: a knife edge (r = 0) exactly over a vertex between
        # two chords must meet one of them (t = 1 - eps on one, -eps on the other)
        ok = (dx != 0) & (t >= -T_ROOM) & (t <= 1 + T_ROOM)
        t = np.clip(t, 0.0, 1.0)
        top = Y + t * dy + r * dx * side
    return np.max(np.where(ok, np.maximum(best, top), best), axis=1)


def _wedge(L, r, x_c, rho_max, room: float = 0.0):
    """(centre, half-width) [rad] of the world directions where a vertex can beat L;
    half-width >= pi where nothing can be pruned. ``room`` [m] widens a roller's box
    on each side: _face_max's T_ROOM takes a chord's end up to T_ROOM x its length
    beyond the face (a review: a chord longer than its end's radius was missed)."""
    hw = np.full(L.shape, 4.0)
    ctr = np.full(L.shape, math.pi / 2)
    fin = np.isfinite(L)
    if math.isinf(r):  # flat face: a vertex at radius <= rho_max reaches Y >= L only
        rho = np.broadcast_to(rho_max, L.shape)
        ok = fin & (L > 0) & (L < rho)  # within acos(L / rho_max) of straight up
        hw[ok] = np.arccos(L[ok] / rho[ok])
    elif r >= 0:  # rollers, and the knife edge (r = 0): what can beat L lies in the
        # box [x_c - r, x_c + r] x [L - r, rho_max], above the axis if L > r; its
        # directions span those of its corners (a box is convex), on the face's side
        ymin = L - r
        ok = fin & (ymin > 0)
        y0, y1 = ymin[ok], np.broadcast_to(rho_max, L.shape)[ok]
        right, left = x_c + r + room, x_c - r - room
        first = np.minimum(np.arctan2(y0, right), np.arctan2(y1, right))
        last = np.maximum(np.arctan2(y0, left), np.arctan2(y1, left))
        ctr[ok], hw[ok] = 0.5 * (first + last), 0.5 * (last - first)
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


def _face_lift(pts, nxt, length, theta, c, s, r, x_c, phi3, idx3, rho_max, radius_table, L):
    """max(L, this face's Y_C) at each angle; L: a lower bound of the lift (any face's
    value at any vertex is one: the lift is the highest face's), so that only the
    vertices that can beat it are visited (a face off the cam: few or none)."""
    M = pts[0].size
    ctr, hw = _wedge(L, r, x_c, rho_max, 2 * T_ROOM * float(length.max()))
    below, above = hw, hw.copy()  # half-widths on each side of ctr
    if not 0 <= r < math.inf:  # concave and flat faces: tighten with the runs' own radii
        below, above = _tighten(L, r, x_c, theta, ctr, below, above, phi3, radius_table, M)
    width = below + above
    full = np.maximum(below, above) >= math.pi
    best = L.copy()
    part = np.flatnonzero(~full)
    if part.size:
        # each angle's run of the polar-sorted vertices holding its wedge (world
        # direction psi = body angle phi - theta), one vertex early: a chord starting
        # just before the wedge can reach into it
        s0, e0 = _run(ctr[part] - below[part], width[part], theta[part], phi3)
        wide = e0 - s0 >= M
        full[part[wide]] = True
        part, s0, n = part[~wide], s0[~wide], (e0 - s0)[~wide]
        p3, len3 = (pts[0][idx3], pts[1][idx3]), length[idx3]  # in polar order
        chords = 0 <= r < math.inf  # only a roller (or knife edge) can rest on a chord
        reach_all = _reaches_all(r, x_c, rho_max)
        for rows, k in _by_length(n):
            ang = part[rows]
            m = _run_max(p3, len3, s0[rows], k, c[ang], s[ang], r, x_c, chords, reach_all)
            best[ang] = np.maximum(best[ang], m)
    if full.any():
        best[full] = np.maximum(best[full], _face_full(pts, nxt, length, c[full], s[full], r, x_c))
    return best


def _by_length(n: np.ndarray):
    """Groups of the angles (indices into n) with runs of about one length, shortest
    first, and the longest run of each: RUN_ELEMENTS angles x vertices a group."""
    order = np.argsort(n, kind="stable")
    i = 0
    while i < order.size:
        k = int(n[order[min(i + RUN_ELEMENTS, order.size) - 1]])  # (at least the group's)
        j = min(i + max(1, RUN_ELEMENTS // max(k, 1)), order.size)
        yield order[i:j], int(n[order[j - 1]])
        i = j


def _run_max(p3, len3, s0, k, c, s, r, x_c, chords: bool, reach_all: bool) -> np.ndarray:
    """The face's maximum over each angle's run: k vertices of the polar order (p3,
    len3: the tiled vertices and their chords' lengths) from s0 (one per angle: (n,)),
    and for a roller the chords to the next of each; the extra vertices of a shorter
    run are harmless (a superset). In polar order the vertices are the polygon's
    (follower_lift's prune), so a chord ends at the run's next vertex: the run is
    rotated once. (s0 <= 2 M and k < M: the indices stay below 3 M.)"""
    w = k + 1 if chords else k
    X, Y = _rotate(c, s, _rows(p3[0], s0, w), _rows(p3[1], s0, w))
    if not chords:
        return _vertex_max((X, Y), r, x_c, reach_all)
    return _face_max((X[:, :-1], Y[:, :-1]), (X[:, 1:], Y[:, 1:]), _rows(len3, s0, k), r, x_c)


def _rows(a: np.ndarray, start: np.ndarray, k: int) -> np.ndarray:
    """a[start[i] : start[i] + k] for each i (a contiguous 1-D array), as rows: each
    row copied from a strided view of a's windows (no index per element: half the
    cost of a gather; the plain constructor costs less than as_strided's checks)."""
    step = a.strides[0]
    return np.ndarray((a.size - k + 1, k), a.dtype, a, 0, (step, step))[start]


TIGHTEN = 1  # rounds of _tighten (a second cost more than its narrower runs saved)


def _run(lo, width, theta, phi3):
    """[s0, e0) of the polar-sorted (tiled) vertices in each body window [lo, lo + width]
    (lo in world directions, shifted to body angles by theta), as _face_lift takes it."""
    lo = lo + theta
    lo = lo - 2 * math.pi * np.floor((lo + math.pi) / (2 * math.pi))
    s0 = np.searchsorted(phi3, lo, "left") - 1
    e0 = np.searchsorted(phi3, lo + width, "right")
    return np.maximum(s0, 0), e0


def _range_max(table, s0, e0):
    """max of the array under ``table`` (sparse_table) over each [s0, e0), e0 > s0."""
    k = np.floor(np.log2(np.maximum(e0 - s0, 1))).astype(int)
    return np.maximum(table[k, s0], table[k, np.maximum(e0 - (1 << k), s0)])


def sparse_table(x: np.ndarray) -> np.ndarray:
    """Row j holds max(x[i : i + 2^j]) (padded at the end): O(1) range maxima."""
    out = [x]
    while (1 << len(out)) <= x.size:
        prev, h = out[-1], 1 << (len(out) - 1)
        out.append(np.maximum(prev, np.concatenate([prev[h:], prev[-h:]])))
    return np.stack(out)


def _tighten(L, r, x_c, theta, ctr, below, above, phi3, table, M):
    """Narrower wedges for concave and flat faces, one side at a time. The wedge assumes
    every vertex may lie at rho_max from the axis; but only the vertices inside it can
    beat L, and those on one side of ctr lie within the largest radius among them, so
    the wedge for that radius bounds that side too (its half-width grows with the
    radius). Repeated TIGHTEN times, per angle: exact, a superset of the vertices that
    can attain the maximum, as before."""
    for _ in range(TIGHTEN):
        for side in (below, above):
            ok = side < math.pi
            if not ok.any():
                continue
            start = ctr[ok] - side[ok] if side is below else ctr[ok]
            s0, e0 = _run(start, side[ok], theta[ok], phi3)
            small = (e0 - s0 < M) & (e0 > s0)
            rows = np.flatnonzero(ok)[small]
            _, h2 = _wedge(L[rows], r, x_c, _range_max(table, s0[small], e0[small]))
            side[rows] = np.minimum(side[rows], h2)
    return below, above


LOCAL = 3  # vertices on each side of the face's direction in the local lower bound


def _local_max(pts, nxt, length, theta, c, s, r, x_c, phi3, idx3, rho_max) -> np.ndarray:
    """max Y_C over the 2 LOCAL vertices (and their chords) nearest in polar angle to
    where the line X = x_c meets the profile: a lower bound of the lift, exact or close
    for any face width, and finite even for a roller narrower than the vertex spacing.

    The meeting point's direction psi = acos(x_c / rho) needs the profile radius rho
    there, which depends on psi: three fixed-point steps from rho_max settle it (the
    radius changes slowly with the angle; any direction still gives a valid bound)."""
    k = min(2 * LOCAL, idx3.size // 3)
    radius = np.hypot(pts[0], pts[1])
    rho = np.full(theta.shape, rho_max)
    for _ in range(3):
        psi = np.arccos(np.clip(x_c / np.maximum(rho, 1e-300), -1.0, 1.0))
        body = np.mod(psi + theta + math.pi, 2 * math.pi) - math.pi  # phi = psi + theta
        j0 = np.searchsorted(phi3, body)  # body >= -pi: the middle period of phi3
        rho = radius[idx3[np.clip(j0, 0, idx3.size - 1)]]
    j = idx3[np.clip((j0 - k // 2)[:, None] + np.arange(k), 0, idx3.size - 1)]
    out = np.empty(theta.size)
    step = max(1, RUN_ELEMENTS // k)  # (a pass over every angle at once mapped MBs afresh)
    for a in range(0, theta.size, step):
        jj, cc, ss = j[a : a + step], c[a : a + step], s[a : a + step]
        P = _rotate(cc, ss, pts[0][jj], pts[1][jj])
        if not 0 <= r < math.inf:  # a concave or flat face rests on vertices only
            out[a : a + step] = _vertex_max(P, r, x_c, _reaches_all(r, x_c, rho_max))
        else:
            Q = _rotate(cc, ss, nxt[0][jj], nxt[1][jj])
            out[a : a + step] = _face_max(P, Q, length[jj], r, x_c)
    return out


def _reaches_all(r: float, x_c: float, rho_max: float) -> bool:
    """A concave face wider than the whole cam: every vertex (|X| <= rho_max) is within
    |r| of x_c horizontally, with room for the rotation's round-off."""
    return r < 0 and (rho_max + abs(x_c)) * (1 + 1e-9) < -r


def _vertex_max(P, r, x_c, reach_all: bool = False) -> np.ndarray:
    """The vertex part of _face_max (a lower bound of the lift for any face);
    ``reach_all``: the caller knows every vertex is within |r| of x_c horizontally."""
    X, Y = P
    if math.isinf(r):
        return np.max(Y, axis=1)
    dx2 = (X - x_c) ** 2
    if reach_all:  # every vertex lies under the face: the same numbers without masks
        return np.max(Y + math.copysign(1.0, r) * np.sqrt(r * r - dx2), axis=1)
    reach = dx2 <= r * r
    yc = Y + math.copysign(1.0, r) * np.sqrt(np.where(reach, r * r - dx2, 0.0))
    return np.max(np.where(reach, yc, -np.inf), axis=1)


def follower_lift(
    points: np.ndarray,
    theta: np.ndarray,
    faces: list[tuple[float, float]],
    r_b: float,
    prune: bool = True,
) -> np.ndarray:
    """Lift [m] at which a follower with ``faces`` [(r, x_c), ...] just touches the cam.

    points : (M, 2) closed profile in the cam frame [m], counter-clockwise.
    theta : (N,) cam angles [rad].
    r_b : base radius [m], which fixes the zero of the lift.
    prune : skip vertices that provably cannot touch (exact, for a profile that is
        star-shaped about the axis); False gives the plain O(N M) maximum, the
        reference the tests compare against.

    -inf where nothing lies under any face (the follower would drop through).
    """
    r0, x0 = faces[0]
    sigma = 1.0 if r0 + r_b > 0 else -1.0
    # the face centre's height (the face's own for a flat face) when S = 0 (Eq. 3)
    rest = r_b if math.isinf(r0) else sigma * math.sqrt((r0 + r_b) ** 2 - x0**2)
    pts = (points[:, 0], points[:, 1])
    nxt = (np.roll(points[:, 0], -1), np.roll(points[:, 1], -1))
    length = np.hypot(nxt[0] - pts[0], nxt[1] - pts[1])  # each chord's, to the next
    theta = np.asarray(theta, dtype=float)
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    # the wedges move to the cam frame by theta: in (-pi, pi] as cos and sin see it
    # (a review: at |theta| ~ 1e9 a 2 pi wrap in floating point passed the slack)
    theta = np.arctan2(s[:, 0], c[:, 0])
    phi = np.arctan2(pts[1], pts[0])
    if prune:  # polar order must be the polygon's order for the chord runs to hold
        turns = np.diff(np.unwrap(phi))
        prune = bool(np.all(turns > 0) and turns.sum() < 2 * math.pi)
    if prune:
        order = np.argsort(phi, kind="stable")
        phi_s = phi[order]
        phi3 = np.concatenate([phi_s - 2 * math.pi, phi_s, phi_s + 2 * math.pi])
        idx3 = np.tile(order, 3)
        rho_max = float(np.hypot(*pts).max())
        radius_table = sparse_table(np.hypot(*pts)[idx3])
    best = np.full(theta.size, -np.inf)
    if not prune:
        for r, x_c in faces:
            best = np.maximum(best, _face_full(pts, nxt, length, c, s, r, x_c))
        return best - rest
    # the faces' centres are at one height and the highest face lifts the follower, so
    # each face's value at the vertices right under it bounds the lift from below: the
    # best of them (exact or close where a face touches: the wedges are narrow)
    for r, x_c in faces:
        L = _local_max(pts, nxt, length, theta, c, s, r, x_c, phi3, idx3, rho_max)
        best = np.maximum(best, L)
    for r, x_c in faces:
        best = _face_lift(
            pts, nxt, length, theta, c, s, r, x_c, phi3, idx3, rho_max, radius_table, best
        )
    return best - rest


UNPRUNED_BUDGET = 4_000_000  # angles x vertices per face where pruning does not apply


def check_angles(theta: np.ndarray, vertices: int = 0, star_shaped: bool = True) -> np.ndarray:
    """The analysis angles and the angles half-way between them (and to 2 pi).

    A profile that is not star-shaped is already rejected (profile_crossing) and its
    check costs O(N M) without pruning: it runs at UNPRUNED_BUDGET / M (at least 36)
    evenly spread analysis angles, enough to say how far off the profile is."""
    if not star_shaped:
        n = max(36, UNPRUNED_BUDGET // max(vertices, 1))
        return theta[:: max(1, math.ceil(theta.size / n))]
    mid = 0.5 * (theta + np.append(theta[1:], 2 * math.pi))
    return np.sort(np.concatenate([theta, mid]))


def max_lift_error(a) -> float:
    """Largest |lift - S(theta)| [m] of the finished profile of ``a`` (an Analysis), at
    the analysis angles and half-way between them.

    Angles where no face touches the cam (a broken dwell, reported as contact_lost)
    are skipped; if the follower finds nothing to rest on where a face should touch,
    the error there counts as the profile's diameter, a finite value far above any
    tolerance.
    """
    from . import motion, profile

    th = check_angles(a.theta, a.profile.points.shape[0], a.profile.is_star_shaped())
    prog = motion.program(a.design, th)
    touching = profile.contact_windows(a.geo, prog, a.segments)[0].any(axis=0)
    faces = [(f.r, f.x_c) for f in a.geo.faces]
    lift = follower_lift(a.profile.points, th, faces, a.geo.r_b)
    err = np.abs(lift - prog.S)
    err = np.where(np.isfinite(err), err, 2.0 * float(np.abs(a.profile.points).max()))
    err = err[touching]
    return float(err.max()) if err.size else 0.0
