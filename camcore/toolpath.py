"""Cutting the cam: the cutter-centre path of a 2-axis contour, and G-code for it.

An end mill of diameter D cutting the outside of the cam runs with its centre on the
profile offset outward by d = D / 2. Each offset vertex is the profile vertex moved by
d along its outward normal (the bisector of its two edges' normals, the curve's normal
to second order). Where the cam is concave tighter than the cutter (a concave radius
below d), the offset folds back and the cutter would cut into the cam (gouge): the
path is then refused, with the cam-angle ranges where it happens.

The gouge check is geometric, not taken from the curvature formulas: no point of the
cutter-centre path may come nearer to the profile polyline than d, less twice the
chord error (every path vertex is tested against every profile edge within reach,
found with a k-d tree).

Chordal accuracy. The profile's chords lie within its measured chord error e of the
exact cam; offsetting by d scales a chord's sagitta on a convex stretch of radius rho
by (rho + d) / rho, so the path lies within e (1 + d kappa_max) of the exact offset
(kappa_max the largest convex curvature of the polyline); where that passes the
export tolerance, the path offsets a profile sampled finer (for_cutter). The G-code writes its
coordinates to DECIMALS places, which moves a vertex by up to ROUNDING_MM more; the
header states the sum, rounded up (a maker's review measured the written file 0.04 um
beyond the bound that left the rounding out).
"""

from __future__ import annotations

import math
import re
import textwrap

import numpy as np
from scipy.spatial import cKDTree

from . import profile
from .export import ExportError, require_star_shaped, round_up, warning
from .model import edited_note
from .units import MM, to_deg, to_mm

FEED_PLANE_MM = 1.0  # the first plunge starts this high above the blank [mm]
SPIN_UP_S = 2  # the dwell after M3 [s] (G4 P in seconds on LinuxCNC, grbl, Mach; a
# Fanuc-style control reads P in ms: 2 ms there, too short but harmless)
DECIMALS = 4  # of the X, Y words [mm]: 0.1 um, what controllers take
ROUNDING_MM = 0.5 * 10.0**-DECIMALS * math.sqrt(2)  # the most a rounded vertex moves
MAX_MOVES = 1_000_000  # lines of cutting moves in one file (~20 MB)
FINEST_MM = 1e-5  # the finest profile sampled for a cutter path (the finest export
# tolerance a design may ask for, camcore.model.Limits)


class GougeError(ExportError):
    """The cutter does not fit: it would cut into the cam at the listed ranges."""


def vertex_normals(points: np.ndarray) -> np.ndarray:
    """Outward unit normals (M, 2) of a closed counter-clockwise polyline: the bisector
    of the two adjacent edges' outward normals (dy, -dx)."""
    edge = np.roll(points, -1, axis=0) - points
    n = np.stack([edge[:, 1], -edge[:, 0]], axis=1)
    n /= np.hypot(n[:, 0], n[:, 1])[:, None]
    v = n + np.roll(n, 1, axis=0)
    return v / np.hypot(v[:, 0], v[:, 1])[:, None]


def discrete_curvature(points: np.ndarray) -> np.ndarray:
    """Signed curvature [1/m] at each vertex of a closed CCW polyline (the circle through
    it and its neighbours; > 0 convex)."""
    a, b, c = np.roll(points, 1, axis=0), points, np.roll(points, -1, axis=0)
    ab, bc, ca = b - a, c - b, a - c
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    la, lb, lc = (np.hypot(v[:, 0], v[:, 1]) for v in (ab, bc, ca))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.nan_to_num(2.0 * cross / (la * lb * lc))


