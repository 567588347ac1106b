"""Exports for manufacturing: STL solid, DXF profile, CSV points, design JSON.

All exports are in millimetres. The STL is the profile extruded by the cam width
w (z from 0 to w). The profile of a valid design is convex, hence star-shaped
about the cam axis, so each cap is a triangle fan around the axis: the solid is
watertight by construction and its volume is exactly the polygon area times w.
A profile that is not star-shaped (a self-intersecting, undercut design) is
refused with a clear error rather than exported as a broken part.
"""

from __future__ import annotations

import io

import numpy as np

from .model import Design, design_to_json
from .motion import FALL, HIGH, LOW, RISE


class ExportError(ValueError):
    """The design cannot be exported as a solid; the message says why."""


def _profile_mm(a) -> np.ndarray:
    if not a.profile.is_star_shaped():
        raise ExportError(
            "the profile is not star-shaped about the cam axis (it crosses itself); "
            "fix the listed violations before exporting a solid"
        )
    return a.profile.points * 1e3


def cam_mesh(a, max_points: int | None = None):
    """trimesh.Trimesh of the cam: profile extruded by the width, in mm.

    ``max_points`` thins the profile evenly for on-screen display (the exports use
    every vertex).
    """
    p = _profile_mm(a)
    if max_points is not None and p.shape[0] > max_points:
        p = p[:: -(-p.shape[0] // max_points)]
    return extrude(p, a.design.cam.width_mm)


def extrude(p: np.ndarray, width: float):
    """Watertight prism over a polygon p (n, 2) that is star-shaped about the origin,
    from z = 0 to z = width; the caps are triangle fans around the origin."""
    import trimesh

    n, w = p.shape[0], width
    verts = np.vstack([
        np.column_stack([p, np.zeros(n)]),  # bottom ring 0..n-1
        np.column_stack([p, np.full(n, w)]),  # top ring n..2n-1
        [[0.0, 0.0, 0.0], [0.0, 0.0, w]],  # axis centres 2n, 2n+1
    ])
    i = np.arange(n)
    j = (i + 1) % n
    cb, ct = 2 * n, 2 * n + 1
    faces = np.vstack([
        np.column_stack([np.full(n, cb), j, i]),  # bottom cap, facing -z
        np.column_stack([np.full(n, ct), n + i, n + j]),  # top cap, facing +z
        np.column_stack([i, j, n + j]),  # side quads as two triangles, facing out
        np.column_stack([i, n + j, n + i]),
    ])
    return trimesh.Trimesh(vertices=verts, faces=faces, process=False)


def stl_bytes(a) -> bytes:
    """Binary STL of the cam solid [mm]."""
    return cam_mesh(a).export(file_type="stl")


def dxf_bytes(a) -> bytes:
    """DXF (R2010, mm) with the closed profile as an LWPOLYLINE on layer PROFILE and
    the axis as a small circle on layer AXIS, for CAM/CNC software."""
    import ezdxf

    p = _profile_mm(a)
    doc = ezdxf.new("R2010", setup=False)
    doc.units = ezdxf.units.MM
    doc.layers.add("PROFILE", color=7)
    doc.layers.add("AXIS", color=1)
    msp = doc.modelspace()
    msp.add_lwpolyline(p.tolist(), close=True, dxfattribs={"layer": "PROFILE"})
    msp.add_circle((0.0, 0.0), radius=1.0, dxfattribs={"layer": "AXIS"})
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue().encode("utf-8")


_PART = {RISE: "rise", HIGH: "high_dwell", FALL: "fall", LOW: "low_dwell"}


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


def cam_angle_csv_text(a) -> str:
    """Per cam angle: S, V, A, pressure angle, contact force, guide forces, stress."""
    th = np.degrees(a.theta)
    cols = {
        "theta_deg": th,
        "S_mm": a.prog.S * 1e3,
        "V_mm_per_rad": a.prog.V * 1e3,
        "A_mm_per_rad2": a.prog.A * 1e3,
        "pressure_angle_deg": np.degrees(a.primary(a.pressure_angle)),
        "contacts": a.n_contacts,
        "FN_N": a.guide.FN,
        "F1_N": a.guide.F1,
        "F2_N": a.guide.F2,
        "stress_MPa": a.stress.max(axis=0) / 1e6,
    }
    lines = [",".join(cols)]
    lines += [",".join(f"{v:.9g}" for v in row) for row in zip(*cols.values(), strict=True)]
    return "\n".join(lines) + "\n"


def json_text(design: Design) -> str:
    return design_to_json(design) + "\n"
