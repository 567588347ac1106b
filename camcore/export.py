"""Exports for manufacturing: STL solid, DXF profile, CSV points, design JSON.

All exports are in millimetres. The STL is the profile extruded by the cam width
w (z from 0 to w). The profile of a valid design is convex, hence star-shaped
about the cam axis, so each cap is a triangle fan around the axis: the solid is
watertight by construction and its volume is exactly the polygon area times w.
A profile that is not star-shaped about the axis (it crosses itself) is refused
with a clear error rather than exported as a broken part. A profile that breaks a
limit but is still star-shaped is exported as the envelope of the follower's
positions: a slight undercut (roller_undercut) or cusp (curvature_convex) is then a
sharp corner where the cam cannot follow the motion, and the CLI exits 1 and says
so (``warning``: also under the app's download buttons and in the G-code header).
"""

from __future__ import annotations

import io
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .checks import CUSPED
from .model import NAME_MAX, Design, design_to_json, edited_note, omega_rad_s, preset_edits
from .motion import RISE, SEGMENT_NAMES, per_second
from .train import on_grid
from .units import to_deg, to_mm, to_mpa, to_um_per_mcycle
from .wear import depth_per_pass, sliding_speed


class ExportError(ValueError):
    """The design cannot be exported as a solid; the message says why."""


# the limits whose breach can make a profile cross itself (checks.py)
FOLDING = CUSPED | {"curvature_face", "velocity_jump", "profile_crossing"}


def require_star_shaped(a) -> None:
    """ExportError unless the profile is star-shaped about the axis: no part, solid or
    cutter path, can be made of a profile that crosses itself."""
    if not a.profile.is_star_shaped():
        # the limits that fold a profile over itself, once each (all, if none of them)
        folding = [v for v in a.violations if v.code in FOLDING] or list(a.violations)
        named = dict.fromkeys(f"{v.code} ({v.equation})" for v in folding)
        broken = ", ".join(named) or "none found"
        raise ExportError(
            "the profile is not star-shaped about the cam axis (it crosses itself): no "
            f"part can be made of it; fix these first: {broken}"
        )


def _profile_mm(a) -> np.ndarray:
    require_star_shaped(a)
    return a.profile.points * 1e3


def thin_evenly(points: np.ndarray, n: int) -> np.ndarray:
    """Indices of about ``n`` of a closed polyline's ``points`` (M, 2), evenly spaced
    along its length, the first kept: for drawing. (Every k-th vertex had starved the
    long stretches of a profile refined near a velocity jump: a teacher's review saw
    a constant-velocity cam's 130 deg fall drawn as two chords.)"""
    m = points.shape[0]
    if m <= n:
        return np.arange(m)
    step = np.hypot(*np.diff(points, axis=0, append=points[:1]).T)
    s = np.concatenate([[0.0], np.cumsum(step)[:-1]])  # arc length at each vertex
    idx = np.searchsorted(s, np.linspace(0.0, s[-1] + step[-1], n, endpoint=False))
    return np.unique(np.minimum(idx, m - 1))


def cam_mesh(a, max_points: int | None = None):
    """trimesh.Trimesh of the cam: profile extruded by the width, in mm, with the
    design's shaft bore, and its keyway or D flat (if any), through it.

    ``max_points`` thins the profile evenly for on-screen display (the exports use
    every vertex).
    """
    p = _profile_mm(a)
    if max_points is not None:
        p = p[thin_evenly(p, max_points)]
    return extrude(p, a.design.cam.width_mm, _checked_bore(a, p))


BORE_SEGMENTS = 256  # the fewest chords of a bore's full circle in the exported mesh


def bore_chords(radius_mm: float, span_rad: float, tol_mm: float) -> int:
    """How many chords draw an arc of ``span_rad`` of a bore of radius ``radius_mm``:
    BORE_SEGMENTS a turn at least, and as many as keep each chord within the export
    tolerance ``tol_mm`` of the circle (its sagitta R (1 - cos(step / 2)) <= tol; a
    maker's review measured a 79 mm bore's 256-gon 2.97 um inside the circle, under a
    header saying "within 0.001 mm")."""
    step = 2.0 * math.acos(max(-1.0, 1.0 - tol_mm / radius_mm))  # the widest chord [rad]
    return max(math.ceil(BORE_SEGMENTS * span_rad / (2 * math.pi)), math.ceil(span_rad / step))


