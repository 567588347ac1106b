"""The tab's GUI: built once by ``build_layout``, returned as a dataclass of handles.

Nothing here reacts to anything: app.session wires the handles' callbacks to its
actions. Above the tabs: the status panel, the cam's STL one click away, and the
animation (play, speed, angle, stations, where we are). Tabs: Design (controls,
program table, key numbers), Curves, Compare, Explore (design-space sweeps), View
(overlays, cameras, stations diagram), Files (presets, upload, kept designs,
downloads).
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass, field
from typing import Any

from camcore.model import Design, load_preset, preset_names

from . import compare, controls, plots, storage
from .explore import ExplorePanel
from .scene import CAMERA_VIEWS, OFF_BY_DEFAULT, OVERLAYS, legend_html
from .segments import SegmentTable

DEFAULT_PRESET = "paper_example"
OVERLAY_LABELS = {
    "contacts": "Contact points",
    "forces": "Contact normals as force arrows (∝ F_N)",
    "instant_centre": "Instant centre I23 = Q and normals",
    "pressure_angle": "Pressure angle φ",
    "arcs": "Base circle and dwell arcs",
    "wear": "Wear along the profile (Archard; pale none → dark indigo most)",
}
DOWNLOADS = (
    ("json", "Design JSON"),
    ("stl", "Cam STL (mm)"),
    ("dxf", "Profile DXF (mm)"),
    ("dxf_cut", "Outline DXF, cut only (mm)"),
    ("follower_dxf", "Follower faces DXF (mm)"),
    ("csv", "Profile CSV"),
    ("series", "Per-angle CSV"),
    ("toolpath", "G-code (cutter path)"),
    ("html", "Printable report"),
    ("pdf", "Report PDF"),
)
STATION_NAMES = ("0", "1", "2", "3", "4", "5")  # the paper's six; app.session adapts them
# steps of the cam angle a teacher clicks through (a review: only the slider's 0.1 deg
# arrow keys, the stations or typing an angle moved it by hand)
STEP_DEG = {"−5°": -5.0, "−1°": -1.0, "+1°": 1.0, "+5°": 5.0}
SPEED_MIN_DEG_S, SPEED_MAX_DEG_S = 5.0, 360.0  # the animation's play speed
# The wide panel (Curves tab): viser's widest theme panel is 24 em = 384 px; the wide
# one takes 62 % of the 3D view's drawing width, at most 1000 px (it stays at the right
# edge and its charts follow). The drawing width is in device pixels (CSS pixels times
# the screen's pixel ratio, times 0.75-1 as viser adapts to the frame rate), so on a
# high-DPI screen the share is larger; panels.STATUS_CSS keeps every panel 80 px
# narrower than the window.
NARROW_PANEL_PX = 384
PAUSE_AT_STATION_S = 3.0  # the animation's stop at each station, when asked
HISTORY_BUTTONS = ("↶ Undo", "↷ Redo")  # every change of the design, a preset's too


def preset_labels() -> dict[str, str]:
    """{label shown: shipped preset name}: each preset by its design's own name up to
    any parenthesis (a teacher's review: the list showed "classroom_harmonic" and the
    like, the CLI's names), shortened at a word to 64 characters; the default first; a
    label two presets would share keeps the preset's name after it."""
    out: dict[str, str] = {}
    names = sorted(preset_names(), key=lambda n: n != DEFAULT_PRESET)
    for name in names:
        own = load_preset(name).name.split(" (")[0]
        label = textwrap.shorten(own, 64, placeholder=" …") or name
        out[label if label not in out else f"{label} [{name}]"] = name
    return out


def wide_panel_px(drawn_width_px: int) -> int:
    """The wide panel's width [px] for a 3D view ``drawn_width_px`` wide (0: unknown,
    taken as 1280)."""
    width = drawn_width_px if drawn_width_px > 0 else 1280
    return int(max(NARROW_PANEL_PX, min(0.62 * width, 1000)))


@dataclass
class Layout:
    """Handles of one tab's widgets (viser GUI handles unless said otherwise)."""

    status: Any
    quick_stl_btn: Any
    quick_md: Any
    # animation
    play_btn: Any
    speed_slider: Any
    angle_slider: Any
    pause_box: Any
    stations_btn: Any
    stations_md: Any  # the stations' angles
    step_btns: Any
    where_md: Any
    # Design tab
    history_btns: Any  # Undo, Redo (app.history)
    history_md: Any  # how many steps each way
    controls: dict[str, Any]  # by design path, see app.controls.SPECS
    low_dwell_md: Any
    spring_btn: Any  # puts the proposed spring rate in (Dynamics)
    spring_md: Any  # what it did
    segments: SegmentTable
    summary_md: Any
    # Curves, Compare
    wide_box: Any
    curves: list[plots.Curve]
    compare_view: compare.CompareView
    explore: ExplorePanel
    # View tab
    view_folder: Any
    overlay_boxes: dict[str, Any]
    view_btns: Any
    camera_btn: Any
    stations_fig_btn: Any
    stations_fig_md: Any  # says the diagram is coming, then where it is
    # Files tab
    preset_dd: Any
    preset_btn: Any
    upload_btn: Any
    save_name: Any
    save_btn: Any
    saved_dd: Any
    open_saved_btn: Any
    delete_saved_btn: Any
    download_btns: dict[str, Any]
    aside_btn: Any  # downloads the working design set aside as unreadable (hidden: none)
    files_md: Any
    stations_img: Any = field(default=None)  # added on the first diagram


def build_layout(gui, base: Design, first, speed_deg_s: float) -> Layout:
    """Build the whole tab in ``gui`` (a client's GuiApi) for design ``base`` whose
    analysis is ``first`` (the curves take their series from it)."""
    h: dict[str, Any] = {"status": gui.add_html("")}
    h["quick_stl_btn"] = gui.add_button("⬇ Download the cam (STL, mm)")
    h["quick_md"] = gui.add_markdown("")  # that button's answer (sent, or why not)
    with gui.add_folder("Animation", expand_by_default=True):
        h["play_btn"] = gui.add_button("▶ Play", color="green")
        h["speed_slider"] = gui.add_slider(
            "Play speed [°/s]", SPEED_MIN_DEG_S, SPEED_MAX_DEG_S, 5, speed_deg_s
        )
        h["angle_slider"] = gui.add_slider("Cam angle θ [°]", 0.0, 360.0, 0.1, 0.0)
        h["step_btns"] = gui.add_button_group("Step θ", tuple(STEP_DEG))
        h["pause_box"] = gui.add_checkbox(
            "Pause at stations",
            False,
            hint=f"playing stops {PAUSE_AT_STATION_S:g} s at each station, where a contact "
            "changes: time to say what happens there",
        )
        h["stations_btn"] = gui.add_button_group("Go to station", STATION_NAMES)
        # each station's angle, in sight (as the buttons' hint it covered the step
        # buttons and the angle box at every station click: an app review at 1280x720)
        h["stations_md"] = gui.add_markdown("")
        h["where_md"] = gui.add_markdown("")
    tabs = gui.add_tab_group()
    with tabs.add_tab("Design"):
        _design_tab(gui, base, h)
    with tabs.add_tab("Curves"):
        h["wide_box"] = gui.add_checkbox(
            "Wide panel",
            False,
            hint="the curves up to 1000 px wide, the panel at the right edge (it covers "
            "part of the 3D view; turn off to see all of it)",
        )
        h["curves"] = plots.build_curves(gui, first)
    with tabs.add_tab("Compare"):
        h["compare_view"] = compare.CompareView(gui)
    with tabs.add_tab("Explore"):
        h["explore"] = ExplorePanel(gui)
    with tabs.add_tab("View") as h["view_folder"]:
        _view_tab(gui, h)
    with tabs.add_tab("Files"):
        _files_tab(gui, h, base)
    return Layout(**h)


def _design_tab(gui, base: Design, h: dict) -> None:
    h["history_btns"] = gui.add_button_group("Design", HISTORY_BUTTONS)
    h["history_md"] = gui.add_markdown("")
    h["controls"] = {}
    for title, expand, specs in controls.FOLDERS:
        with gui.add_folder(title, expand_by_default=expand):
            for spec in specs:
                h["controls"][spec.path] = _control(gui, spec, base)
                if spec.path == "dynamics.spring_rate_N_per_m":  # (right under it)
                    h["spring_btn"] = gui.add_button(
                        "Use the proposed spring rate",
                        hint="k = the proposal of the key numbers: n k_min at this preload "
                        "(and the jump-speed margin, if set), rounded up; Undo takes it back",
                    )
                    h["spring_md"] = gui.add_markdown("")
            if title == "Motion program":
                h["low_dwell_md"] = gui.add_markdown("")
                folder = gui.add_folder("Program segments (any program)", expand_by_default=False)
                h["segments"] = SegmentTable(gui, folder, on_change=lambda segs: None)
    with gui.add_folder("Key numbers", expand_by_default=True):
        h["summary_md"] = gui.add_markdown("")


def _control(gui, spec: controls.Spec, base: Design):
    v = controls.control_value(base, spec)
    if v is None:  # e.g. a classic slider on another program: the default's value
        v = controls.control_value(Design(), spec)
    if spec.widget == "slider":
        lo, hi = min(spec.lo, v), max(spec.hi, v)
        return controls.fine(
            gui.add_slider(spec.label, lo, hi, spec.step, float(v), hint=spec.hint)
        )
    if spec.widget == "number":
        return controls.fine(gui.add_number(spec.label, float(v), step=spec.step, hint=spec.hint))
    if spec.widget == "dropdown":
        return gui.add_dropdown(
            spec.label, spec.labels or spec.options, initial_value=v, hint=spec.hint
        )
    if spec.widget == "text":
        return gui.add_text(spec.label, str(v), hint=spec.hint)
    return gui.add_checkbox(spec.label, bool(v), hint=spec.hint)


def _view_tab(gui, h: dict) -> None:
    h["overlay_boxes"] = {
        name: gui.add_checkbox(OVERLAY_LABELS[name], name not in OFF_BY_DEFAULT)
        for name in OVERLAYS
    }
    gui.add_html(legend_html())
    h["view_btns"] = gui.add_button_group("Camera", CAMERA_VIEWS)
    h["camera_btn"] = gui.add_button("Reset camera")
    h["stations_fig_btn"] = gui.add_button("Stations diagram (the paper's Fig. 4)")
    h["stations_fig_md"] = gui.add_markdown("")


def _files_tab(gui, h: dict, base: Design) -> None:
    labels = {name: label for label, name in preset_labels().items()}
    h["preset_dd"] = gui.add_dropdown(
        "Preset",
        tuple(labels.values()),
        initial_value=labels.get(DEFAULT_PRESET, next(iter(labels.values()))),
        hint="the shipped designs (by the CLI's names: "
        + ", ".join(labels)
        + ", e.g. camcore report --preset paper_example)",
    )
    h["preset_btn"] = gui.add_button("Load preset")
    h["upload_btn"] = gui.add_upload_button("Open design JSON…", mime_type="application/json")
    gui.add_markdown("**Kept in this browser** (only you see them)")
    h["save_name"] = gui.add_text("Name", storage.proposed_name(base.name))
    h["save_btn"] = gui.add_button("Save in this browser")
    h["saved_dd"] = gui.add_dropdown("Saved designs", ("–",), initial_value="–")
    h["open_saved_btn"] = gui.add_button("Open saved")
    h["delete_saved_btn"] = gui.add_button("Delete saved")
    h["aside_btn"] = gui.add_button(  # shown while the browser holds one (Session._restore)
        "⬇ The design this version could not open", visible=False
    )
    # the tab's answers (saved, opened, sent, refused) stand here, under the buttons
    # whose answer has no other sign (a review: under the ten download buttons a
    # save's "Saved ..." was off screen at 1280x720; a download shows in the browser)
    h["files_md"] = gui.add_markdown("")
    gui.add_markdown("**Download**")
    h["download_btns"] = {kind: gui.add_button(label) for kind, label in DOWNLOADS}
