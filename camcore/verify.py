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
"""

from __future__ import annotations

import math

import numpy as np

CHUNK = 192  # cam angles per block: bounds memory at CHUNK x vertices x 8 bytes


def follower_lift(
    points: np.ndarray, theta: np.ndarray, faces: list[tuple[float, float]], r_b: float
) -> np.ndarray:
    """Lift [m] at which a follower with ``faces`` [(r, x_c), ...] just touches the cam.

    points : (M, 2) closed profile in the cam frame [m].
    theta : (N,) cam angles [rad].
    r_b : base radius [m], which fixes the zero of the lift.
    """
    r0, x0 = faces[0]
    sigma = 1.0 if r0 + r_b > 0 else -1.0
    rest = sigma * math.sqrt((r0 + r_b) ** 2 - x0**2)
    # Only vertices within the follower's reach can matter: those farther from the
    # axis than the base circle's top point minus a follower diameter are skipped
    # cheaply below by the |X - x_c| <= |r| test.
    px, py = points[:, 0], points[:, 1]
    out = np.empty(theta.size)
    for start in range(0, theta.size, CHUNK):
        th = theta[start:start + CHUNK, None]
        c, s = np.cos(th), np.sin(th)
        X = c * px + s * py  # world coordinates of every vertex at every angle
        Y = -s * px + c * py
        best = np.full(th.shape[0], -np.inf)
        for r, x_c in faces:
            dx2 = (X - x_c) ** 2
            reach = dx2 <= r * r
            yc = Y + math.copysign(1.0, r) * np.sqrt(np.where(reach, r * r - dx2, 0.0))
            best = np.maximum(best, np.max(np.where(reach, yc, -np.inf), axis=1))
        out[start:start + CHUNK] = best - rest
    return out


def max_lift_error(a) -> float:
    """Largest |lift - S(theta)| [m] over the analysis grid of ``a`` (an Analysis)."""
    faces = [(f.r, f.x_c) for f in a.geo.faces]
    lift = follower_lift(a.profile.points, a.theta, faces, a.geo.r_b)
    return float(np.max(np.abs(lift - a.prog.S)))