def bore_outline(cam, tol_mm: float) -> np.ndarray | None:
    """The shaft hole [mm] as a closed polygon with increasing polar angle, or None;
    every chord within ``tol_mm`` (the design's export tolerance) of the circle
    (bore_chords).

    A round bore is a regular polygon. With a keyway (cam.keyway_width_mm b,
    cam.keyway_depth_mm t2) the hole is the circle plus a slot of width b reaching
    t2 beyond the bore radius, centred on +Y: the theta = 0 ray, where the follower
    sits when the rise begins, so the key fixes the cam's phase on the shaft. With a
    D flat (cam.bore_flat_mm across it) the circle is cut by a chord square to that
    ray, for the same reason. The outline stays star-shaped about the axis (its polar
    angle only increases).
    """
    R = cam.bore_diameter_mm / 2
    if R <= 0:
        return None
    if cam.keyway_width_mm <= 0 and cam.bore_flat_mm <= 0:
        m = bore_chords(R, 2 * math.pi, tol_mm)
        t = math.pi / 2 + 2 * math.pi * np.arange(m) / m
        return R * np.column_stack([np.cos(t), np.sin(t)])
    hw, foot, top = _bore_break(cam)
    a_c = math.atan2(foot, hw)  # polar angle of the right foot
    span = math.pi + 2 * a_c  # the arc from the left foot round the bottom to the right
    arc = np.linspace(math.pi - a_c, 2 * math.pi + a_c, bore_chords(R, span, tol_mm) + 1)
    circle = R * np.column_stack([np.cos(arc), np.sin(arc)])
    if top == foot:  # a flat: the closing edge, from the arc's end to its start
        return circle
    return np.vstack([[[hw, top], [-hw, top]], circle])


def _bore_break(cam) -> tuple[float, float, float]:
    """Where a keyway or a D flat breaks the bore circle, on the theta = 0 ray [mm]:
    the half-width hw of the break, the height ``foot`` where its sides meet the
    circle and its ``top``. A keyway: its half-width b / 2, the sides' feet and the
    slot's top R + t2. A flat: the chord at the across-flat size less the radius,
    from one foot to the other (top = foot: no sides)."""
    R = cam.bore_diameter_mm / 2
    if cam.keyway_width_mm > 0:
        hw = cam.keyway_width_mm / 2
        return hw, math.sqrt(R * R - hw * hw), R + cam.keyway_depth_mm
    c = cam.bore_flat_mm - R  # the flat's distance from the axis
    return math.sqrt(R * R - c * c), c, c


def broken_bore_xyb(cam) -> list[tuple[float, float, float]]:
    """A keyed or D-flat bore of bore_outline as LWPOLYLINE vertices (x, y, bulge)
    [mm]: the slot's top and left side as lines (a flat: the chord alone), the circle
    from the left foot round the bottom to the right foot as one arc (bulge
    tan(angle / 4), counter-clockwise), and the right side closing it."""
    hw, foot, top = _bore_break(cam)
    bulge = math.tan((math.pi + 2 * math.atan2(foot, hw)) / 4)  # from pi - a_c to 2 pi + a_c
    if top == foot:  # a flat: the chord, then the arc back to its start
        return [(hw, foot, 0.0), (-hw, foot, bulge)]
    return [(hw, top, 0.0), (-hw, top, 0.0), (-hw, foot, bulge), (hw, foot, 0.0)]


def _checked_bore(a, p: np.ndarray) -> np.ndarray | None:
    """The bore's outline, refused where it reaches the profile polygon ``p`` [mm]: its
    chords, not only its vertices (an adversarial review: a 159.9 mm bore passed the
    80 mm vertices and crossed the chords at 79.45 mm, a self-overlapping solid)."""
    hole = bore_outline(a.design.cam, a.design.limits.export_tolerance_mm)
    if hole is not None and np.hypot(*hole.T).max() >= _nearest_mm(p):
        raise ExportError(
            f"the bore (and its keyway) reach {np.hypot(*hole.T).max():g} mm from "
            f"the axis and cut through the profile (its chords come to {_nearest_mm(p):g} mm)"
        )
    return hole


def _nearest_mm(p: np.ndarray) -> float:
    """How close the closed polygon p (n, 2) comes to the axis: its nearest edge point."""
    d = np.roll(p, -1, axis=0) - p
    t = np.clip(-np.sum(p * d, axis=1) / np.maximum(np.sum(d * d, axis=1), 1e-300), 0.0, 1.0)
    return float(np.hypot(*(p + t[:, None] * d).T).min())


