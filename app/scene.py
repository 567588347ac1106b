"""The 3D view of one tab: cam solid, follower body, guide, teaching overlays.

Scene units are metres; the cam axis is the scene Z axis and the paper's world X-Y
plane is the scene X-Y plane (Y up, along the follower's motion). ``build`` shows an
analysis, re-sending only the nodes whose geometry changed; ``pose`` only moves them
(cam frame rotation, follower frame translation) and updates the small overlay lines.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import trimesh

from camcore import profile, wear
from camcore.checks import violation_mask
from camcore.export import ExportError, cam_mesh, thin_evenly
from camcore.units import from_mm

CAM_RGB = (150, 165, 185)
FOLLOWER_RGB = (205, 110, 30)
IDLE_FACE_RGB = (230, 205, 180)  # a double follower's face that does not touch: dimmed
STEM_RGB = (235, 165, 80)
GUIDE_RGB = (120, 120, 130)
BAD_RGB = (220, 20, 30)
EDGE_RGB = (40, 50, 70)
HIGH_RGB = (30, 150, 60)
LOW_RGB = (40, 100, 220)
FORCE_RGB = (0, 150, 170)  # teal: the high-dwell arc is the green
Q_RGB = (200, 0, 200)
PHI_RGB = (0, 0, 0)
CONTACT_RGB = (255, 200, 0)  # not BAD_RGB: a red ball hid a broken stretch's red
PAD_T = 0.006  # concave pad thickness [m]
YOKE_T = 0.006

DISPLAY_POINTS = 1200  # profile vertices drawn on screen (exports use all of them)
OVERLAYS = ("contacts", "forces", "instant_centre", "pressure_angle", "arcs", "wear")
OFF_BY_DEFAULT = frozenset({"wear"})
# the wear band: pale lavender (none) to dark indigo (the most); not red, which marks
# a broken limit (a teacher's review read a healthy cam's wear as broken stretches)
WEAR_LOW_RGB = np.array([238, 228, 250])  # no wear ...
WEAR_HIGH_RGB = np.array([75, 0, 130])  # ... the profile's largest wear


def quat_z(angle: float) -> tuple[float, float, float, float]:
    return (math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2))


def _sector(cx, cy, r_in, r_out, a0, a1, z0, z1, n=48) -> trimesh.Trimesh:
    """A ring sector about (cx, cy), angles from +Y (clockwise positive), extruded in z."""
    a = np.linspace(a0, a1, n)
    inner = np.column_stack([cx + r_in * np.sin(a), cy + r_in * np.cos(a)])
    outer = np.column_stack([cx + r_out * np.sin(a), cy + r_out * np.cos(a)])
    ring = np.vstack([inner, outer[::-1]])  # closed polygon, 2n vertices
    m = ring.shape[0]
    verts = np.vstack(
        [np.column_stack([ring, np.full(m, z0)]), np.column_stack([ring, np.full(m, z1)])]
    )
    faces = []
    for i in range(n - 1):  # caps as quad strip between inner i and outer i
        o_i, o_j = m - 1 - i, m - 2 - i
        faces += [[i, o_i, i + 1], [i + 1, o_i, o_j]]
        faces += [[m + i, m + i + 1, m + o_i], [m + i + 1, m + o_j, m + o_i]]
    for i in range(m):  # side walls
        j = (i + 1) % m
        faces += [[i, j, m + j], [i, m + j, m + i]]
    # the winding is consistent by construction; outward iff the signed volume is > 0
    # (a1 < a0 turns it inside out): cheaper than trimesh's fix_normals on every redraw
    tri = verts[np.array(faces)]
    volume = np.einsum("ij,ij->", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])) / 6.0
    faces_arr = np.array(faces) if volume > 0 else np.array(faces)[:, ::-1]
    return trimesh.Trimesh(verts, faces_arr, process=False)


def _box(x0, x1, y0, y1, z0, z1) -> trimesh.Trimesh:
    b = trimesh.creation.box(extents=(x1 - x0, y1 - y0, z1 - z0))
    b.apply_translation(((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2))
    return b


def _prism(poly: np.ndarray, z0: float, z1: float) -> trimesh.Trimesh:
    """A convex polygon (n, 2), counter-clockwise, extruded from z0 to z1."""
    n = poly.shape[0]
    verts = np.vstack(
        [np.column_stack([poly, np.full(n, z0)]), np.column_stack([poly, np.full(n, z1)])]
    )
    i = np.arange(1, n - 1)
    caps = [
        np.column_stack([np.zeros_like(i), i + 1, i]),
        np.column_stack([np.full_like(i, n), n + i, n + i + 1]),
    ]
    j, k = np.arange(n), (np.arange(n) + 1) % n
    walls = [np.column_stack([j, k, n + k]), np.column_stack([j, n + k, n + j])]
    return trimesh.Trimesh(verts, np.vstack(caps + walls), process=True)


def _classic_body(a, f, z0: float, z1: float):
    """A flat-faced tappet (a plate as wide as the contact wanders, camcore's
    flat_face_width) or a knife edge (a wedge with its tip at the contact), at zero
    lift; returns (mesh, top y, x extent) [m]."""
    geo = a.geo
    rb = geo.r_b
    if geo.flat:
        half = max(0.6 * float(np.abs(a.prog.V + geo.stem_x).max()) * 2, 0.15 * rb)
        lo, hi = geo.stem_x - half, geo.stem_x + half
        top = geo.y0 + PAD_T
        return _box(lo, hi, geo.y0, top, z0, z1), top, lo, hi
    wide, tall = 0.12 * rb, 0.2 * rb
    tip = np.array([f.x_c, geo.y0])
    tri = np.array([tip, tip + (wide / 2, tall), tip + (-wide / 2, tall)])
    return _prism(tri, z0, z1), geo.y0 + tall, f.x_c - wide / 2, f.x_c + wide / 2


def follower_parts(a) -> dict[str, tuple[trimesh.Trimesh, tuple[int, int, int]]]:
    """Meshes of the follower (at zero lift, world frame) and the fixed guide [m]."""
    d, geo = a.design, a.geo
    w = from_mm(d.cam.width_mm)
    z0, z1 = -w / 2, w / 2
    parts: dict[str, tuple[trimesh.Trimesh, tuple[int, int, int]]] = {}
    tops, xs = [], []
    for i, f in enumerate(geo.faces):
        if geo.flat or f.r == 0:  # flat-faced tappet or knife edge (issue 10)
            mesh, top, x_lo, x_hi = _classic_body(a, f, z0, z1)
            parts[f"face{i}"] = (mesh, FOLLOWER_RGB)
            tops.append(top)
            xs += [x_lo, x_hi]
        elif f.r > 0:  # roller
            cyl = trimesh.creation.cylinder(radius=f.r, height=w * 0.9, sections=48)
            cyl.apply_translation((f.x_c, geo.y0, 0.0))
            parts[f"face{i}"] = (cyl, FOLLOWER_RGB)
            pin = trimesh.creation.cylinder(radius=f.r * 0.25, height=w * 1.3, sections=16)
            pin.apply_translation((f.x_c, geo.y0, 0.0))
            parts[f"pin{i}"] = (pin, GUIDE_RGB)
            top = geo.y0 + f.r + 0.002
            plate = _box(
                f.x_c - f.r * 0.3, f.x_c + f.r * 0.3, geo.y0, top + 1e-4, z0 - 0.004, z0 - 0.001
            )
            parts[f"plate{i}"] = (plate, STEM_RGB)
            tops.append(top)
            xs += [f.x_c - f.r, f.x_c + f.r]
        else:  # concave pad: the useful part of the arc, on its own side of the stem
            R = -f.r
            on = a.in_contact[i]
            px = a.point_world[i, on, 0] if on.any() else np.array([0.0])
            lo, hi = float(px.min()) - 0.004, float(px.max()) + 0.004
            if len(geo.faces) == 2:
                lo, hi = (lo, min(hi, -0.0005)) if i == 0 else (max(lo, 0.0005), hi)
            a0 = math.asin(max(-1.0, min(1.0, (lo - f.x_c) / R)))
            a1 = math.asin(max(-1.0, min(1.0, (hi - f.x_c) / R)))
            pad = _sector(f.x_c, geo.y0, R, R + PAD_T, a0, a1, z0, z1)
            parts[f"face{i}"] = (pad, FOLLOWER_RGB)
            ends = [f.x_c + (R + PAD_T) * math.sin(t) for t in (a0, a1)]
            tops.append(max(geo.y0 + (R + PAD_T) * math.cos(t) for t in (a0, a1)))
            xs += ends
    sw = from_mm(d.dynamics.guide_width_mm)
    y_yoke = max(tops)
    sx = geo.stem_x  # a single follower's axis (its offset)
    x_lo, x_hi = min(min(xs), sx - sw / 2), max(max(xs), sx + sw / 2)
    parts["yoke"] = (_box(x_lo, x_hi, y_yoke - 1e-4, y_yoke + YOKE_T, z0, z1), STEM_RGB)
    l1, l2 = from_mm(d.dynamics.overhang_mm), from_mm(d.dynamics.guide_length_mm)
    g0 = y_yoke + YOKE_T + l1
    stem_top = g0 + l2 + max(0.02, 1.2 * geo.h)
    parts["stem"] = (
        _box(
            sx - sw / 2,
            sx + sw / 2,
            y_yoke + YOKE_T - 1e-4,
            stem_top,
            -min(sw, w) / 2,
            min(sw, w) / 2,
        ),
        STEM_RGB,
    )
    gw = max(0.006, sw * 0.8)
    guide: Any = trimesh.util.concatenate(
        [
            _box(sx - sw / 2 - gw, sx - sw / 2 - 2e-4, g0, g0 + l2, z0, z1),
            _box(sx + sw / 2 + 2e-4, sx + sw / 2 + gw, g0, g0 + l2, z0, z1),
        ]
    )
    parts["guide"] = (guide, GUIDE_RGB)
    return parts


def _polyline_segments(p: np.ndarray, closed: bool = False) -> np.ndarray:
    q = np.vstack([p, p[:1]]) if closed else p
    return np.stack([q[:-1], q[1:]], axis=1)


def _flat(p2: np.ndarray, z: float) -> np.ndarray:
    return np.column_stack([p2, np.full(len(p2), z)])


def _circle(r: float, n: int = 180) -> np.ndarray:
    t = np.linspace(0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def vertex_colors(rgb) -> np.ndarray:
    """sRGB colours [0-255] as line segments' per-vertex colours must be sent: three.js
    takes vertex colours as linear and brightens them on screen (a review measured the
    dwell arcs drawn pastel and the base circle near-white beside the legend's
    swatches; a single colour for a whole node is converted by viser and is right).
    The sRGB decoding curve of IEC 61966-2-1: c / 12.92 up to 0.04045, else
    ((c + 0.055) / 1.055)^2.4."""
    c = np.asarray(rgb, dtype=float) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return np.rint(linear * 255.0).astype(np.uint8)


def legend_html() -> str:
    """What the 3D view's colours mean, as swatches (a teacher's review: nothing said
    what the green and blue arcs, the magenta lines or the pale pad were)."""
    items = (
        (CAM_RGB, "the cam"),
        (FOLLOWER_RGB, "follower face or roller touching the cam"),
        (IDLE_FACE_RGB, "a double follower's face not touching"),
        (BAD_RGB, "on the cam: where a limit is broken"),
        (CONTACT_RGB, "contact points"),
        (FORCE_RGB, "contact normals, the force arrows"),
        (Q_RGB, "instant centre I23 = Q and the normals through it"),
        (PHI_RGB, "pressure angle φ: the normal and the stroke"),
        (HIGH_RGB, "high-dwell arc (Eq. 20)"),
        (LOW_RGB, "low-dwell arc"),
        (GUIDE_RGB, "base circle (dashed), guide, roller pins"),
        (STEM_RGB, "stem, yoke and plates"),
        (EDGE_RGB, "the cam's outline, and its θ = 0 datum from the hub to the rim"),
    )

    def swatch(rgb) -> str:
        return (
            "<span style='display:inline-block;width:0.9em;height:0.9em;margin-right:0.4em;"
            f"vertical-align:-0.1em;border:1px solid #666;background:rgb{tuple(map(int, rgb))}'>"
            "</span>"
        )

    rows = "".join(f"<div>{swatch(c)}{text}</div>" for c, text in items)
    rows += (
        f"<div>{swatch(WEAR_LOW_RGB)}{swatch(WEAR_HIGH_RGB)}wear along the profile, "
        "none to the most</div>"
    )
    return (  # (indented and spaced as the controls around it)
        "<div style='font-size:0.85em;line-height:1.5;padding:0 0 10px 9px'>"
        f"<b>Colours</b>{rows}</div>"
    )


def _display_points(a) -> np.ndarray:
    """The profile thinned to about DISPLAY_POINTS vertices for drawing."""
    return a.profile.points[thin_evenly(a.profile.points, DISPLAY_POINTS)]


LABEL_SHARE = 0.025  # a label's height in a preset view: of the view's height
PHI_LEGS = 0.2  # the pressure-angle construction's legs at most: of the view's height
ARROW_SHARE = 0.33  # the longest force arrow at most: of the view's height
CONTACT_SHARE = 0.008  # a contact point's sphere's radius at most: of the view's height


def label_height(pos, look, fov: float) -> float:
    """The labels' height [m] for a camera at ``pos`` looking at ``look`` with the
    vertical field of view ``fov`` [rad]: LABEL_SHARE of the height it sees there
    (18 px of a 720 px projector, 27 of 1080, in every preset view; a share of the
    base radius had made them 8 px in the Front view and 54 px in the close-up)."""
    dist = float(np.linalg.norm(np.subtract(pos, look)))
    return LABEL_SHARE * 2 * dist * math.tan(fov / 2)


def _label_size(height: float) -> dict:
    """Labels sized in the scene, so they grow as a teacher zooms in."""
    return {"font_size_mode": "scene", "font_scene_height": height}


def geometry_key(design) -> str:
    """Everything the drawn geometry depends on (not speed, spring, mass, material)."""
    return design.model_dump_json(
        include={
            "motion": True,
            "follower": True,
            "limits": {"resolution_deg"},
            # (the keyway too: the 3D cam had kept its old keyway, or none: a review)
            "cam": {
                "base_radius_mm",
                "width_mm",
                "bore_diameter_mm",
                "keyway_width_mm",
                "keyway_depth_mm",
                "bore_flat_mm",
            },
            "dynamics": {"guide_width_mm", "guide_length_mm", "overhang_mm"},
        }
    )


class SceneView:
    """Scene nodes of one client. All methods are called with the session lock held."""

    def __init__(self, scene, overlays: dict[str, bool] | None = None):
        self.scene = scene
        self.a = None
        self.k = 0
        self.show = (
            {name: name not in OFF_BY_DEFAULT for name in OVERLAYS}
            if overlays is None
            else overlays
        )
        self.mesh_error: str | None = None
        self.cam_frame = scene.add_frame("/cam", show_axes=False)
        self.follower_frame = scene.add_frame("/follower", show_axes=False)
        self.nodes: dict[str, Any] = {}
        self.builds = 0  # geometry rebuilds
        self._face_rgb: dict[int, tuple] = {}
        self._geometry: str | None = None
        self._made: dict[str, Any] = {}  # node name -> what it was made from (see _put)
        self._wear_at = (0.0, 0.0)  # (z, thickness) of the wear band, drawn when shown
        self._wear_of: Any = None  # the analysis the band on screen was drawn for
        self.label_h = 0.005  # the labels' height [m] (set_label_height)

    def set_label_height(self, height: float) -> None:
        """Size every label ``height`` [m] high (label_height of the preset view), and
        the contact points and force arrows to the view with them."""
        self.label_h = height
        for name in ("label0", "label1", "q_label", "phi_label"):
            if name in self.nodes:
                self.nodes[name].font_scene_height = height
        if self.a is not None:
            self._size_contacts(self.a)
            self.pose(self.k)  # the phi label stands a label's height below the contact

    def _view_height(self) -> float:
        """What the preset view shows, top to bottom [m] (the labels are a share of it)."""
        return self.label_h / LABEL_SHARE

    def _arrow_max(self) -> float:
        """The longest force arrow [m]: half the base radius, or a third of the view (a
        teacher's review: in the close-up a 137 N arrow ran off the top of the frame)."""
        assert self.a is not None
        return min(0.5 * self.a.geo.r_b, ARROW_SHARE * self._view_height())

    def _size_contacts(self, a) -> None:
        """The contact points' spheres: 3 % of r_b, at most CONTACT_SHARE of the view (a
        teacher's review: 60 px across in the close-up, they hid the contact)."""
        r = min(0.03 * a.geo.r_b + 0.5e-3, CONTACT_SHARE * self._view_height())
        for i in range(len(a.geo.faces)):
            key = f"contact{i}"
            if key in self.nodes and self._made.get(key) != r:
                self._made[key] = r
                self.nodes[key] = self.scene.add_icosphere(
                    f"/ov/{key}", radius=r, color=CONTACT_RGB, position=(0, 0, self.zt)
                )

    # --- build once per analysis ---------------------------------------------------
    def build(self, a) -> None:
        """Show a new analysis. The geometry (cam, follower, arcs, overlay markers) is
        rebuilt only when it changed: a new speed, spring or material moves no node."""
        self.a = a
        w = from_mm(a.design.cam.width_mm)
        zt = w / 2 + 2e-4
        thick = max(2e-4, 0.004 * a.geo.r_b)
        key = geometry_key(a.design)
        if key != self._geometry:
            self._geometry = key
            self.builds += 1
            self._build_geometry(a, w, zt, thick)
        self.fn_max = max(1e-9, float(np.max(np.abs(a.guide.FN))))  # the arrows' scale
        self._size_contacts(a)  # (to the view: set_label_height)
        self._build_bad(a, zt + 1e-4, thick * 2.5)
        self._wear_at = (zt + 3e-4, thick * 6.0)
        self._build_wear(a)
        self.pose(self.k if self.k < a.theta.size else 0)

    def _put(self, name: str, made_from: Any, make) -> bool:
        """Add node ``name`` with ``make()`` unless the one on screen was made from the
        same ``made_from`` (compared with ==): a new lift re-sends the cam, not the
        follower's unchanged parts, the hub or the overlay markers. True if (re)made."""
        if name in self.nodes and self._made.get(name) == made_from:
            return False
        self.nodes[name] = make()
        self._made[name] = made_from
        return True

    def _build_geometry(self, a, w, zt, thick) -> None:
        s = self.scene
        try:
            m = cam_mesh(a, max_points=DISPLAY_POINTS)
            verts = from_mm(np.asarray(m.vertices)) - np.array([0.0, 0.0, w / 2])
            self.nodes["cam"] = s.add_mesh_simple(
                "/cam/solid",
                verts.astype(np.float32),
                np.asarray(m.faces, dtype=np.uint32),
                color=CAM_RGB,
                flat_shading=True,
            )
            self.mesh_error = None
        except ExportError as exc:  # an undercut profile: draw its outline only
            self.mesh_error = str(exc)
            if "cam" in self.nodes:
                self.nodes.pop("cam").remove()
        pts = _display_points(a)
        self.nodes["outline"] = s.add_line_segments(
            "/cam/outline",
            _polyline_segments(_flat(pts, zt), closed=True),
            EDGE_RGB,
            thickness=thick * 0.6,
        )
        self._put(
            "hub",
            (a.geo.r_b, zt, thick),
            lambda: s.add_line_segments(
                "/cam/hub",
                _polyline_segments(_flat(_circle(0.1 * a.geo.r_b, 48), zt), True),
                EDGE_RGB,
                thickness=thick * 0.6,
            ),
        )
        self._build_arcs(a, zt + 2e-4, thick * 1.5)
        r0 = profile.datum_radius(a.profile.points)
        cam = a.design.cam  # from the hub, or beyond the bore and its keyway (on this ray)
        r1 = max(0.1 * a.geo.r_b, from_mm(cam.bore_diameter_mm / 2 + cam.keyway_depth_mm))
        self._put(  # the cam's theta = 0 ray, turning with it (a teacher's review: the
            # stations diagram's datum had nothing to match on the 3D cam)
            "datum",
            (r0, r1, zt, thick),
            lambda: s.add_line_segments(
                "/cam/datum",
                np.array([[[0.0, r1, zt], [0.0, r0, zt]]], dtype=np.float32),
                EDGE_RGB,
                thickness=thick * 2.0,  # (thicker than the black pressure-angle lines)
            ),
        )
        parts = follower_parts(a)
        self._face_meshes = [parts[f"face{i}"][0] for i in range(len(a.geo.faces))]
        for name, (mesh, rgb) in parts.items():
            parent = "" if name == "guide" else "/follower"
            verts, faces = np.asarray(mesh.vertices, np.float32), np.asarray(mesh.faces, np.uint32)
            made = self._put(
                name,
                # the number of faces too: a single roller where a double's face was
                # must not keep that face's dimmed colour (_highlight_faces is for two)
                (verts.tobytes(), faces.tobytes(), rgb, len(a.geo.faces)),
                lambda name=name, verts=verts, faces=faces, rgb=rgb, parent=parent: (
                    s.add_mesh_simple(
                        f"{parent}/{name}",
                        verts,
                        faces,
                        color=rgb,
                        flat_shading=False,
                        opacity=0.55 if name == "guide" else None,
                    )
                ),
            )
            if made and name.startswith("face"):  # a new node: its colour is set on the next pose
                self._face_rgb.pop(int(name[4:]), None)
        for name in [n for n in self.nodes if n.startswith(("face", "pin", "plate"))]:
            if name not in parts:  # e.g. the roller pins after a switch to concave faces
                self.nodes.pop(name).remove()
        self._build_face_labels(a)
        self._build_overlays(a, zt)

    def _build_bad(self, a, z, thick) -> None:
        """Red profile segments over the cam angles where a limit is violated."""
        mask = violation_mask(a.violations, np.degrees(a.profile.theta))
        segs = _polyline_segments(_flat(a.profile.points, z), closed=True)
        bad = segs[mask & np.roll(mask, -1)]
        if bad.shape[0] == 0:
            if "bad" in self.nodes:
                self.nodes.pop("bad").remove()
            return
        self.nodes["bad"] = self.scene.add_line_segments("/cam/bad", bad, BAD_RGB, thickness=thick)

    def _build_wear(self, a) -> None:
        """The cam's Archard wear along its profile as a heat band on the top face (pale:
        none, dark indigo: the profile's largest), from camcore.wear.along_profile. Drawn
        only while shown (off by default): it is a profile-long computation and ~40 kB
        per redraw that a hidden band would waste; set_overlay draws it when asked."""
        if not self.show["wear"]:
            if "wear" in self.nodes:
                self.nodes.pop("wear").remove()
            return
        if self._wear_of is a and "wear" in self.nodes:  # already drawn for this analysis
            return
        self._wear_of = a
        z, thick = self._wear_at
        pts = _display_points(a)
        phi, depth = wear.along_profile(a)
        polar = np.mod(np.arctan2(pts[:, 1], pts[:, 0]), 2 * np.pi)
        top = float(depth.max())
        level = np.interp(polar, phi, depth, period=2 * np.pi) / top if top > 0 else 0 * polar
        rgb = WEAR_LOW_RGB + np.clip(level, 0, 1)[:, None] * (WEAR_HIGH_RGB - WEAR_LOW_RGB)
        colors = vertex_colors(np.stack([rgb, np.roll(rgb, -1, axis=0)], axis=1))
        self.nodes["wear"] = self.scene.add_line_segments(
            "/cam/wear",
            _polyline_segments(_flat(pts, z), closed=True),
            colors,
            thickness=thick,
        )

    def _build_arcs(self, a, z, thick) -> None:
        """Base circle (thin, dashed) and the dwell arcs of the profile (coloured)."""
        from camcore.motion import HIGH, LOW

        base = _polyline_segments(_flat(_circle(a.geo.r_b, 240), z), True)[::2]
        segs = _polyline_segments(_flat(a.profile.points, z), closed=True)
        part = a.profile.part
        same = part == np.roll(part, -1)
        high, low = segs[same & (part == HIGH)], segs[same & (part == LOW)]
        cols = [
            np.broadcast_to(vertex_colors(c), (len(x), 2, 3))
            for c, x in ((GUIDE_RGB, base), (HIGH_RGB, high), (LOW_RGB, low))
        ]
        self.nodes["arcs"] = self.scene.add_line_segments(
            "/cam/arcs",
            np.concatenate([base, high, low]),
            np.concatenate(cols),
            thickness=thick,
            visible=self.show["arcs"],
        )

    def _build_face_labels(self, a) -> None:
        for i in range(2):
            key = f"label{i}"
            if i >= len(a.geo.faces):
                if key in self.nodes:
                    self.nodes.pop(key).remove()
                continue
            f = a.geo.faces[i]
            mesh = self._face_meshes[i]
            lo, hi = mesh.bounds[:, 0]
            y = float(mesh.bounds[1, 1])
            name = f.name.split(" ")[0] if len(a.geo.faces) == 2 else f.name
            left = i == 0 and len(a.geo.faces) == 2
            pos, size = (float(lo if left else hi), y, 0.0), _label_size(self.label_h)
            self._put(
                key,
                (name, pos, tuple(size.items()), left),
                lambda key=key, name=name, pos=pos, size=size, left=left: self.scene.add_label(
                    f"/follower/{key}",
                    name,
                    position=pos,
                    **size,
                    anchor="bottom-right" if left else "bottom-left",
                ),
            )

    def _build_overlays(self, a, zt) -> None:
        """The markers pose() moves (contact points, forces, I23, the pressure angle):
        made again only when their size, height or number of faces changes."""
        s = self.scene
        r = 0.03 * a.geo.r_b + 0.5e-3
        self.zt = zt + r
        self.thin = max(3e-4, 0.006 * a.geo.r_b)
        made_from = (r, zt, len(a.geo.faces))
        if self._made.get("overlays") == made_from and "phi_label" in self.nodes:
            return
        self._made["overlays"] = made_from
        for i in range(2):
            key = f"contact{i}"
            if i < len(a.geo.faces):
                self.nodes[key] = s.add_icosphere(
                    f"/ov/{key}", radius=r, color=CONTACT_RGB, position=(0, 0, zt + r)
                )
                self._made[key] = r
            elif key in self.nodes:
                self.nodes.pop(key).remove()
        one = np.zeros((1, 2, 3))
        self.nodes["forces"] = s.add_line_segments(
            "/ov/forces", one, FORCE_RGB, thickness=self.thin * 1.4
        )
        self.nodes["q"] = s.add_icosphere("/ov/q", radius=r * 1.2, color=Q_RGB)
        self.nodes["q_label"] = s.add_label(
            "/ov/q/label",
            "I23 = Q",
            position=(0, -2 * r, 0),
            **_label_size(self.label_h),
            anchor="top-center",
        )
        self.nodes["q_lines"] = s.add_line_segments(
            "/ov/q_lines", one, Q_RGB, thickness=self.thin * 0.5
        )
        self.nodes["phi"] = s.add_line_segments("/ov/phi", one, PHI_RGB, thickness=self.thin * 0.6)
        self.nodes["phi_label"] = s.add_label(
            "/ov/phi_label", "φ", **_label_size(self.label_h), anchor="center-center"
        )

    # --- per frame -----------------------------------------------------------------
    def pose(self, k: int) -> None:
        """Move everything to grid index k: transforms and small overlay lines only."""
        a = self.a
        if a is None:
            return
        self.k = k
        th = float(a.theta[k])
        S = float(a.prog.S[k])
        self.cam_frame.wxyz = quat_z(-th)  # clockwise cam
        self.follower_frame.position = (0.0, S, 0.0)
        on = a.in_contact[:, k]
        self._highlight_faces(on)
        z = self.zt
        pw = a.point_world[:, k, :]
        for i in range(len(a.geo.faces)):
            node = self.nodes[f"contact{i}"]
            node.position = (float(pw[i, 0]), float(pw[i, 1]), z)
            node.visible = bool(on[i]) and self.show["contacts"]
        # force arrows: along the normal (cam -> follower), length ~ F_N
        segs = []
        for i in np.flatnonzero(on):
            p, n = pw[i], a.normal[i, k]
            L = float(a.FN[i, k]) * self._arrow_max() / self.fn_max
            if L <= 0:
                continue
            tip = p + n * L
            head = 0.25 * min(L, 0.3 * a.geo.r_b)
            side = np.array([-n[1], n[0]])
            for sgn in (1, -1):
                segs.append((tip, tip - n * head + sgn * side * head * 0.5))
            segs.append((p, tip))
        fz = self.nodes["forces"]
        if segs:
            arr = np.array([[[*u, z], [*v, z]] for u, v in segs], np.float32)
            fz.points = arr
        fz.visible = bool(segs) and self.show["forces"]
        # instant centre Q = I23 on the X axis, with the common normals through it
        q = tuple(float(x) for x in profile.instant_centre(a.prog.V[k : k + 1])[0])
        self.nodes["q"].position = (q[0], q[1], z)
        self.nodes["q"].visible = self.show["instant_centre"]
        lines = []
        centres = profile.face_centres(a.geo, a.prog.S[k : k + 1])[:, 0]
        for i in np.flatnonzero(on):
            f, c = a.geo.faces[i], centres[i]
            lines.append(((q[0], q[1], z), (float(pw[i, 0]), float(pw[i, 1]), z)))
            if 0 < f.r < math.inf:
                lines.append(((q[0], q[1], z), (float(c[0]), float(c[1]), z)))
        self.nodes["q_lines"].points = np.array(lines, np.float32)
        self.nodes["q_lines"].visible = self.show["instant_centre"]
        # pressure angle at the driving face: normal vs. the follower's path (Y)
        i = 0 if on[0] else len(a.geo.faces) - 1
        p, n = pw[i], a.normal[i, k]
        # its legs a share of what the view shows (the labels' height says that): at
        # 0.45 r_b the close-up had its arc off screen and the label 15 mm from the
        # contact, out on the cam
        L = min(0.45 * a.geo.r_b, PHI_LEGS * self.label_h / LABEL_SHARE)
        phi = float(a.pressure_angle[i, k])
        # drawn below the contact, on the cam: the stroke's line and the normal's (the
        # line of action, on through Q) run on through the contact, and the angle between
        # them is the same there (a teacher's review: drawn upward, into the follower, its
        # arc hid under the force arrow and its label stood apart from it)
        pts = [
            ((p[0], p[1], z), (p[0], p[1] - L, z)),
            ((p[0], p[1], z), (p[0] - n[0] * L, p[1] - n[1] * L, z)),
        ]
        t = np.linspace(0, 1, 12)
        ang0 = math.atan2(-n[1], -n[0])
        arc = np.array(
            [
                (
                    p[0] + 0.6 * L * math.cos(ang0 + (-math.pi / 2 - ang0) * u),
                    p[1] + 0.6 * L * math.sin(ang0 + (-math.pi / 2 - ang0) * u),
                    z,
                )
                for u in t
            ]
        )
        pts += [(tuple(arc[j]), tuple(arc[j + 1])) for j in range(len(arc) - 1)]
        self.nodes["phi"].points = np.array(pts, np.float32)
        # no construction where nothing touches (a broken dwell): it would show a lie
        touching = bool(on.any())
        self.nodes["phi"].visible = self.show["pressure_angle"] and touching
        lab = self.nodes["phi_label"]
        # beside the arc, on the stroke's side away from the normal: clear of both legs
        # and of the follower (pad, roller, plate and yoke all lie above the contact)
        side = 1.0 if n[0] >= 0 else -1.0  # (the normal's leg runs to -n[0] below)
        half = 0.55 * self.label_h * len("φ = 00.0°") / 2  # a label's half width
        lab.position = (p[0] + side * (half + 0.3 * self.label_h), p[1] - 0.6 * L, z)
        # its size, as the paper gives it (Eqs. 5, 13: "phi remains positive" in the
        # fall; a teacher's review: students read "-7.3°" against the paper); the curve
        # keeps the sign, which says the side the normal leans to
        lab.text = f"φ = {abs(math.degrees(phi)):.1f}°"
        lab.visible = self.show["pressure_angle"] and touching

    def _highlight_faces(self, on: np.ndarray) -> None:
        """The touching face of a double follower in full colour, the idle one dimmed
        (sent only when it changes, not every frame)."""
        if on.size != 2:
            return
        for i in range(2):
            rgb = FOLLOWER_RGB if on[i] else IDLE_FACE_RGB
            node = self.nodes.get(f"face{i}")
            if node is not None and self._face_rgb.get(i) != rgb:
                node.color = rgb
                self._face_rgb[i] = rgb

    def set_overlay(self, name: str, on: bool) -> None:
        self.show[name] = on
        if name == "wear":
            if self.a is not None:
                self._build_wear(self.a)
        elif name == "arcs" and name in self.nodes:
            self.nodes[name].visible = on
        elif self.a is not None:
            self.pose(self.k)


CAMERA_VIEWS = ("Front", "Contact close-up", "3D")
FRONT_FOV = math.radians(8.0)  # a long lens: nearly orthographic, the cam looks round


DEFAULT_FRAME = (16 / 9, 0.0)  # (aspect, panel share) before the browser says


def camera_for(
    view: str,
    a,
    k: int,
    frame: tuple[float, float] = DEFAULT_FRAME,
    extent: tuple[float, float] | None = None,
) -> tuple[tuple, tuple, float]:
    """(position, look_at, fov [rad]) of a preset view of analysis ``a`` at grid index k.

    Front: straight along -z with a long lens, the whole mechanism in frame. Contact
    close-up: the same lens on the contact region, following the follower's lift (call
    again as the cam turns). 3D: the perspective view from above and to the side.

    ``frame`` = (aspect, panel share): the 3D view's width over its height, and the
    share of its width the control panel covers at its right edge. Front and close-up
    put the mechanism in the middle of the part left visible (centred on the whole
    view, the close-up had the right face S2 under the panel at 1280 x 720).
    ``extent``: closeup_extent(a), if the caller keeps it."""
    aspect, share = frame
    if view == "Contact close-up":  # (called every frame while playing: cheap)
        y = a.geo.r_b + float(a.prog.S[k])  # the contacts sit near the top of the cam
        x0, x1 = closeup_extent(a) if extent is None else extent
        # 0.8 r_b high (the flanks in frame), and wide enough that the follower and
        # every contact of the cycle fit the part of the view the panel leaves
        span = max(0.8 * a.geo.r_b, 1.25 * (x1 - x0) / (aspect * (1.0 - share)))
        dist = span / (2 * math.tan(FRONT_FOV / 2))
        x = 0.5 * (x0 + x1) + _beside_panel(dist, aspect, share)
        return (x, y, dist), (x, y, 0.0), FRONT_FOV
    # in frame: the follower's highest part at full lift (the stem's end) and the cam's
    # widest radius below its axis (any point of the cam passes there as it turns)
    top = max(float(m.bounds[1, 1]) for m, _ in follower_parts(a).values()) + a.geo.h
    bottom = -float(np.hypot(*a.profile.points.T).max())
    H = top - bottom
    cy = (top + bottom) / 2
    if view == "3D":
        look = np.array([0.18 * H, cy, 0.0])
        pos = look + np.array([0.18 * H, 0.12 * H, 0.95 * H])
        return tuple(pos), tuple(look), math.radians(50.0)
    dist = 1.15 * H / (2 * math.tan(FRONT_FOV / 2))
    x = _beside_panel(dist, aspect, share)
    return (x, cy, dist), (x, cy, 0.0), FRONT_FOV


def closeup_extent(a) -> tuple[float, float]:
    """The x range [m] the close-up keeps in view: the follower's faces (or roller,
    plate, point) and every contact point of the cycle (an offset follower's sit off
    the cam's axis). ~1 ms: a caller that follows the animation keeps it per analysis."""
    xs = [m.bounds[:, 0] for name, (m, _) in follower_parts(a).items() if name != "guide"]
    touching = a.point_world[..., 0][a.in_contact]
    lo = min(min(float(x[0]) for x in xs), float(touching.min(initial=np.inf)))
    hi = max(max(float(x[1]) for x in xs), float(touching.max(initial=-np.inf)))
    return lo, hi


def _beside_panel(dist: float, aspect: float, share: float) -> float:
    """How far right [m] to move a front camera ``dist`` from the cam's plane so that
    x = 0 shows in the middle of the view's uncovered part: the panel's half share of
    the visible width (2 dist tan(fov/2) aspect)."""
    return share * dist * math.tan(FRONT_FOV / 2) * aspect
