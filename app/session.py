"""One browser tab: its design, analysis, GUI, 3D view, curves and animation.

Data flows one way: controls -> Design -> camcore.analysis.analyze -> views. All
state of a tab lives here and is guarded by one re-entrant lock (viser runs plain
callbacks in a thread pool; programmatic value changes call callbacks inline).
"""

from __future__ import annotations

import json
import math
import re
import threading
import time
from dataclasses import dataclass

import numpy as np

from camcore import export
from camcore.analysis import analyze
from camcore.model import (
    MAX_SEGMENTS,
    Design,
    DesignError,
    MotionLaw,
    design_from_json,
    design_to_json,
    load_preset,
    preset_names,
)
from camcore.motion import SEGMENT_NAMES
from camcore.report import summary
from camcore.units import to_mm

from . import compare, plots, state, storage, uploads
from .scene import CAMERA_VIEWS, OFF_BY_DEFAULT, OVERLAYS, SceneView, camera_for

DEFAULT_PRESET = "paper_example"
FPS = 30.0
OVERLAY_LABELS = {
    "contacts": "Contact points",
    "forces": "Contact normals as force arrows (∝ F_N)",
    "instant_centre": "Instant centre I23 = Q and normals",
    "pressure_angle": "Pressure angle φ",
    "arcs": "Base circle and dwell arcs",
    "wear": "Wear along the profile (Archard; pale none → dark red most)",
}


# Background work (the verified analysis and the comparison: ~0.1 s each) waits until a
# tab has been still this long, and runs for one tab at a time across the server.
SETTLE_S = 0.6
BACKGROUND = threading.BoundedSemaphore(1)


def slug(name: str) -> str:
    s = re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_").lower()
    return (s or "cam")[:40].rstrip("_")


def file_stem(design: Design) -> str:
    """A download's name: the design, its follower, and a short fingerprint of the
    whole design, so two files of different (edited) designs never share a name and a
    file says which design it holds."""
    import hashlib

    digest = hashlib.sha256(design_to_json(design).encode()).hexdigest()[:6]
    return f"{slug(design.name)}-{design.follower.kind.value}-{digest}"


@dataclass(frozen=True)
class MotionSegmentView:
    """One row of the segment table, from a MotionSegment or a dict of the table."""

    kind: str
    angle_deg: float
    lift_mm: float | None
    law: str | None

    @classmethod
    def of(cls, g) -> MotionSegmentView:
        if isinstance(g, dict):
            kind = str(g.get("kind"))
            law = g.get("law")
            return cls(kind if kind in ("rise", "fall", "dwell") else "dwell",
                       float(g.get("angle_deg", 0.0)), g.get("lift_mm"),
                       law if law in MotionLaw.__members__ else None)
        return cls(g.kind.value, float(g.angle_deg), g.lift_mm,
                   g.law.value if g.law else None)