def extrude(p: np.ndarray, width: float, hole: np.ndarray | None = None):
    """Watertight prism over a polygon p (n, 2), counter-clockwise and star-shaped
    about the origin, from z = 0 to z = width, with the polygonal ``hole`` (star-shaped
    about the origin, increasing polar angle; see bore_outline) through it, if given.

    Caps: a triangle fan around the origin, or with a hole a "zipper" strip between
    the two rings, advancing along whichever ring comes next in polar angle (valid
    because both rings are star-shaped about the origin).
    """
    import trimesh

    n = p.shape[0]
    if hole is not None:
        a0 = math.atan2(p[0, 1], p[0, 0])
        ang = np.mod(np.arctan2(hole[:, 1], hole[:, 0]) - a0, 2 * math.pi)
        inner = np.roll(hole, -int(np.argmin(ang)), axis=0)  # first at or after ray a0
        cap = _zipper(p, inner, a0)  # indices: outer 0..n-1, inner n..n+m-1
    else:
        inner = np.zeros((1, 2))  # the axis point as the fan's centre
        i = np.arange(n)
        cap = np.column_stack([i, (i + 1) % n, np.full(n, n)])
    ring = np.vstack([p, inner])
    k = ring.shape[0]
    verts = np.vstack(
        [np.column_stack([ring, np.zeros(k)]), np.column_stack([ring, np.full(k, width)])]
    )
    faces = [cap + k, cap[:, ::-1]]  # top faces +z, bottom faces -z
    faces += _wall(np.arange(n), k)  # outer wall, facing out
    if hole is not None:
        faces += _wall(n + np.arange(inner.shape[0])[::-1], k)  # bore wall, facing the axis
    return trimesh.Trimesh(vertices=verts, faces=np.vstack(faces), process=False)


def _wall(loop: np.ndarray, k: int) -> list[np.ndarray]:
    """Quads (as triangle pairs) between the bottom and top copies of a closed loop."""
    i, j = loop, np.roll(loop, -1)
    return [np.column_stack([i, j, j + k]), np.column_stack([i, j + k, i + k])]


def _zipper(p: np.ndarray, inner: np.ndarray, a0: float) -> np.ndarray:
    """Counter-clockwise triangles between the outer ring p (n points, polar angles
    increasing from a0) and the inner ring (m points, polar angles increasing from its
    first point, which lies at or just after the ray a0)."""
    n, m = p.shape[0], inner.shape[0]
    ang_o = a0 + np.mod(np.arctan2(p[:, 1], p[:, 0]) - a0, 2 * math.pi)
    ang_i = a0 + np.mod(np.arctan2(inner[:, 1], inner[:, 0]) - a0, 2 * math.pi)
    next_o = np.append(ang_o[1:], a0 + 2 * math.pi)
    next_i = np.append(ang_i[1:], ang_i[0] + 2 * math.pi)
    is_outer = np.concatenate([np.ones(n, bool), np.zeros(m, bool)])
    order = np.lexsort((~is_outer, np.concatenate([next_o, next_i])))
    step_outer = is_outer[order]
    i = np.cumsum(step_outer) - step_outer  # outer vertex before each step
    j = np.cumsum(~step_outer) - ~step_outer  # inner vertex before each step
    o0, o1 = i % n, (i + 1) % n
    i0, i1 = n + j % m, n + (j + 1) % m
    return np.where(
        step_outer[:, None], np.column_stack([o0, o1, i0]), np.column_stack([o0, i1, i0])
    )


WELD_MM = 1e-3  # a vertex merged away by the weld lies this close to a kept one at most
MIN_EDGE_MM = 1e-5  # shorter edges are merged: float32 resolves ~8e-6 mm at 100 mm, and
# readers weld vertices closer than their own tolerance (trimesh: 1e-8)


def weld_float32(p: np.ndarray) -> np.ndarray:
    """The polygon p (n, 2) [mm] as STL will store it: rounded to 32-bit floats, with
    every vertex dropped that does not advance strictly counter-clockwise about the axis
    from the one before (a duplicate, or one on the same ray) or lies within MIN_EDGE_MM
    of it.

    A reader welds equal vertices and drops zero-area triangles; a mesh built from the
    float64 polygon (e.g. the two contact points of a double follower with e = 1e-6 mm)
    would then have holes. The dropped vertices lie within WELD_MM of a kept one."""
    q = p.astype(np.float32).astype(np.float64)
    while True:
        prev = np.roll(q, 1, axis=0)
        advance = prev[:, 0] * q[:, 1] - prev[:, 1] * q[:, 0]  # cross(prev, this)
        drop = (advance <= 0) | (np.hypot(*(q - prev).T) < MIN_EDGE_MM)
        if not drop.any():
            return q
        if q.shape[0] - drop.sum() < 3:
            raise ExportError("the profile collapses at 32-bit precision")
        gap = np.hypot(*(q - prev)[drop].T).max()
        if gap > WELD_MM:
            raise ExportError(
                f"the profile turns back by {gap:.3g} mm about the axis; it is not star-shaped"
            )
        q = q[~drop]