def distance_to_polyline(q: np.ndarray, points: np.ndarray, reach: float) -> np.ndarray:
    """Distance of each point q (M, 2) to the closed polyline (N, 2), in their unit, for
    points within ``reach`` of it (larger distances come back as reach). Also used by
    camcore.checks.hub_wall_mm."""
    a = points
    b = np.roll(points, -1, axis=0)
    seg = b - a
    half = 0.5 * float(np.hypot(seg[:, 0], seg[:, 1]).max())
    tree = cKDTree(0.5 * (a + b))  # edge midpoints: an edge within reach has its
    out = np.full(q.shape[0], reach)  # midpoint within reach + half its longest length
    for i, near in enumerate(tree.query_ball_point(q, reach + half)):
        if not near:
            continue
        j = np.asarray(near)
        ap = q[i] - a[j]
        L2 = (seg[j] ** 2).sum(axis=1)
        t = np.clip((ap * seg[j]).sum(axis=1) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
        d = np.hypot(*(ap - t[:, None] * seg[j]).T)
        out[i] = min(out[i], float(d.min()))
    return out


def _runs_deg(theta: np.ndarray, bad: np.ndarray) -> list[tuple[float, float]]:
    """Contiguous runs of ``bad`` as (first, last) cam angles [deg]."""
    out, start = [], None
    for i, b in enumerate(bad):
        if b and start is None:
            start = i
        if start is not None and (not b or i == bad.size - 1):
            end = i if b else i - 1
            out.append((float(to_deg(theta[start])), float(to_deg(theta[end]))))
            start = None
    return out


def cutter_path(a, cutter_diameter: float | None = None) -> tuple[np.ndarray, float]:
    """The cutter-centre path [m] (M, 2, cam frame, counter-clockwise) of ``a`` (an
    Analysis) and its chordal bound [m]; GougeError where the cutter does not fit.

    cutter_diameter [m]: default the design's cam.cutter_diameter_mm."""
    path, bound, _ = _cut(a, cutter_diameter)
    return path, bound


def for_cutter(a, D: float):
    """``a``, or ``a`` with its profile sampled finer (camcore.analysis.profile_at), so
    that the path of a cutter of diameter ``D`` [m] holds the export tolerance: its
    chordal bound e (1 + d kappa_max) exceeds the profile's e (a review: a 500 mm cutter
    on a 3 mm cam ran 2.5 mm inside the exact offset at a 0.1 mm tolerance). The profile
    is sampled no finer than FINEST_MM: a bound still over the tolerance is stated."""
    tol = a.design.limits.export_tolerance_mm * MM
    grow = 1.0 + 0.5 * D * max(float(discrete_curvature(a.profile.points).max()), 0.0)
    if a.chord_error * grow <= tol:
        return a
    from .analysis import profile_at  # (analysis is the heavier module: only when needed)

    return profile_at(a, max(FINEST_MM * MM, tol / grow))


def _cut(a, cutter_diameter: float | None) -> tuple[np.ndarray, float, np.ndarray]:
    """cutter_path's path and bound, and the profile vertices [m] it offsets (finer
    than ``a``'s where the cutter needs it: for_cutter)."""
    require_star_shaped(a)  # a self-crossing profile is no part, whatever the cutter
    D = a.design.cam.cutter_diameter_mm * MM if cutter_diameter is None else cutter_diameter
    d = 0.5 * D
    a = for_cutter(a, D)
    pts = a.profile.points
    path = pts + d * vertex_normals(pts)
    gap = distance_to_polyline(path, pts, d)
    # the exact cam is within the chord error e of the polyline, and on a concave
    # stretch looser than the cutter the offset vertices come within d e / |rho| < e of
    # the chords: only a shortfall beyond 2 e is the cutter reaching into the cam
    e = max(a.chord_error, a.design.limits.export_tolerance_mm * MM)
    bad = gap < d - 2 * e - 1e-12
    if bad.any():
        ranges = _runs_deg(a.profile.theta, bad)
        where = ", ".join(f"{lo:.2f}-{hi:.2f}" for lo, hi in ranges[:8])
        raise GougeError(
            f"a {to_mm(D):g} mm cutter would gouge the cam (a concave stretch tighter than "
            f"its radius) at cam angles {where} deg; the tightest concave radius is "
            f"{to_mm(_tightest_concave(a)):.5g} mm: a cutter of at most twice that "
            f"({2 * to_mm(_tightest_concave(a)):.4g} mm) always fits"
        )
    kappa = max(float(discrete_curvature(pts).max()), 0.0)
    return path, a.chord_error * (1.0 + d * kappa), pts


def _tightest_concave(a) -> float:
    """The tightest concave radius |rho| [m] of the cam (Eq. 21, rho < 0) where the
    follower touches it, as the report's radius_of_curvature_mm gives it; the
    polyline's own (the circle through three vertices, coarser: 66.4 mm for 66.04) only
    if the analysis has none."""
    tight = profile.radius_extremes(a.rho, a.in_contact)[1]
    if math.isfinite(tight):
        return tight
    k = discrete_curvature(a.profile.points)
    return 1.0 / -k.min() if k.min() < 0 else math.inf


def _comments(text: str) -> list[str]:
    """G-code comments of ``text``, parentheses made brackets, anything unusual
    stripped (a design name is user input; in G-code a ')' would end the comment and
    run the rest), wrapped at spaces into lines of at most 80 characters (a review: a
    note cut at 80 had named a field "cam.fe"). A line after the first starts "... ":
    a controller acts on a comment that starts with a command word (MSG, LOGOPEN,
    DEBUG, PRINT, even after spaces), and a security review had put one there from a
    long design name."""
    text = text.translate(str.maketrans("()", "[]"))
    text = re.sub(r"[^A-Za-z0-9 _.,:=+\-/&\[\]]", "_", text)
    lines = textwrap.wrap(text, 78, subsequent_indent="... ")
    return [f"({line})" for line in lines] or ["()"]


MAX_PASSES = 100  # of one file: it grows with them


def check_passes(cam) -> None:
    """ExportError if cam.pass_depth_mm asks for more than MAX_PASSES passes. (A rule
    of this export, not of the design: it had refused the whole design, and a report
    of its analysis, for a machining value; a designer's review.)"""
    if cam.passes <= MAX_PASSES:
        return
    many = f"{cam.passes} passes, " if cam.passes < 1e9 else ""  # (1e9: capped)
    raise ExportError(
        f"cam.pass_depth_mm = {cam.pass_depth_mm:g} mm would cut the "
        f"{cam.cut_depth_mm:g} mm in {many}more than {MAX_PASSES} passes: "
        f"use at least {math.ceil(cam.cut_depth_mm / MAX_PASSES * 1000) / 1000:g} mm"
    )


def check_size(cam, moves_per_pass: int) -> None:
    """ExportError if the passes would write more than MAX_MOVES cutting moves (the
    contour once per pass: 100 passes of a fine profile made a 100 MB file), naming
    the least pass depth that fits."""
    if cam.passes * moves_per_pass <= MAX_MOVES:
        return
    fits = max(1, MAX_MOVES // moves_per_pass)
    least = math.ceil(cam.cut_depth_mm / fits * 1000) / 1000
    raise ExportError(
        f"the G-code would cut {cam.passes} passes of {moves_per_pass:,} moves, more than "
        f"{MAX_MOVES:,} in one file: use a pass depth of at least {least:g} mm, or a "
        "coarser export tolerance (fewer vertices)"
    )


def _deep_pass_comments(depth: float, diameter: float) -> list[str]:
    """A pass deeper than the cutter's diameter [mm]: the operator checks the tool."""
    if depth <= diameter:
        return []
    return [
        *_comments(
            f"CAUTION: {depth:g} mm per pass, more than the cutter diameter {diameter:g} mm:"
        ),
        *_comments("check the flute length, or set a smaller depth per pass"),
    ]


def _bore_comments(cam) -> list[str]:
    """What this program leaves to other operations: the design's bore and keyway."""
    if cam.bore_diameter_mm <= 0:
        return []
    key = (
        f" and its {cam.keyway_width_mm:g} x {cam.keyway_depth_mm:g} mm keyway"
        if cam.keyway_width_mm > 0
        else f" with its flat, {cam.bore_flat_mm:g} mm across"
        if cam.bore_flat_mm > 0
        else ""
    )
    return _comments(f"not cut here: the {cam.bore_diameter_mm:g} mm bore{key}")


def _feed_comments(cam) -> list[str]:
    """What the operator must still check or set: the feeds while they are the
    program's defaults, the spindle speed while the design gives none (M3 without S)."""
    defaults = type(cam)()
    out = []
    if (cam.feed_mm_per_min, cam.plunge_mm_per_min) == (
        defaults.feed_mm_per_min,
        defaults.plunge_mm_per_min,
    ):
        out.extend(_comments("feeds are defaults: check them for your machine and material"))
    if cam.spindle_rpm == 0:
        out.extend(_comments("no spindle speed given: M3 has no S word, set it before the run"))
    return out


def _warning_comments(a) -> list[str]:
    """export.warning in comments of at most 80 characters (none for a valid design)."""
    text = warning(a)
    return [] if text is None else _comments("WARNING: " + text)


def _plain(x: float) -> str:
    """A feed or speed as G-code takes it: plain decimals, 3 places at most, never an
    exponent (":g" writes 1e+06 or 5e-05, which controllers do not read: a review)."""
    return f"{x:.3f}".rstrip("0").rstrip(".")


def _xy(p) -> str:
    """The X and Y words of a point [mm], to DECIMALS places."""
    return f"X{p[0]:.{DECIMALS}f} Y{p[1]:.{DECIMALS}f}"


ARC_TOL_MM = 1e-9  # path vertices this near one radius lie on one dwell's arc [mm]


def _contour_moves(v: np.ndarray, cam_r: np.ndarray) -> list[str]:
    """The moves from v[0] through v[1:] [mm, clockwise]: G1 chords, and each run of
    three or more vertices where the cam is at one distance from the axis (``cam_r``,
    per vertex) as one G2 arc about X0 Y0: a dwell, where the contact point stands
    still, so the cam is a circle about its axis and the cutter's path the circle a
    cutter radius out (the DXF draws it so too). I and J are the centre's offset from
    the arc's start as written (incremental, every control's default). A move after an
    arc says G1 again: both words are modal."""
    r = cam_r
    out, mode, i, m = [], "G1", 0, v.shape[0] - 1
    while i < m:
        j = i
        while j < m and abs(r[j + 1] - r[i]) < ARC_TOL_MM:
            j += 1
        if j - i >= 2:  # an arc through v[i + 1 .. j - 1] to v[j]
            x0, y0 = (round(float(c), DECIMALS) for c in v[i])
            out.append(f"G2 {_xy(v[j])} I{-x0 + 0.0:.{DECIMALS}f} J{-y0 + 0.0:.{DECIMALS}f}")
            mode, i = "G2", j
        else:
            out.append(_xy(v[i + 1]) if mode == "G1" else f"G1 {_xy(v[i + 1])}")
            mode, i = "G1", i + 1
    return out


def gcode(a, cutter_diameter: float | None = None) -> str:
    """G-code (RS-274, millimetres, absolute) that cuts the cam's outside contour.

    The blank's top face is Z = 0; the cut goes through the cam width and
    cam.breakthrough_mm below it, in cam.passes equal passes (cam.pass_depth_mm at
    most each). Cam frame: the axis at X = Y = 0, theta = 0 on +Y (the DXF datum).
    Climb milling with a clockwise spindle: the path runs clockwise around the cam.
    Each pass: a plunge at a point D beyond the path's outermost point on its ray (off
    the cam and off a blank up to the cam's largest radius + D), a straight feed in
    onto the path, the contour, and back out the same way. Feeds and spindle speed:
    cam.feed_mm_per_min, cam.plunge_mm_per_min, cam.spindle_rpm (0: M3 without S)."""
    cam = a.design.cam
    feed, plunge = _plain(cam.feed_mm_per_min), _plain(cam.plunge_mm_per_min)
    check_passes(cam)
    D = cam.cutter_diameter_mm * MM if cutter_diameter is None else cutter_diameter
    path, bound, pts = _cut(a, D)
    check_size(cam, path.shape[0] + 2)
    stated = round_up(to_mm(bound) + ROUNDING_MM)
    path = to_mm(path[::-1])  # clockwise
    cam_r = to_mm(np.hypot(*pts.T))[::-1]  # the cam's radius at each vertex
    # start at the path's outermost point and plunge D further out along its ray: the
    # cam and the blank (up to the cam's largest radius + D) lie inside that radius
    radius = np.hypot(path[:, 0], path[:, 1])
    shift = -int(np.argmax(radius))
    path, cam_r = np.roll(path, shift, axis=0), np.roll(cam_r, shift)
    start = path[0]
    lead = start * (1.0 + to_mm(D) / float(radius.max()))
    clear = math.floor(10 * (float(np.hypot(*lead)) - to_mm(D) / 2)) / 10  # the cutter's
    # nearest edge at the plunge, rounded down: a clearance must not be overstated
    depths = cam.cut_depth_mm * np.arange(1, cam.passes + 1) / cam.passes
    bottom = (
        f"Z-{cam.cut_depth_mm:g} = the cam width and {cam.breakthrough_mm:g} mm breakthrough"
        if cam.breakthrough_mm > 0
        else f"Z-{cam.width_mm:g} = the cam width exactly: add a breakthrough allowance"
    )
    passes = (
        "one pass, full depth" if cam.passes == 1 else f"{cam.passes} passes of {depths[0]:g} mm"
    )
    lines = [
        "%",
        *_comments(f"cam contour: {a.design.name}"),
        *(_comments(e) if (e := edited_note(a.design)) else []),
        *_comments(f"follower {a.design.follower.kind.value}, cutter diameter {to_mm(D):g} mm"),
        *_comments("units mm, absolute, Z0 = top of the blank, cam axis at X0 Y0, theta = 0 on +Y"),
        *_comments(f"path within {stated:g} mm of the exact offset, climb, clockwise"),
        *_comments("the cutter centre path, no cutter compensation G41/G42: G40"),
        *_comments(f"{passes}, feed {feed} plunge {plunge} mm/min"),
        *_comments(bottom),
        *_comments(f"plunge off the part, clear of a blank of radius up to {clear:.1f} mm"),
        *_comments("one contour at final size: rough out a larger blank first"),
        *_comments("work zero G54, no tool change and no length offset called: load the"),
        *_comments("cutter and set its length offset first, G43 H on a Fanuc-style control"),
        *_comments(f"rapids at Z{cam.safe_height_mm:g}: above every clamp. No coolant called"),
        *_bore_comments(cam),
        *_deep_pass_comments(depths[0], to_mm(D)),
        *_feed_comments(cam),
        *_warning_comments(a),
        # no G49: it would cancel the length offset the operator set (a maker's review)
        "G21 G90 G17 G40 G80 G54",
        f"G0 Z{cam.safe_height_mm:.4f}",
        f"G0 {_xy(lead)}",
        f"M3 S{_plain(cam.spindle_rpm)}" if cam.spindle_rpm > 0 else "M3",
        f"G4 P{SPIN_UP_S:g}",
        # down to the feed plane at rapid, beside the blank: the plunge feed is for the cut
        # (a review: from a 50 mm rapid height it fed through air for a minute)
        f"G0 Z{min(cam.safe_height_mm, FEED_PLANE_MM):.4f}",
    ]
    closed = np.vstack([path, path[:1]]), np.append(cam_r, cam_r[0])
    contour = _contour_moves(*closed) + [f"G1 {_xy(lead)}"]
    for z in depths:  # each pass starts and ends at the lead point, off the part
        lines += [f"G1 Z{-z:.4f} F{plunge}", f"G1 {_xy(start)} F{feed}"]
        lines += contour
    lines += [f"G0 Z{cam.safe_height_mm:.4f}", "M5", "M30", "%"]
    return "\n".join(lines) + "\n"