class Session:
    """Everything one client sees. ``client`` is a viser ClientHandle."""

    def __init__(self, client, design: Design | None = None, animate: bool = True):
        self.client = client
        self.lock = threading.RLock()
        self._syncing = False
        self.closed = threading.Event()
        self.base = design or load_preset(DEFAULT_PRESET)
        self.design = self.base
        self.analysis = None
        self.station_events: list[str] = []  # what happens at each station, in words
        self.camera_view = "Front"  # a preset of scene.CAMERA_VIEWS
        self.error: str | None = None
        self.verified = False
        self.gen = 0
        self.theta_deg = 0.0
        self.playing = False
        self.speed = 45.0
        self.last_download: tuple[str, bytes] | None = None
        self.timings: list[float] = []  # seconds per re-analysis + redraw
        self.frames_played = 0  # animation frames drawn by the loop
        self._ticket_lock = threading.Lock()
        self._ticket = 0  # newest design-control change (see on_control)
        self._wake_anim = threading.Event()
        self._wake_settle = threading.Event()
        self.store = storage.BrowserStore(client)
        self.saved: dict[str, str] = {}
        self._persist = False  # on once the browser's stored design has been read
        with self.lock:
            self._build_gui()
            self.view = SceneView(client.scene)
            client.scene.set_up_direction("+y")
            self._apply(self.base, reset_camera=True)
        self.threads = []
        restore = threading.Thread(target=self._restore, daemon=True,
                                   name=f"cam-restore-{id(self)}")
        restore.start()
        self.threads.append(restore)
        if animate:
            for target in (self._animate, self._settle):
                t = threading.Thread(target=target, daemon=True,
                                     name=f"cam-{target.__name__}-{id(self)}")
                t.start()
                self.threads.append(t)

    # --- GUI ------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.client.gui
        self.status = gui.add_html("")
        # the part, one click away for the maker (the other formats are in Files)
        self.quick_stl_btn = gui.add_button("⬇ Download the cam (STL, mm)")
        self.quick_stl_btn.on_click(lambda _: self.download("stl"))
        with gui.add_folder("Animation", expand_by_default=True):
            self.play_btn = gui.add_button("▶ Play", color="green")
            self.speed_slider = gui.add_slider("Speed [°/s]", 5, 360, 5, self.speed)
            self.angle_slider = gui.add_slider("Cam angle θ [°]", 0.0, 360.0, 0.1, 0.0)
            self.stations_btn = gui.add_button_group("Go to station", ["0", "1", "2", "3",
                                                                       "4", "5"])
            self.where_md = gui.add_markdown("")
        self.play_btn.on_click(lambda _: self.toggle_play())
        self.speed_slider.on_update(lambda e: self._set_speed(e.target.value))
        self.angle_slider.on_update(lambda e: self._on_angle(e.target.value))
        self.stations_btn.on_click(lambda e: self.goto_station(e.target.value))

        tabs = gui.add_tab_group()
        self.controls: dict[str, object] = {}
        with tabs.add_tab("Design"):
            for title, expand, specs in state.FOLDERS:
                with gui.add_folder(title, expand_by_default=expand):
                    for spec in specs:
                        self.controls[spec.path] = self._add_control(gui, spec)
                    if title == "Motion program":
                        self.low_dwell_md = gui.add_markdown("")
                        self.seg_folder = gui.add_folder("Program segments (any program)",
                                                         expand_by_default=False)
                        self.seg_rows: list[dict] = []
                        self.seg_extra: list = []
            with gui.add_folder("Key numbers", expand_by_default=True):
                self.summary_md = gui.add_markdown("")
        with tabs.add_tab("Curves"):
            self.curves = plots.build_curves(gui, analyze(self.base, verify=False))
        with tabs.add_tab("Compare"):
            self.compare_view = compare.CompareView(gui)
        with tabs.add_tab("View") as self.view_folder:
            self.overlay_boxes = {}
            for name in OVERLAYS:
                cb = gui.add_checkbox(OVERLAY_LABELS[name], name not in OFF_BY_DEFAULT)
                cb.on_update(lambda e, n=name: self._set_overlay(n, e.target.value))
                self.overlay_boxes[name] = cb
            self.view_btns = gui.add_button_group("Camera", CAMERA_VIEWS)
            self.view_btns.on_click(lambda e: self.set_camera_view(e.target.value))
            self.camera_btn = gui.add_button("Reset camera")
            self.camera_btn.on_click(lambda _: self.reset_camera())
            self.stations_fig_btn = gui.add_button("Stations diagram (the paper's Fig. 4)")
            self.stations_fig_btn.on_click(lambda _: self.show_stations_diagram())
            self.stations_img = None
        with tabs.add_tab("Files"):
            names = preset_names()
            self.preset_dd = gui.add_dropdown(
                "Preset", names, initial_value=DEFAULT_PRESET if DEFAULT_PRESET in names
                else names[0])
            self.preset_btn = gui.add_button("Load preset")
            self.preset_btn.on_click(lambda _: self.load_preset(self.preset_dd.value))
            self.upload_btn = gui.add_upload_button("Open design JSON…",
                                                    mime_type="application/json")
            self.upload_btn.on_upload(lambda e: self.upload(e.target.value.name,
                                                            e.target.value.content))
            gui.add_markdown("**Kept in this browser** (only you see them)")
            self.save_name = gui.add_text("Name", "my cam")
            self.save_btn = gui.add_button("Save in this browser")
            self.save_btn.on_click(lambda _: self.save_named(self.save_name.value))
            self.saved_dd = gui.add_dropdown("Saved designs", ("–",), initial_value="–")
            self.open_saved_btn = gui.add_button("Open saved")
            self.open_saved_btn.on_click(lambda _: self.open_saved(self.saved_dd.value))
            self.delete_saved_btn = gui.add_button("Delete saved")
            self.delete_saved_btn.on_click(lambda _: self.delete_saved(self.saved_dd.value))
            gui.add_markdown("**Download**")
            self.download_btns = {}
            for kind, label in (("json", "Design JSON"), ("stl", "Cam STL (mm)"),
                                ("dxf", "Profile DXF (mm)"), ("csv", "Profile CSV"),
                                ("series", "Per-angle CSV"),
                                ("toolpath", "G-code (cutter path)"),
                                ("html", "Printable report"), ("pdf", "Report PDF")):
                b = gui.add_button(label)
                b.on_click(lambda _, k=kind: self.download(k))
                self.download_btns[kind] = b
            self.files_md = gui.add_markdown("")

    # --- the browser's storage ---------------------------------------------------------
    def _restore(self) -> None:
        """Read this browser's working design and saved list (a reload, or a server
        restart, brings the user back to them). Until the read returns nothing is
        written, so the default design never overwrites what the browser kept."""
        gen0 = self.gen
        working = storage.parse_working(self.store.read(storage.WORKING_KEY))
        saved = storage.parse_saved(self.store.read(storage.SAVED_KEY))
        if self.closed.is_set():
            return
        with self.lock:
            self.saved = saved
            self._show_saved()
            restore = working is not None and self.gen == gen0 and working != self.design
            self._persist = True
        if restore:
            self.set_design(working)
            with self.lock:
                self.files_md.content = (f"Restored your last design from this browser: "
                                         f"*{state.esc(working.name)}*.")
        else:
            with self.lock:
                self._save_working()

    def _save_working(self) -> None:
        if self._persist and self.error is None:
            self.store.write(storage.WORKING_KEY, design_to_json(self.design))

    def _show_saved(self) -> None:
        names = tuple(self.saved) or ("–",)
        self.saved_dd.options = names
        if self.saved_dd.value not in names:
            self.saved_dd.value = names[0]

    def save_named(self, name: str) -> None:
        with self.lock:
            try:
                self.saved = storage.with_saved(self.saved, str(name), self.design)
            except ValueError as exc:
                self.files_md.content = f"✖ Not saved: {state.esc(exc)}."
                return
            self.store.write(storage.SAVED_KEY, json.dumps(self.saved))
            self._show_saved()
            self.saved_dd.value = str(name).strip()
            self.files_md.content = f"Saved **{state.esc(str(name).strip())}** in this browser."

    def open_saved(self, name: str) -> None:
        text = self.saved.get(name) if isinstance(name, str) else None
        design = storage.parse_working(text)
        if design is None:
            with self.lock:
                self.files_md.content = "✖ Choose a saved design first."
            return
        self.set_design(design)
        with self.lock:
            self.files_md.content = f"Opened **{state.esc(name)}** from this browser."

    def delete_saved(self, name: str) -> None:
        with self.lock:
            if not isinstance(name, str) or name not in self.saved:
                self.files_md.content = "✖ Choose a saved design first."
                return
            self.saved = {k: v for k, v in self.saved.items() if k != name}
            self.store.write(storage.SAVED_KEY, json.dumps(self.saved))
            self._show_saved()
            self.files_md.content = f"Deleted **{state.esc(name)}** from this browser."

    def _add_control(self, gui, spec: state.Spec):
        v = state.get_path(self.base, spec.path)
        if v is None:  # e.g. a classic slider on another program: the default's value
            v = state.get_path(Design(), spec.path)
        if spec.widget == "slider":
            lo, hi = min(spec.lo, v), max(spec.hi, v)
            h = gui.add_slider(spec.label, lo, hi, spec.step, float(v), hint=spec.hint)
        elif spec.widget == "number":
            h = gui.add_number(spec.label, float(v), step=spec.step, hint=spec.hint)
        elif spec.widget == "dropdown":
            h = gui.add_dropdown(spec.label, spec.options, initial_value=v, hint=spec.hint)
        else:
            h = gui.add_checkbox(spec.label, bool(v), hint=spec.hint)
        h.on_update(lambda _e: self.on_control())
        return h

    def values(self) -> dict[str, object]:
        return {p: h.value for p, h in self.controls.items()}

    def _sync_controls(self, design: Design) -> None:
        self._syncing = True
        try:
            classic = design.motion.classic is not None
            for spec in state.SPECS:
                h = self.controls[spec.path]
                v = state.get_path(design, spec.path)
                if spec.path.startswith("motion."):
                    h.disabled = not classic  # other programs: edited as segments
                if v is None:
                    continue
                if spec.widget == "slider":
                    h.min, h.max = min(h.min, v), max(h.max, v)
                h.value = v
        finally:
            self._syncing = False

    def _enable_for_kind(self, design: Design) -> None:
        k = design.follower.kind
        self.controls["follower.face_radius_mm"].disabled = not k.is_concave
        self.controls["follower.roller_radius_mm"].disabled = not k.is_roller
        self.controls["follower.offset_mm"].disabled = not k.is_double
        self.controls["follower.single_offset_mm"].disabled = k.is_double

    # --- design changes -------------------------------------------------------------
    def on_control(self) -> None:
        """Any design control changed: rebuild the design from all controls.

        Changes coalesce: each callback takes a ticket, and only the newest ticket
        redraws (it reads every control's latest value), so a burst of slider events
        queued on the lock costs one analysis, not one per event.
        """
        with self._ticket_lock:
            self._ticket += 1
            mine = self._ticket
        with self.lock:
            if self._syncing or self.closed.is_set() or mine != self._ticket:
                return
            vals = self.values()
            design, err = state.try_design(self.base, vals)
            if err is not None:
                self.error = err
                self.low_dwell_md.content = state.low_dwell_text(vals)  # e.g. "negative"
                self._show_status()
                return
            self.error = None
            self._apply(design)

    def _apply(self, design: Design, reset_camera: bool = False) -> None:
        """Analyse (fast path, no verification) and redraw everything. Lock held."""
        t0 = time.perf_counter()
        a = analyze(design, verify=False)
        self.design, self.analysis = design, a
        self.gen += 1
        self.verified = False
        k = self._index(self.theta_deg)
        with self.client.atomic():
            self.view.build(a)
            self.view.pose(k)
            for c in self.curves:
                c.update(a, k)
            plots.relabel_limits(self.curves, a)
            self._enable_for_kind(design)
            self._sync_segment_rows(design)
            self._show_station_buttons(a)
            self.low_dwell_md.content = state.low_dwell_text(self.values(), design)
            self._show_summary(summary(a))
            self._show_where(k)
            self._show_status()
        self._save_working()
        if reset_camera:
            self.reset_camera()
        self.timings.append(time.perf_counter() - t0)
        del self.timings[:-200]
        self._wake_settle.set()

    def _show_status(self) -> None:
        a = self.analysis
        viol = list(a.violations) if a is not None else []
        mesh = self.view.mesh_error if hasattr(self, "view") else None
        html = state.status_html(self.error, viol, a.lift_error if a else None, self.verified)
        if mesh:
            html += state._BOX.format(bg="#fde2e2", fg="#d62728",
                                      body=f"<b>No solid:</b> {mesh}")
        self.status.content = html

    def set_design(self, design: Design, reset_camera: bool = True) -> None:
        """Replace the whole design (preset, upload): controls follow."""
        with self.lock:
            self.base = design
            self.error = None
            self._sync_controls(design)
            self._apply(design, reset_camera=reset_camera)

    # --- the segment table (issue 10) -----------------------------------------------
    def _sync_segment_rows(self, design: Design) -> None:
        """Show the design's segments in the table: values in place when the rows
        match, rebuilt when segments were added, removed or changed kind. Lock held."""
        segs = design.motion.segments
        if [r["kind"].value for r in self.seg_rows] != [g.kind.value for g in segs]:
            self._build_segment_rows(design)
        self._syncing = True
        try:
            for row, g in zip(self.seg_rows, segs, strict=True):
                row["angle"].value = float(g.angle_deg)
                if g.lift_mm is not None:
                    row["lift"].value = float(g.lift_mm)
                    row["law"].value = g.law.value
        finally:
            self._syncing = False
        self._show_segment_sums(design.motion.segments)

    def _build_segment_rows(self, design: Design | list[dict]) -> None:
        segs = [MotionSegmentView.of(g) for g in
                (design.motion.segments if isinstance(design, Design) else design)]
        for row in self.seg_rows:
            for h in row.values():
                h.remove()
        for h in self.seg_extra:
            h.remove()
        self.seg_rows, self.seg_extra = [], []
        gui = self.client.gui
        laws = tuple(law.value for law in MotionLaw)
        with self.seg_folder:
            for i, g in enumerate(segs):
                dwell = g.kind == "dwell"
                row = {
                    "kind": gui.add_dropdown(f"{i + 1}. kind", ("rise", "fall", "dwell"),
                                             initial_value=g.kind),
                    "angle": gui.add_number(f"{i + 1}. angle [°]", g.angle_deg,
                                            min=0.0, max=360.0, step=0.5),
                    "lift": gui.add_number(f"{i + 1}. lift [mm]", g.lift_mm or 5.0,
                                           min=0.001, max=1000.0, step=0.5, disabled=dwell),
                    "law": gui.add_dropdown(f"{i + 1}. law", laws, disabled=dwell,
                                            initial_value=g.law or laws[0]),
                    "move": gui.add_button_group(f"{i + 1}.", ("↑", "↓", "✕")),
                }
                for key in ("kind", "angle", "lift", "law"):
                    row[key].on_update(lambda _e: self.on_segments())
                row["move"].on_click(lambda e, j=i: self.on_segment_move(j, e.target.value))
                self.seg_rows.append(row)
            add = gui.add_button("Add a segment (a 0° dwell at the end)")
            add.on_click(lambda _e: self.on_segment_move(len(self.seg_rows), "+"))
            self.seg_sums = gui.add_markdown("")
            self.seg_extra = [add, self.seg_sums]

    def _show_segment_sums(self, segs) -> None:
        total = sum(float(g["angle_deg"] if isinstance(g, dict) else g.angle_deg) for g in segs)
        net = sum((1 if k == "rise" else -1 if k == "fall" else 0) * float(lift or 0) for k, lift in
                  ((g["kind"], g.get("lift_mm")) if isinstance(g, dict)
                   else (g.kind.value, g.lift_mm) for g in segs))
        ok = abs(total - 360) <= 1e-6 and abs(net) <= 1e-9
        self.seg_sums.content = (f"Σ angles = **{total:g}°** (must be 360) · rises − falls = "
                                 f"**{net:g} mm** (must be 0){'' if ok else ' ⚠'}")

    def _segment_rows_as_dicts(self) -> list[dict]:
        out = []
        for row in self.seg_rows:
            kind = row["kind"].value
            g = {"kind": kind, "angle_deg": float(row["angle"].value)}
            if kind != "dwell":
                g.update(lift_mm=float(row["lift"].value), law=row["law"].value)
            out.append(g)
        return out

    def on_segments(self, segs: list[dict] | None = None) -> None:
        """A table value changed (or a row moved): the program is the table's segments
        with every other control as it is; invalid input keeps the last valid design."""
        with self.lock:
            if self._syncing or self.closed.is_set():
                return
            segs = self._segment_rows_as_dicts() if segs is None else segs
            data = self.design.model_dump(mode="json")
            data["motion"] = {"segments": segs}
            self._show_segment_sums(segs)
            design, err = state.try_design_dict(data)
            if err is not None:
                self.error = err
                if len(segs) != len(self.seg_rows) or [r["kind"].value for r in self.seg_rows] \
                        != [g["kind"] for g in segs]:
                    self._build_segment_rows(segs)  # show the user's edit, even if invalid
                    self._show_segment_sums(segs)
                self._show_status()
                return
            self.error = None
            self.base = design
            self._sync_controls(design)
            self._apply(design)

    def on_segment_move(self, i: int, action: str) -> None:
        """↑ / ↓ move segment i, ✕ removes it, + appends a 0° dwell."""
        with self.lock:
            segs = self._segment_rows_as_dicts()
            if action == "+" and len(segs) < MAX_SEGMENTS:
                segs.append({"kind": "dwell", "angle_deg": 0.0})
            elif action == "✕" and len(segs) > 1 and 0 <= i < len(segs):
                segs.pop(i)
            elif action == "↑" and 0 < i < len(segs):
                segs[i - 1], segs[i] = segs[i], segs[i - 1]
            elif action == "↓" and 0 <= i < len(segs) - 1:
                segs[i], segs[i + 1] = segs[i + 1], segs[i]
            else:
                return
            self.on_segments(segs)

    def load_preset(self, name: str) -> None:
        # viser does not check a dropdown's value against its options: only a shipped
        # name is looked up (camcore.model.load_preset never joins it onto a path)
        if name not in preset_names():
            with self.lock:
                self.files_md.content = f"✖ No preset {state.esc(str(name)[:60])}."
            return
        try:
            d = load_preset(name)
        except DesignError as exc:
            with self.lock:
                self.error = f"preset {name}: {exc}"
                self._show_status()
            return
        self.set_design(d)
        with self.lock:
            self.files_md.content = f"Loaded preset **{state.esc(name)}**."

    def upload(self, name: str, content: bytes) -> None:
        try:
            d = design_from_json(content)
        except DesignError as exc:
            with self.lock:
                self.error = f"file {name or 'upload'}: {exc} (the current design is kept)"
                self._show_status()
                self.files_md.content = (f"✖ Could not open **{state.esc(name)}**: "
                                         f"{state.esc(exc)}")
            return
        self.set_design(d)
        with self.lock:
            self.files_md.content = f"Opened **{state.esc(name)}** ({state.esc(d.name)})."

    def upload_refused(self, name: str, size: int) -> None:
        """The upload guard (app.uploads) dropped a transfer larger than its cap."""
        with self.lock:
            self.files_md.content = (
                f"✖ **{state.esc(name)}** refused: {size:,} bytes, more than the "
                f"{uploads.MAX_UPLOAD_BYTES:,}-byte limit (a design file is a few kB).")

    def download(self, kind: str) -> None:
        with self.lock:
            a, d = self.analysis, self.design
            if self.error is not None:  # the controls no longer describe d: say so
                self.files_md.content = (
                    "✖ Download refused: the input is invalid (see the red panel). "
                    "Fix it, or load a design, and the files will hold what you see.")
                return
            try:
                spec = export.EXPORTS[kind]  # a fixed table: the client's value is only a key
                name, data = f"{file_stem(d)}{spec.suffix}", spec.write(a)
            except (KeyError, export.ExportError) as exc:
                self.files_md.content = f"✖ Cannot export {state.esc(kind)}: {state.esc(exc)}"
                return
            self.last_download = (name, data)
            self.files_md.content = (f"Sent **{state.esc(name)}** ({len(data):,} bytes) of "
                                     f"*{state.esc(d.name)}*, {d.follower.kind.label}.")
        self.client.send_file_download(name, data, save_immediately=True)

    # --- angle, stations, animation ------------------------------------------------
    def _index(self, theta_deg: float) -> int:
        th = self.analysis.theta
        x = math.radians(theta_deg % 360.0)
        j = int(np.clip(np.searchsorted(th, x), 1, th.size - 1))
        return j - 1 if x - th[j - 1] < th[j] - x else j

    def _show_summary(self, s: dict) -> None:
        """Key numbers, and what happens at each station in words (for _show_where)."""
        self.summary_md.content = state.summary_markdown(s)
        self.station_events = [st["event"] for st in s["stations"]]

    def _show_where(self, k: int) -> None:
        a = self.analysis
        th = math.degrees(a.theta[k])
        st = np.degrees(a.stations)
        step = a.design.limits.resolution_deg
        at = [i for i, s in enumerate(st) if abs(th - s) <= step / 2 + 1e-9]
        events = ""
        if at:
            where = "at station " + " and ".join(str(i) for i in at)
            known = self.station_events
            events = "  \n" + "  \n".join(f"*{state.esc(known[i])}*" for i in at
                                           if i < len(known))
        else:
            i, n = int(np.searchsorted(st, th)), len(st)
            where = (f"between stations {i - 1} and {i}" if 0 < i < n
                     else f"between stations {n - 1} and 0")
        faces = [a.geo.faces[i].name for i in np.flatnonzero(a.in_contact[:, k])]
        touch = ", ".join(faces) if faces else "none"
        seg = SEGMENT_NAMES[int(a.prog.segment[k])]
        if a.prog.index[k] != a.prog.index[k - 1]:  # a boundary: say both (k - 1 wraps)
            seg = f"{SEGMENT_NAMES[int(a.prog.segment[k - 1])]} ends, {seg} begins"
        self.where_md.content = (
            f"**θ = {th:.1f}°** · {seg} · **{where}**  \n"
            f"In contact: **{touch}** · S = {to_mm(a.prog.S[k]):.3f} mm · "
            f"F_N = {a.guide.FN[k]:.1f} N{events}")

    def _goto(self, theta_deg: float, markers: bool = True, slider: bool = True) -> None:
        """Lock held."""
        self.theta_deg = theta_deg % 360.0
        k = self._index(self.theta_deg)
        with self.client.atomic():
            self.view.pose(k)
            if slider:
                self._syncing = True
                try:
                    self.angle_slider.value = round(self.theta_deg, 1)  # as the text
                finally:
                    self._syncing = False
            if self.camera_view == "Contact close-up":  # follow the contacts as S changes
                pos, look, _ = camera_for(self.camera_view, self.analysis, k)
                self.client.camera.position, self.client.camera.look_at = pos, look
            if markers:
                self._show_where(k)
                for c in self.curves:
                    c.marker(math.degrees(self.analysis.theta[k]))

    def _on_angle(self, value: float) -> None:
        with self.lock:
            if self._syncing:
                return
            self._goto(float(value), slider=False)

    def _show_station_buttons(self, a) -> None:
        names = tuple(str(i) for i in range(len(a.stations)))
        if tuple(self.stations_btn.options) != names:
            self.stations_btn.options = names

    def goto_station(self, i: int | str) -> None:
        """Jump to station i; anything else (a hostile client's value) is ignored."""
        with self.lock:
            n = len(self.analysis.stations)
            if str(i) not in {str(k) for k in range(n)}:
                return
            self._set_playing(False)
            self._goto(math.degrees(float(self.analysis.stations[int(i)])))

    def _set_speed(self, v: float) -> None:
        self.speed = float(v)

    def _set_overlay(self, name: str, on: bool) -> None:
        with self.lock:
            self.view.set_overlay(name, bool(on))

    def _set_playing(self, on: bool) -> None:
        self.playing = on
        self.play_btn.label = "⏸ Pause" if on else "▶ Play"
        self.play_btn.color = "orange" if on else "green"
        if on:
            self._wake_anim.set()

    def toggle_play(self) -> None:
        with self.lock:
            self._set_playing(not self.playing)
            if not self.playing:
                self._goto(self.theta_deg)

    def frame(self, dt: float, n: int = 0) -> None:
        """One animation step of dt seconds (called by the loop; public for the bench)."""
        with self.lock:
            if self.closed.is_set():
                return
            slow = n % 3 == 0  # angle slider and label at 10 Hz
            self._goto(self.theta_deg + self.speed * dt, markers=False, slider=slow)
            if n % 15 == 0:  # curve markers at 2 Hz: each one resends the plot data
                k = self._index(self.theta_deg)
                self._show_where(k)
                for c in self.curves:
                    c.marker(math.degrees(self.analysis.theta[k]))

    def _animate(self) -> None:
        period, n, last = 1.0 / FPS, 0, time.perf_counter()
        while not self.closed.is_set():
            if not self.playing:
                self._wake_anim.wait(0.5)  # asleep while paused
                self._wake_anim.clear()
                last = time.perf_counter()
                continue
            now = time.perf_counter()
            try:
                self.frame(min(now - last, 0.2), n)
                self.frames_played += 1
            except Exception:  # client gone mid-frame
                if self.closed.is_set():
                    return
                raise
            last, n = now, n + 1
            time.sleep(max(0.0, period - (time.perf_counter() - now)))

    def _settle(self) -> None:
        """Background: verified analysis and the four-follower comparison, once the tab
        has been still for SETTLE_S, and one tab at a time across the server
        (BACKGROUND), so that the cheap re-analysis of every tab always comes first."""
        while not self.closed.is_set():
            if not self._wake_settle.wait(0.5):
                continue
            self._wake_settle.clear()
            time.sleep(SETTLE_S)  # let a slider drag finish
            if self._wake_settle.is_set():
                continue
            with BACKGROUND:
                if not self._wake_settle.is_set() and not self.closed.is_set():
                    self.settle_once()

    def settle_once(self) -> None:
        with self.lock:
            design, gen = self.design, self.gen
        av = analyze(design, verify=True)
        with self.lock:
            if gen != self.gen or self.closed.is_set():
                return  # changed meanwhile: the comparison would be stale too
        results = compare.compute(design)
        with self.lock:
            if gen != self.gen or self.closed.is_set():
                return
            old = [(v.code, v.ranges_deg) for v in self.analysis.violations]
            self.analysis, self.verified = av, True
            if [(v.code, v.ranges_deg) for v in av.violations] != old:
                self.view.build(av)
                for c in self.curves:
                    c.update(av, self._index(self.theta_deg))
            self._show_summary(summary(av))
            self._show_status()
            self.compare_view.update(results)

    def show_stations_diagram(self) -> None:
        """The mechanism at every station side by side (camcore.document), under the
        button; drawn from the design on screen, replaced on each click."""
        from camcore.document import stations_image

        with self.lock:
            a = self.analysis
        image = stations_image(a)  # ~0.5 s of matplotlib, outside the lock
        with self.lock:
            if self.stations_img is not None:
                self.stations_img.image = image
            else:
                with self.view_folder:
                    self.stations_img = self.client.gui.add_image(image, format="png")

    def set_camera_view(self, view: str) -> None:
        """A preset view (Front by default; the close-up follows the animation)."""
        if view not in CAMERA_VIEWS:  # a client may send anything
            return
        with self.lock:
            self.camera_view = view
            self.reset_camera()

    def reset_camera(self) -> None:
        pos, look, fov = camera_for(self.camera_view, self.analysis, self.view.k)
        cam = self.client.camera
        cam.up_direction = (0.0, 1.0, 0.0)
        cam.fov = fov
        cam.position = pos
        cam.look_at = look

    def close(self) -> None:
        self.closed.set()
        self._wake_anim.set()
        self._wake_settle.set()
        for t in self.threads:
            if t is not threading.current_thread():
                t.join(timeout=2.0)