def plain(text: str, n: int = 80) -> str:
    """User text (a design name) for a file format that has no escaping: printable
    ASCII only, at most ``n`` characters (a newline would end a DXF value early)."""
    return re.sub(r"[^A-Za-z0-9 _.,:=+\-/()&]", "_", text)[:n]


def file_label(a, edited: bool = True) -> str:
    """What an exported part is, written into the file (a maker's review: the STL's
    header was all zeros, the DXF said nothing of its design), and, if ``edited``,
    whether it is an edited preset (edited_note; the DXF drawing gives that a line)."""
    # the fixed part first, then the note: a reader that cuts it short cuts the name
    note = edited_note(a.design) if edited else None
    return (
        _label_head(a, "profile within")
        + "cam "
        + (f"{note}; " if note else "")
        + plain(a.design.name, NAME_MAX)
    )


def stl_label(a, rounding_mm: float = 0.0) -> str:
    """file_label in the STL header's 80 bytes: "within", and an edited preset as
    "edited KEY" (its fields are in the other files: a user's review found the
    key cut to "paper_exa" and the name gone). ``rounding_mm``: what STL's 32-bit
    floats moved the vertices, added to the tolerance it states (an adversarial
    review: a 400 mm cam at 1e-5 mm was stored 2.1e-5 mm off, under "within 1e-05")."""
    edits = preset_edits(a.design)
    return (
        _label_head(a, "within", rounding_mm)
        + (f"edited {edits[0]}: " if edits else "cam ")
        + plain(a.design.name, NAME_MAX)
    )


def _label_head(a, within: str, rounding_mm: float = 0.0) -> str:
    """The fixed start of file_label and stl_label: program, version, unit, tolerance
    (with ``rounding_mm`` added, to 2 digits rounded up, where it is not negligible)."""
    from . import package_version

    tol = a.design.limits.export_tolerance_mm
    if rounding_mm > 0.01 * tol:
        tol = round_up(tol + rounding_mm, 2)
    return f"camdesigner {package_version()}, mm, {within} {tol:g} mm: "


def round_up(x: float, digits: int = 3) -> float:
    """x rounded up to ``digits`` significant digits (a bound must not shrink)."""
    if x <= 0:
        return x
    scale = 10.0 ** (digits - 1 - math.floor(math.log10(x)))
    return math.ceil(x * scale) / scale


def stl_bytes(a) -> bytes:
    """Binary STL of the cam solid [mm], built from the float32-welded profile; its
    80-byte header says what it is (stl_label; never "solid...", which some readers
    take for an ASCII STL)."""
    exact = _profile_mm(a)
    p = weld_float32(exact)
    blob = extrude(p, a.design.cam.width_mm, _checked_bore(a, p)).export(file_type="stl")
    rounding = float(np.abs(exact.astype(np.float32).astype(np.float64) - exact).max())
    header = stl_label(a, math.hypot(rounding, rounding)).encode("ascii")[:80].ljust(80, b" ")
    return header + blob[80:]


def warning(a) -> str | None:
    """What a maker must read before making the part of ``a`` (an Analysis): the limits
    it breaks, and for an undercut or cusp that the part must not be made as it is;
    None if it breaks none."""
    if not a.violations:
        return None
    codes = sorted({v.code for v in a.violations})  # (a limit broken twice named once)
    text = (
        f"the design breaks {'these limits' if len(codes) > 1 else 'a limit'}: {', '.join(codes)}"
    )
    if CUSPED & set(codes):
        text += (
            ". The profile is undercut or cusped: the part has a sharp corner where the "
            "cam cannot follow the motion, and wears fast. Do not make it as it is"
        )
    return text


PART_KINDS = ("stl", "dxf", "dxf_cut", "csv", "toolpath")  # the exports that are the part itself


def mounting_note(a) -> str | None:
    """What a maker of ``a``'s part should know about mounting it: without a bore the
    part is a solid disc that no shaft goes through (the default, as in the paper);
    None when it has one."""
    if a.design.cam.bore_diameter_mm > 0:
        return None
    return (
        "no shaft bore (cam.bore_diameter_mm = 0): the part is a solid disc; set a bore "
        "(and a keyway or a D flat) to mount it on a shaft"
    )


def datum_note(a) -> str:
    """The DXF's note on the theta = 0 ray: what the follower does when the cam stands
    there (the program's first segment, and where the first motion after it starts if
    it is a dwell: what the cam does next, a review's program began with a dwell and a
    fall), and where the follower's axis is if it is offset."""
    segs = a.segments
    first = segs[0]

    def word(g) -> str:
        return "rise" if g.code == RISE else "fall"

    if first.is_motion:
        what = f"as the {word(first)} starts"
    else:
        move = next((g for g in segs if g.is_motion), None)
        what = f"in a dwell at S={to_mm(first.S0) + 0.0:g} mm" + (  # (no -0)
            f", the {word(move)} starts at THETA={to_deg(move.start):g} deg" if move else ""
        )
    where = (  # an offset follower is not on the ray: its stroke is parallel to it
        "follower on this ray"
        if a.geo.stem_x == 0
        else f"follower stroke parallel to this ray, axis at X={to_mm(a.geo.stem_x):g} mm,"
    )
    return f"THETA=0: {where} {what}; cam turns CW seen from +Z"


def dxf_bytes(a, reference: bool = True) -> bytes:
    """DXF (R2010, mm) for CAM/CNC software; ``reference`` False: PROFILE and BORE only
    (the outline to cut, for laser, waterjet and plasma software that cuts every layer
    whatever its plot flag: a maker's review).

    Layers: PROFILE (the closed profile, one LWPOLYLINE), BORE (the shaft hole: a true
    circle, or with a keyway its outline of three lines and a true arc, with a D flat a
    line and a true arc, which CAM software recognizes as the bore), and two reference
    layers that are not features and are set not to plot: CENTERLINES (a centre cross at
    the axis, CENTER linetype) and DATUM (the angular datum: a radial line on the theta
    = 0 ray, with a note saying what the follower does there, ``datum_note``, and one
    saying what the file is, ``file_label``; the cam turns clockwise).
    """
    import ezdxf

    p = _profile_mm(a)
    cam = a.design.cam
    doc = ezdxf.new("R2010", setup=True)  # setup: the standard linetypes (CENTER)
    doc.units = ezdxf.units.MM
    doc.header.custom_vars.append("camdesigner", file_label(a))  # (a drawing property)
    doc.layers.add("PROFILE", color=7)
    msp = doc.modelspace()
    xyb = profile_xyb(p)
    msp.add_lwpolyline(xyb, format="xyb", close=True, dxfattribs={"layer": "PROFILE"})
    if reference:
        _reference_layers(doc, a, p, xyb)
    hole = bore_outline(cam, a.design.limits.export_tolerance_mm)
    if hole is not None:
        doc.layers.add("BORE", color=3)
        if cam.keyway_width_mm > 0 or cam.bore_flat_mm > 0:
            msp.add_lwpolyline(
                broken_bore_xyb(cam), format="xyb", close=True, dxfattribs={"layer": "BORE"}
            )
        else:
            msp.add_circle(
                (0.0, 0.0), radius=cam.bore_diameter_mm / 2, dxfattribs={"layer": "BORE"}
            )
    # the drawing's extents in the header: viewers that zoom to extents find the cam
    # (a maker's review: $EXTMIN/$EXTMAX were left at their empty defaults)
    from ezdxf import bbox

    ext = bbox.extents(msp)  # written as $EXTMIN, $EXTMAX (zoom to extents finds the cam)
    msp.reset_extents(ext.extmin, ext.extmax)
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue().encode("utf-8")


ARC_RADIUS_MM = 1e-9  # vertices this near one radius lie on one dwell's arc [mm]


def profile_xyb(p: np.ndarray) -> list[tuple[float, float, float]]:
    """The closed profile ``p`` (M, 2) [mm, counter-clockwise] as LWPOLYLINE vertices
    (x, y, bulge): a dwell's arc (three or more consecutive vertices at one distance from
    the axis: in a dwell the contact point stands still, so the cam there is a circle
    about its axis) as one true arc (bulge tan(angle / 4)), the rest as its chords (a
    maker's review: lasers and CAM programs take an arc as an arc, where a chain of
    chords is ~1,000 short moves)."""
    r = np.hypot(p[:, 0], p[:, 1])
    # start where the radius changes, so that no arc runs across the polyline's ends
    # (the profile starts at theta = 0, often inside the low dwell)
    step = np.flatnonzero(np.abs(r - np.roll(r, 1)) >= ARC_RADIUS_MM)
    first = int(step[0]) if step.size else 0
    p, r = np.roll(p, -first, axis=0), np.roll(r, -first)
    polar = np.arctan2(p[:, 1], p[:, 0])
    out, i, m = [], 0, p.shape[0]
    while i < m:
        j = i
        while j + 1 < m and abs(r[j + 1] - r[i]) < ARC_RADIUS_MM:
            j += 1
        if j - i >= 2:  # an arc from vertex i to vertex j
            swept = (polar[j] - polar[i]) % (2 * np.pi)
            out.append((float(p[i, 0]), float(p[i, 1]), float(np.tan(swept / 4))))
            i = j
        else:
            out.append((float(p[i, 0]), float(p[i, 1]), 0.0))
            i += 1
    return out


def _on_plus_y(xyb: list[tuple[float, float, float]]) -> float:
    """Where the closed outline ``xyb`` (profile_xyb's vertices and bulges [mm]) crosses
    the +Y ray from the axis, on its chords or on a dwell's true arc (a circle about the
    axis), so that the datum line ends on the outline as cut (the nearest vertex had
    left it a chord's sag short: 0.14 mm at a 1 mm tolerance)."""
    v = np.array(xyb)
    p, q, bulge = v[:, :2], np.roll(v[:, :2], -1, axis=0), v[:, 2]
    arc = bulge != 0.0
    swept = 4.0 * np.arctan(bulge)  # counter-clockwise from p to q
    to_y = (np.pi / 2 - np.arctan2(p[:, 1], p[:, 0])) % (2 * np.pi)
    on_arc = arc & (to_y <= swept)
    crosses = ~arc & ((np.sign(p[:, 0]) != np.sign(q[:, 0])) | (p[:, 0] == 0.0))
    with np.errstate(all="ignore"):
        t = np.where(p[:, 0] != q[:, 0], p[:, 0] / (p[:, 0] - q[:, 0]), 0.0)
    y = np.where(on_arc, np.hypot(p[:, 0], p[:, 1]), p[:, 1] + t * (q[:, 1] - p[:, 1]))
    return float(np.max(y[(on_arc | crosses) & (y > 0)]))


def _reference_layers(doc, a, p: np.ndarray, xyb: list[tuple[float, float, float]]) -> None:
    """dxf_bytes' CENTERLINES and DATUM layers, set not to plot: the centre cross, the
    theta = 0 ray with its note, and what the file is."""
    for name, color, ltype in (("CENTERLINES", 8, "CENTER"), ("DATUM", 1, "DASHED")):
        layer = doc.layers.add(name, color=color, linetype=ltype)
        layer.dxf.plot = 0  # reference geometry, not a feature
    msp = doc.modelspace()
    r_min = float(np.hypot(p[:, 0], p[:, 1]).min())
    c = 0.15 * r_min
    msp.add_line((-c, 0.0), (c, 0.0), dxfattribs={"layer": "CENTERLINES"})
    msp.add_line((0.0, -c), (0.0, c), dxfattribs={"layer": "CENTERLINES"})
    top = _on_plus_y(xyb)
    msp.add_line((0.0, 0.3 * r_min), (0.0, top), dxfattribs={"layer": "DATUM"})
    notes = (datum_note(a), file_label(a, edited=False), edited_note(a.design))
    for text, y in zip(filter(None, notes), (0.35, 0.29, 0.23), strict=False):
        note = msp.add_text(text, height=0.04 * r_min, dxfattribs={"layer": "DATUM"})
        note.set_placement((0.02 * r_min, y * r_min))
        _fit_inside(note, 0.9 * r_min)


def _fit_inside(note, right: float) -> None:
    """Shrink the TEXT ``note`` to end by x = ``right`` [mm] (inside the cam): a note of
    the file's 110 characters had run 2.5 cam radii past the cam, and a viewer's zoom
    to extents showed mostly text (an export review)."""
    from ezdxf import bbox

    box = bbox.extents([note])
    if box.has_data and box.extmax.x > right:
        left = note.dxf.insert.x
        note.dxf.height *= (right - left) / (box.extmax.x - left)


FACE_MARGIN_MM = 2.0  # the follower drawing's face reaches this beyond the contact [mm]


def follower_dxf_bytes(a) -> bytes:
    """DXF (R2010, mm) of the follower's working faces, to build its body around: on
    layer FACE each concave face's arc (radius |r_f|, a true ARC) or the flat face's
    line, over the stretch the contact runs (report's face_contact_x_mm) and
    FACE_MARGIN_MM beyond it each way (no farther than the face's circle reaches
    across); on CENTERLINES (not plotted) the follower's axis
    and each face's centre; on NOTES (not plotted) what it is. The follower stands at
    zero lift: X from its axis, Y from the cam's axis, the cam below. A roller is a
    bearing and a knife edge its tip: ExportError says so (a maker's review: nothing
    gave the follower's faces)."""
    import ezdxf

    from .report import _face_contact_x_mm

    geo, f = a.geo, a.design.follower
    if not (geo.flat or f.kind.is_concave):
        rollers = "its rollers are bearings" if f.kind.is_double else "its roller is a bearing"
        what = "its tip is a point" if geo.r == 0 else f"{rollers} (r_c {to_mm(geo.r):g} mm)"
        raise ExportError(f"a {f.kind.label} follower has no face to draw: {what}")
    # each face with its own stretch (a face that never touches is not drawn)
    faces = [
        (face, span)
        for face, span in zip(geo.faces, _face_contact_x_mm(a).values(), strict=False)
        if span is not None
    ]
    if not faces:
        raise ExportError("no face touches the cam: there is no working face to draw")
    doc = ezdxf.new("R2010", setup=True)
    doc.units = ezdxf.units.MM
    doc.header.custom_vars.append("camdesigner", file_label(a))
    for name, color, ltype in (
        ("FACE", 7, "Continuous"),
        ("CENTERLINES", 8, "CENTER"),
        ("NOTES", 1, "Continuous"),
    ):
        layer = doc.layers.add(name, color=color, linetype=ltype)
        layer.dxf.plot = int(name == "FACE")
    msp = doc.modelspace()
    y0, sx = to_mm(geo.y0), to_mm(geo.stem_x)
    top = 0.0
    for face, (lo, hi) in faces:
        lo, hi = lo - FACE_MARGIN_MM, hi + FACE_MARGIN_MM
        if len(geo.faces) == 2:  # a double follower's faces stay on their own side
            lo, hi = (lo, min(hi, 0.0)) if face.x_c > 0 else (max(lo, 0.0), hi)
        if geo.flat:
            msp.add_line((lo, y0), (hi, y0), dxfattribs={"layer": "FACE"})
            top = max(top, y0)
            continue
        R, cx = -to_mm(face.r), to_mm(face.x_c) - sx  # the face's centre, below the cam
        # (the margin ends where the circle turns down: a 2.5 mm face had failed acos)
        lo, hi = max(lo, cx - R), min(hi, cx + R)
        a0, a1 = (math.degrees(math.acos((x - cx) / R)) for x in (hi, lo))  # from +X
        msp.add_arc((cx, y0), R, a0, a1, dxfattribs={"layer": "FACE"})
        msp.add_line((cx, y0 - 0.05 * R), (cx, y0 + 0.05 * R), dxfattribs={"layer": "CENTERLINES"})
        top = max(top, y0 + R)
    msp.add_line((0.0, 0.0), (0.0, top + 20.0), dxfattribs={"layer": "CENTERLINES"})
    what = (
        "flat face"
        if geo.flat
        else f"concave face{'s' if len(faces) == 2 else ''} r_f = {to_mm(-geo.r):g} mm"
    )
    for text, dy in (
        (f"{what}: the contact's stretch and {FACE_MARGIN_MM:g} mm beyond it", 8.0),
        ("follower at zero lift: X from its axis, Y from the cam's axis", 4.0),
    ):
        msp.add_text(text, height=2.5, dxfattribs={"layer": "NOTES"}).set_placement((2.0, top + dy))
    from ezdxf import bbox

    ext = bbox.extents(msp)
    msp.reset_extents(ext.extmin, ext.extmax)
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue().encode("utf-8")


_PART = {k: v.replace(" ", "_") for k, v in SEGMENT_NAMES.items()}  # CSV: no spaces


def csv_text(a) -> str:
    """Profile vertices in traversal order: the cam angle at which each is a contact
    point, x_mm, y_mm in the cam frame (Eq. 11), radius, and the profile segment."""
    p = a.profile.points * 1e3
    th = np.degrees(a.profile.theta)
    rad = np.hypot(p[:, 0], p[:, 1])
    lines = ["cam_angle_deg,x_mm,y_mm,radius_mm,segment"]
    lines += [
        f"{t:.6f},{x:.9f},{y:.9f},{r:.9f},{_PART[int(s)]}"
        for t, (x, y), r, s in zip(th, p, rad, a.profile.part, strict=True)
    ]
    return "\n".join(lines) + "\n"


def series_columns(a) -> dict[str, np.ndarray]:
    """Per cam angle, every quantity a designer plots or checks (issue 11).

    The program's segment (program_rows: numbered from 1, as the app's table). Motion
    per radian of cam angle and per second (x w, w^2, w^3); the pressure angle
    and cam radius of curvature rho at the touching face (the rise face when both
    touch); the load F_t (Eq. 29), the guide forces, and per face (``_1`` the rise face
    S1 / left roller, ``_2`` the fall face of a double follower) F_N, rho and the Hertz
    stress (Eq. 42; 0 where the face is idle), the sliding speed and the Archard wear of
    the cam point it touches per million passes (camcore.wear); the shaft torque
    (camcore.machine)."""
    p = a.prog
    v, acc, jerk = per_second(p, omega_rad_s(a.design))
    cols = {
        "theta_deg": to_deg(a.theta),
        "segment": program_rows(a.segments)[p.index],
        "S_mm": to_mm(p.S),
        "V_mm_per_rad": to_mm(p.V),
        "A_mm_per_rad2": to_mm(p.A),
        "J_mm_per_rad3": to_mm(p.J),
        "V_m_per_s": v,
        "A_m_per_s2": acc,
        "J_m_per_s3": jerk,
        "pressure_angle_deg": to_deg(a.primary(a.pressure_angle)),
        "rho_mm": to_mm(a.primary(a.rho)),
        "contacts": a.n_contacts,
        "Ft_N": a.Ft,
        "F1_N": a.guide.F1,
        "F2_N": a.guide.F2,
    }
    wear, slide = depth_per_pass(a), sliding_speed(a)
    for f in range(a.FN.shape[0]):
        cols[f"FN_N_{f + 1}"] = a.FN[f]
        cols[f"rho_mm_{f + 1}"] = to_mm(a.rho[f])
        cols[f"stress_MPa_{f + 1}"] = to_mpa(a.stress[f])
        cols[f"sliding_m_per_s_{f + 1}"] = slide[f]
        cols[f"wear_um_per_Mcycle_{f + 1}"] = to_um_per_mcycle(wear[f])
    cols["cam_torque_Nm"] = a.torque.sum(axis=0)
    if a.train is not None and not a.train.resonance:  # the elastic train (camcore.train)
        cols["Fc_train_N"] = on_grid(a.train, a.theta, a.train.contact_force)
        cols["x_train_mm"] = to_mm(on_grid(a.train, a.theta, a.train.x))
    return cols


def program_rows(segs) -> np.ndarray:
    """Per motion.Segment of ``segs``, the program's segment it is, numbered from 1 as
    the app's table numbers them; an empty dwell motion.segments adds between a fall
    and a rise counts as the fall's (a designer's review read 0, 1, 2, 4 for a program
    of four)."""
    rows, last = [], 0
    for g in segs:
        last = g.row if g.row is not None else last
        rows.append(last + 1)
    return np.array(rows)


def series_csv_text(a) -> str:
    """series_columns as CSV, one row per cam angle of the analysis grid."""
    cols = series_columns(a)
    lines = [",".join(cols)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in zip(*cols.values(), strict=True)]
    return "\n".join(lines) + "\n"


def json_text(design: Design) -> str:
    return design_to_json(design) + "\n"


@dataclass(frozen=True)
class ExportKind:
    """One export format: the file-name suffix added to the design's slug, and its writer."""

    suffix: str
    help: str
    write: Callable[[Any], bytes]  # Analysis -> file bytes


# The one dispatch table of exports, used by the CLI and the app alike.
EXPORTS: dict[str, ExportKind] = {
    "stl": ExportKind(".stl", "STL of the cam solid (mm)", stl_bytes),
    "dxf": ExportKind(".dxf", "DXF of the profile (mm)", dxf_bytes),
    "dxf_cut": ExportKind(
        "_cut.dxf",
        "DXF of the outline to cut only (mm; profile and bore, no reference layers)",
        lambda a: dxf_bytes(a, reference=False),
    ),
    "follower_dxf": ExportKind(
        "_follower.dxf",
        "DXF of the follower's working faces (mm; concave arcs or the flat face, over "
        "the contact's stretch)",
        follower_dxf_bytes,
    ),
    "csv": ExportKind(
        "_profile.csv", "CSV of the profile vertices", lambda a: csv_text(a).encode()
    ),
    "series": ExportKind(
        "_series.csv",
        "CSV per cam angle: S, V, A, J (per rad and per "
        "second), pressure angle, rho, forces, stress, torque",
        lambda a: series_csv_text(a).encode(),
    ),
    "toolpath": ExportKind(
        ".nc",
        "G-code of the cutter-centre path (mm; cutter "
        "cam.cutter_diameter_mm, refused where it would gouge)",
        lambda a: _toolpath().gcode(a).encode(),
    ),
    "json": ExportKind(".json", "the design as JSON", lambda a: json_text(a.design).encode()),
    "html": ExportKind(
        "_report.html",
        "the printable design report (self-contained HTML)",
        lambda a: _document().html_report(a).encode(),
    ),
    "pdf": ExportKind(
        "_report.pdf", "the printable design report as PDF", lambda a: _document().pdf_report(a)
    ),
}


def _toolpath():
    from . import toolpath  # it imports ExportError from here

    return toolpath


def _document():
    from . import document  # matplotlib is imported only when a report is asked for

    return document
