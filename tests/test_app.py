"""Server-side tests of the design studio: drive the GUI handles of a real viser server
(through websocket clients that viser counts as browser tabs, tests/fake_tab.py) and
check the scene, curves and panels change as they should."""

from __future__ import annotations

import contextlib
import io
import itertools
import json
import math
import re
import threading
import time

import numpy as np
import pytest
import trimesh
from conftest import wait_for
from fake_tab import FakeTab
from viser._gui_handles import GuiEvent, UploadedFile

from app import panels, scene
from app.controls import LABEL_OF_LAW
from camcore import sweep
from camcore.model import Design, design_to_json, load_preset
from camcore.report import summary


@contextlib.contextmanager
def restored_tab(
    app, monkeypatch, stored: dict, writes: dict | None = None, read=None, join: bool = True
):
    """A new tab whose browser storage holds ``stored`` (key -> text), its restore
    finished (unless ``join`` is False); what the tab writes goes to ``writes``. Yields
    its Session. ``read``: the store's read instead (self, key) -> text."""
    from app import storage

    default = lambda self, key: stored.get(key)  # noqa: E731
    monkeypatch.setattr(storage.BrowserStore, "read", read or default)
    sink = {} if writes is None else writes
    monkeypatch.setattr(storage.BrowserStore, "write", lambda self, k, v: sink.__setitem__(k, v))
    before = set(app.sessions)
    t = FakeTab(app.port)
    try:
        assert wait_for(lambda: set(app.sessions) - before)
        (s,) = [app.sessions[c] for c in set(app.sessions) - before]
        if join:
            s._restorer.join(10)
        yield s
    finally:
        t.close()


def fire_upload(handle, name: str, content: bytes) -> None:
    """What viser does when a browser uploads a file to ``handle``."""
    handle._impl.value = UploadedFile(name, content)
    for cb in handle._impl.update_cb:
        cb(GuiEvent(client=None, client_id=None, target=handle))


def test_session_starts_on_paper_example(tab):
    s = tab
    assert s.design == load_preset("paper_example")
    assert s.error is None
    assert "All design limits met" in s.ui.status.content
    assert s.view.nodes["cam"].vertices.shape[0] > 1000
    assert s.view.builds == 1
    assert "station 0" in s.ui.where_md.content
    assert "S1 (left face), S2 (right face)" in s.ui.where_md.content  # low dwell: both touch


def test_control_change_reanalyses_and_redraws(tab):
    s = tab
    old_verts = s.view.nodes["cam"].vertices.copy()
    builds = s.view.builds
    s.ui.controls["motion.lift_mm"].value = 25.0
    assert s.design.motion.lift_mm == 25.0
    assert s.view.builds == builds + 1
    new_verts = s.view.nodes["cam"].vertices
    r_old = np.hypot(old_verts[:, 0], old_verts[:, 1]).max()
    r_new = np.hypot(new_verts[:, 0], new_verts[:, 1]).max()
    assert r_new > r_old + 0.009  # the high-dwell arc moved out by ~10 mm
    s_curve = s.ui.curves[0].handle.data[1]  # S [mm]
    assert abs(np.nanmax(s_curve) - 25.0) < 1e-6
    assert "Low dwell" in s.ui.low_dwell_md.content


def test_speed_change_redraws_forces_but_keeps_the_geometry(tab):
    s = tab
    builds, cam = s.view.builds, s.view.nodes["cam"]
    force_plot = next(c for c in s.ui.curves if "F_N" in c.handle.title)
    before = np.array(force_plot.handle.data[1])
    s_data = s.ui.curves[0].handle.data
    s.ui.controls["cam.speed_rpm"].value = 600.0
    assert s.design.cam.speed_rpm == 600.0
    assert s.view.builds == builds and s.view.nodes["cam"] is cam  # nothing re-sent
    assert s.ui.curves[0].handle.data is s_data  # S did not change: its plot not re-sent
    # a quarter of the inertia force M A omega^2 (about 53 N at 1200 rpm): F_N falls where
    # the follower accelerates and rises where it decelerates
    change = np.array(force_plot.handle.data[1]) - before
    assert np.nanmin(change) < -10 and np.nanmax(change) > 10
    s.ui.controls["cam.base_radius_mm"].value = 90.0
    assert s.view.builds == builds + 1 and s.view.nodes["cam"] is not cam


def test_invalid_value_keeps_last_design_and_explains(tab):
    s = tab
    good, a = s.design, s.analysis
    s.ui.controls["motion.rise_deg"].value = 250.0  # 250 + 70 + 130 > 360
    assert s.design == good and s.analysis is a or s.analysis.design == good
    assert "Invalid input" in s.ui.status.content
    assert "exceeds 360 deg by 90 deg" in s.ui.status.content
    # in the controls' words (a first-hour user read "rise_deg + high_dwell_deg + ...")
    assert "Rise β_r [°] + High dwell β_h [°] + Fall β_f [°]" in s.ui.status.content
    assert "−90" in s.ui.low_dwell_md.content or "-90" in s.ui.low_dwell_md.content
    s.ui.controls["follower.face_radius_mm"].value = -50.0  # still invalid, now two problems
    assert s.design == good
    s.ui.controls["motion.rise_deg"].value = 100.0
    assert "face_radius_mm" in s.ui.status.content and "base radius" in s.ui.status.content
    s.ui.controls["follower.face_radius_mm"].value = -250.0
    assert s.error is None and "Invalid input" not in s.ui.status.content
    assert s.design == good


def test_limit_violations_are_highlighted(tab):
    s = tab
    assert "bad" not in s.view.nodes
    s.ui.controls["motion.lift_mm"].value = 40.0
    s.ui.controls["motion.rise_deg"].value = 30.0
    codes = {v.code for v in s.analysis.violations}
    assert "pressure_angle" in codes
    assert "design-limit violation" in s.ui.status.content
    assert "Eqs. 5, 13" in s.ui.status.content
    assert s.view.nodes["bad"].points.shape[0] > 0  # red segments on the cam profile
    phi_plot = next(c for c in s.ui.curves if c.title.startswith("Pressure angle"))
    assert np.max(phi_plot.shade) > 0  # shaded angles on the pressure-angle curve
    on = phi_plot.x[phi_plot.shade > 0]
    assert on.min() >= 0 and on.max() <= 31  # only over the (short) rise


def test_follower_kind_changes_the_body(tab):
    s = tab
    s.ui.controls["follower.kind"].value = "double_roller"
    assert s.design.follower.kind.value == "double_roller"
    assert {"pin0", "pin1"} <= set(s.view.nodes)
    assert s.ui.controls["follower.face_radius_mm"].disabled
    assert not s.ui.controls["follower.roller_radius_mm"].disabled
    s.ui.controls["follower.kind"].value = "single_concave"
    assert "pin0" not in s.view.nodes and "face1" not in s.view.nodes
    assert s.ui.controls["follower.offset_mm"].disabled
    assert "In contact: <b>face</b>" in s.ui.where_md.content


def test_material_and_allowable_stress_are_set_in_the_app(tab):
    """A designer's material: the cam surface sets the allowable (its default in the
    word), a figure of one's own replaces it (0: the surface's again), the safety
    factor divides it; the key numbers show the limit and the stress plot draws it."""
    s = tab
    s.ui.controls["follower.kind"].value = "single_roller"  # ~212 MPa
    stress_plot = next(c for c in s.ui.curves if c.title.startswith("Contact (Hertz)"))

    def limit_drawn() -> float | None:
        if not stress_plot.handle.series[2].get("show", True):
            return None  # hidden (its values stay finite: uPlot cannot range NaN)
        return float(np.max(stress_plot.handle.data[2]))

    assert "1000 MPa / 1.25 = 800 MPa" in s.ui.summary_md.content
    # 212 MPa under an 800 MPa line would flatten the curve: the line is hidden
    assert limit_drawn() is None
    assert np.isfinite(np.asarray(stress_plot.handle.data[2], float)).all()
    assert "limit 800 MPa (far above" in stress_plot.handle.series[2]["label"]
    s.ui.controls["material.grade"].value = "bronze (350 MPa)"
    assert s.design.material.grade.value == "bronze"
    assert "350 MPa / 1.25 = 280 MPa" in s.ui.summary_md.content
    assert limit_drawn() == pytest.approx(280.0)
    assert stress_plot.handle.series[2]["label"] == "limit 280 MPa"
    assert "contact_stress" not in {v.code for v in s.analysis.violations}
    s.ui.controls["limits.allowable_contact_stress_MPa"].value = 200.0  # 212 x 1.25 > 200
    assert s.design.limits.allowable_contact_stress_MPa == 200.0
    assert "contact_stress" in {v.code for v in s.analysis.violations}
    assert "Hertz stress" in s.ui.status.content and "allowable 200 MPa" in s.ui.status.content
    assert "limit 160 MPa" in stress_plot.handle.series[2]["label"]
    s.ui.controls["limits.contact_stress_safety_factor"].value = 1.0
    s.ui.controls["limits.allowable_contact_stress_MPa"].value = 0.0  # the surface's again
    assert s.design.limits.allowable_contact_stress_MPa is None
    assert "350 MPa / 1 = 350 MPa" in s.ui.summary_md.content
    assert s.analysis.valid


def test_a_jump_speed_margin_and_a_largest_cam_are_set_in_the_limits(tab):
    """A designer asks for contact up to 1.6 x the speed, then a cam within 150 mm:
    the status names the broken limit; 0 takes each off again."""
    s = tab
    s.ui.controls["limits.min_jump_speed_ratio"].value = 1.6
    assert s.design.limits.min_jump_speed_ratio == 1.6
    assert "jump_speed" in {v.code for v in s.analysis.violations}
    assert "below the margin 1.6 x" in s.ui.status.content
    s.ui.controls["limits.min_jump_speed_ratio"].value = 0.0
    assert s.design.limits.min_jump_speed_ratio is None and s.analysis.valid
    s.ui.controls["limits.max_outer_diameter_mm"].value = 150.0  # the cam is ~190 mm
    assert "outer_diameter" in {v.code for v in s.analysis.violations}
    assert "above the limit 150 mm" in s.ui.status.content
    s.ui.controls["limits.max_outer_diameter_mm"].value = 0.0
    assert s.design.limits.max_outer_diameter_mm is None and s.analysis.valid


def test_bad_upload_keeps_design_then_good_upload_loads(tab):
    s = tab
    good = s.design
    fire_upload(s.ui.upload_btn, "broken.json", b"{not json")
    assert s.design == good
    assert "not a JSON document" in s.ui.status.content
    assert "broken.json" in s.ui.files_md.content
    fire_upload(s.ui.upload_btn, "bad.json", b'{"cam": {"base_radius_mm": -5}}')
    assert s.design == good and "base_radius_mm" in s.ui.status.content
    other = load_preset("valve_lift_roller")
    fire_upload(s.ui.upload_btn, "valve.json", design_to_json(other).encode())
    assert s.design == other and s.error is None
    assert s.ui.controls["cam.base_radius_mm"].value == other.cam.base_radius_mm
    assert s.ui.controls["follower.kind"].value == other.follower.kind.label
    assert "not in the file" not in s.ui.files_md.content  # a complete file
    fire_upload(s.ui.upload_btn, "short.json", b'{"cam": {"width_mm": 12}}')
    assert s.design.cam.width_mm == 12 and s.design.cam.base_radius_mm == 80.0
    assert panels.esc("cam.base_radius_mm = 80.0") in s.ui.files_md.content  # said, not silent


def test_a_file_that_cannot_be_opened_does_not_block_downloads(tab, downloads):
    """A failed upload is said in the status panel, but the controls still describe the
    design on screen: its files download. An invalid control value still refuses them,
    and the quick button above the tabs answers under itself, where the user looks."""
    s = tab
    fire_upload(s.ui.upload_btn, "broken.json", b"{not json")
    assert "not a JSON document" in s.ui.status.content
    assert "Could not open" in s.ui.status.content and "Invalid input" not in s.ui.status.content
    s.ui.download_btns["stl"].value = True
    assert downloads and downloads[-1][0].endswith(".stl")
    assert "Sent" in s.ui.files_md.content
    s.ui.controls["follower.face_radius_mm"].value = -50.0  # |r_f| < r_b: invalid input
    n, files = len(downloads), s.ui.files_md.content
    s.ui.quick_stl_btn.value = True
    assert len(downloads) == n and "Download refused" in s.ui.quick_md.content
    assert s.ui.files_md.content == files
    s.ui.controls["follower.face_radius_mm"].value = -250.0
    assert s.ui.quick_md.content == ""  # the answer spoke of the input before
    s.ui.quick_stl_btn.value = True
    assert len(downloads) == n + 1 and "Sent" in s.ui.quick_md.content


def test_a_value_typed_beyond_a_slider_widens_it(tab):
    """A slider's box takes values beyond the slider's range: the range widens, so the
    browser does not cut the value back at its next redraw (tests/test_browser.py shows
    that it would), and the design keeps what was typed."""
    s = tab
    lift = s.ui.controls["motion.lift_mm"]
    lift.value = 70.0  # the slider ends at 60
    assert s.design.motion.lift_mm == 70.0 and lift.max >= 70.0
    base = s.ui.controls["cam.base_radius_mm"]
    base.value = -5.0  # below the slider's 10: widened too (the design refuses it)
    assert base.min <= -5.0 and s.error is not None
    base.value = 90.0
    assert s.error is None and s.design.motion.lift_mm == 70.0
    assert base.min == 10  # back to its own range once the value is back in it
    lift.value = float("inf")  # refused, and not a range to keep
    assert s.error is not None and lift.max == 70.0
    lift.value = 20.0
    assert s.error is None and lift.max == 60


def test_the_browser_s_clamp_of_a_value_typed_beyond_a_slider_is_undone(tab):
    """The box beside a slider cuts a value beyond the slider's range back to its end
    when it loses focus, and sends that; if the Tab comes before the widened range
    reached the browser, the end arrives just after the value typed (a review: a lift
    of 70 on the 60 mm slider drew a 60 mm cam without a word, 2 tries of 4; an r_f of
    -10 became -20 with a red box naming -20). That end is undone; a value passing
    through others on the way, or coming later, is the user's."""
    s = tab
    lift = s.ui.controls["motion.lift_mm"]
    lift.value = 70.0  # the slider ends at 60
    lift.value = 60.0  # the browser's clamp, at once
    assert s.design.motion.lift_mm == 70.0 and lift.value == 70.0 and lift.max >= 70.0
    assert "Lift h [mm]: 70 stands" in s.ui.quick_md.content
    face = s.ui.controls["follower.face_radius_mm"]
    face.value = -10.0  # above the slider's -20
    face.value = -20.0
    assert face.value == -10.0 and s.error is not None
    assert "|r_f| = 10 mm" in s.error
    face.value = -250.0
    # typed on purpose: 70, then 6 and 60 (each keystroke arrives)
    lift.value = 70.0
    lift.value = 6.0
    lift.value = 60.0
    assert s.design.motion.lift_mm == 60.0 and lift.value == 60.0
    # the end, later than a Tab comes
    lift.value = 70.0
    s._arrived["motion.lift_mm"] = [(70.0, time.monotonic() - 5.0, 0.0, 60.0)]
    lift.value = 60.0
    assert s.design.motion.lift_mm == 60.0
    # back to the end at once, on purpose (a typo's 600 taken back to 60): taken for a
    # clamp too (from here the two look alike), and said, and typing it again works
    for v in (6.0, 60.0, 600.0, 60.0):
        lift.value = v
    assert lift.value == 600.0 and "to have 60, type it again" in s.ui.quick_md.content
    for v in (6.0, 60.0):
        lift.value = v
    assert s.design.motion.lift_mm == 60.0 and s.error is None
    assert s.ui.quick_md.content == ""
    # the browser clamps to the range it has: a slider widened to 70 cuts 90 to 70
    lift.value = 70.0
    lift.value = 90.0
    lift.value = 70.0
    assert s.design.motion.lift_mm == 90.0 and lift.max >= 90.0


def test_archard_k_is_entered_in_its_own_scale(tab):
    """Archard's k (~1e-8 mm^3/(N m)) is below what the browser's number box keeps (7
    decimals: it became 0, switching wear off): the control is in 1e-9 mm^3/(N m). The
    design's value is kept to the last bit while the control still shows it."""
    s = tab
    k = s.ui.controls["wear.coefficient_mm3_per_N_m"]
    assert s.design.wear.coefficient_mm3_per_N_m == 1e-8 and k.value == 10.0
    s.ui.controls["cam.width_mm"].value = 20.0  # another edit: k is not re-rounded
    assert s.design.wear.coefficient_mm3_per_N_m == 1e-8
    k.value = 2.0
    assert s.design.wear.coefficient_mm3_per_N_m == pytest.approx(2e-9, rel=1e-15, abs=0)
    assert "| wear depth max (Archard) | 0.0000 " not in s.ui.summary_md.content
    k.value = 0.0
    assert "| wear depth max (Archard) | 0.0000 " in s.ui.summary_md.content  # (can fail)
    k.value = 3.0
    assert s.design.wear.coefficient_mm3_per_N_m == 3e-9  # the decimal typed, exactly
    k.value = 2.5  # decimals are kept (the box's precision comes from its step)
    assert s.design.wear.coefficient_mm3_per_N_m == 2.5e-9 and k.precision >= 2


@pytest.mark.parametrize(
    "name, content, message",
    [
        ("huge.json", b'{"name": "' + b"x" * 30_000_000 + b'"}', "the limit is"),
        ("deep.json", b"[" * 100_000 + b"]" * 100_000, "not a JSON document"),
        ("photo.png", bytes(range(256)) * 64, "not a text file"),
        ("empty.json", b"", "the file is empty"),
        ("future.json", b'{"schema_version": 7}', "written by a newer program"),
        ("list.json", b"[1, 2]", "a design is a JSON object"),
        ("big.json", b'{"cam": {"width_mm": ' + b"9" * 400 + b"}}", "cam.width_mm"),
        ("long.json", b'{"motion": {"lift_mm": "' + b"A" * 900_000 + b'"}}', "is required"),
    ],
    # short ids: a 30 MB id went into PYTEST_CURRENT_TEST, and a worker process started
    # under it (the app fixture, when this test runs first) could not be spawned
    ids=["huge", "deep", "photo", "empty", "future", "list", "400 digits", "900 kB value"],
)
def test_hostile_uploads_keep_the_design_and_the_server(app, tab, name, content, message):
    """(400 digits had crashed the upload with OverflowError, and a 900 kB value had
    come back whole in the status and in Files.)"""
    s = tab
    good = s.design
    fire_upload(s.ui.upload_btn, name, content)
    assert s.design == good and message in s.ui.status.content and name in s.ui.files_md.content
    assert len(s.ui.status.content) < 3000 and len(s.ui.files_md.content) < 3000
    # the server keeps serving: the same tab still redraws on a control change
    s.ui.controls["motion.lift_mm"].value = 12.0
    assert s.design.motion.lift_mm == 12.0 and s.error is None


def test_a_refused_file_s_box_goes_at_the_next_file_action(tab, downloads):
    """A maker's review: the red "Could not open the file" box stayed through station
    clicks and a download, the download's answer under it. A download (or a save)
    is the user going on: the box goes; a station click leaves it."""
    s = tab
    fire_upload(s.ui.upload_btn, "bad.json", b'{"cam": {"base_radius_mm": -40}}')
    assert "Could not open the file" in s.ui.status.content
    s.goto_station(2)
    assert "Could not open the file" in s.ui.status.content
    s.ui.download_btns["stl"].value = True
    assert wait_for(lambda: "Sent" in s.ui.files_md.content, 30.0), s.ui.files_md.content
    assert "Could not open the file" not in s.ui.status.content


def test_a_refused_upload_clears_an_earlier_file_s_box(app, tab):
    """The red box of a file that could not be opened is about that file: a later
    upload refused for its size says so under Files, and the old box goes (it had
    stayed, naming the earlier file, above the refusal)."""
    from viser import _messages

    s = tab
    fire_upload(s.ui.upload_btn, "bad.json", b'{"cam": {"base_radius_mm": -40}}')
    assert "Could not open the file" in s.ui.status.content
    big = _messages.FileTransferStartUpload(
        source_component_uuid=s.ui.upload_btn._impl.uuid,
        transfer_uuid="t-big2",
        filename="big.json",
        mime_type="application/json",
        part_count=50,
        size_bytes=5_000_000,
    )
    s.client.gui._handle_file_transfer_start(s.client.client_id, big)
    assert "big.json** refused" in s.ui.files_md.content
    assert "Could not open the file" not in s.ui.status.content


def test_preset_and_downloads(tab, downloads):
    s = tab
    s.ui.preset_dd.value = "Classroom: simple harmonic rise/fall, single concave face"
    s.ui.preset_btn.value = True  # click
    assert s.design == load_preset("classroom_harmonic")
    s.ui.preset_dd.value = "../../paper_example"  # a hostile client's value: not a label
    s.ui.preset_btn.value = True
    assert s.design == load_preset("classroom_harmonic") and "No preset" in s.ui.files_md.content
    s.ui.download_btns["stl"].value = True
    name, data = downloads[-1]
    assert name.endswith(".stl")
    mesh = trimesh.load(io.BytesIO(data), file_type="stl")
    assert mesh.is_watertight
    expect = s.analysis.profile.area * 1e6 * s.design.cam.width_mm
    assert abs(mesh.volume - expect) / expect < 1e-6
    s.ui.quick_stl_btn.value = True  # the same part from the button above the tabs
    assert downloads[-1] == (name, data)
    assert "no shaft bore" in s.ui.quick_md.content  # a solid disc: said where one looks
    said = s.ui.quick_md.content
    assert "Bore diameter" in said and "bore_diameter_mm" not in said  # the control's name
    s.ui.download_btns["json"].value = True
    assert "no shaft bore" not in s.ui.files_md.content  # (a design file is no part)
    assert downloads[-1][1].decode().startswith("{")
    for kind, ext in (
        ("dxf", ".dxf"),
        ("dxf_cut", "_cut.dxf"),
        ("csv", "_profile.csv"),
        ("series", "_series.csv"),
        ("toolpath", ".nc"),
        ("follower_dxf", "_follower.dxf"),  # (the preset's single concave face)
    ):
        s.ui.download_btns[kind].value = True
        assert downloads[-1][0].endswith(ext) and len(downloads[-1][1]) > 1000
    s.ui.controls["follower.kind"].value = "single roller"  # no face to draw: said why
    sent = len(downloads)
    s.ui.download_btns["follower_dxf"].value = True
    assert "has no face to draw: its roller is a bearing" in s.ui.files_md.content
    assert len(downloads) == sent


def test_stations_angle_and_animation(tab):
    s = tab
    s.ui.stations_btn.value = "2"
    assert abs(np.radians(s.theta_deg) - s.analysis.stations[2]) < 1e-9
    assert "at station 2" in s.ui.where_md.content
    assert "station 2: S2 touches; from here the load is shared" in s.ui.where_md.content
    assert "S1 (left face), S2 (right face)" in s.ui.where_md.content  # both on the dwell arc
    assert "F_N = 68.4 N per face" in s.ui.where_md.content  # F_t / (2 cos psi_h): shared
    wxyz = np.array(s.view.cam_frame.wxyz)
    assert abs(2 * np.arctan2(-wxyz[3], wxyz[0]) - s.analysis.stations[2]) < 1e-2
    assert s.ui.angle_slider.value == pytest.approx(107.4)  # as the text says, not 107.5
    assert "θ = 107.4°" in s.ui.where_md.content
    s.ui.angle_slider.value = 50.0
    assert s.theta_deg == 50.0 and "rise" in s.ui.where_md.content
    assert "per face" not in s.ui.where_md.content  # S1 alone drives the rise
    y = s.view.follower_frame.position[1]
    assert abs(y - float(np.interp(np.radians(50), s.analysis.theta, s.analysis.prog.S))) < 1e-4
    s.ui.angle_slider.value = 0.0  # a boundary: both segments are named
    assert "low dwell ends, rise begins" in s.ui.where_md.content
    s.ui.angle_slider.value = 50.0
    builds = s.view.builds
    s.ui.play_btn.value = True
    assert s.playing and "Pause" in s.ui.play_btn.label
    assert wait_for(lambda: s.theta_deg > 52.0, 5.0)
    s.ui.play_btn.value = True
    assert not s.playing
    t = s.theta_deg
    time.sleep(0.3)
    assert s.theta_deg == t  # paused
    assert s.view.builds == builds  # animation never rebuilt meshes


def test_overlays_switch(tab):
    s = tab
    s.ui.angle_slider.value = 120.0
    assert s.view.nodes["forces"].visible
    s.ui.overlay_boxes["forces"].value = False
    assert not s.view.nodes["forces"].visible
    s.ui.overlay_boxes["arcs"].value = False
    assert not s.view.nodes["arcs"].visible
    s.ui.overlay_boxes["instant_centre"].value = False
    assert not s.view.nodes["q"].visible
    # the wear heat band along the profile: off by default (not even sent), darker where
    # wear is larger; drawn when switched on, redrawn with the design, gone when off
    assert "wear" not in s.view.nodes
    s.ui.overlay_boxes["wear"].value = True
    band = s.view.nodes["wear"]
    assert band.visible
    colors = np.asarray(band.colors, float)
    assert colors.shape[1:] == (2, 3) and np.ptp(colors[:, 0, 0]) > 50
    s.ui.controls["motion.lift_mm"].value = 25.0
    assert s.view.nodes["wear"] is not band  # the new cam's band
    s.ui.overlay_boxes["wear"].value = False
    assert "wear" not in s.view.nodes


def test_a_new_lift_resends_the_cam_not_the_unchanged_follower(tab):
    """A redraw sends only the nodes whose geometry changed: a new lift reshapes the
    cam and lengthens the stem; a roller follower's wheels, pins, yoke and guide, the
    hub and the overlay markers stay (concave pads follow the contact's range, so they
    are sent again)."""
    s = tab
    before = dict(s.view.nodes)
    s.ui.controls["motion.lift_mm"].value = 25.0
    after = dict(s.view.nodes)
    for name in ("cam", "outline", "stem", "face0"):  # face0: a concave pad
        assert after[name] is not before[name], name
    for name in ("hub", "forces", "q", "phi", "contact0"):
        assert after[name] is before[name], name
    s.ui.controls["follower.kind"].value = "double_roller"  # the pins appear
    assert {"pin0", "pin1"} <= set(s.view.nodes) and s.view.nodes["face0"] is not after["face0"]
    before = dict(s.view.nodes)
    s.ui.controls["motion.lift_mm"].value = 20.0
    after = dict(s.view.nodes)
    for name in ("cam", "outline", "stem"):
        assert after[name] is not before[name], name
    for name in ("face0", "face1", "pin0", "yoke", "guide", "hub", "label0", "label1", "q"):
        assert after[name] is before[name], name
    s.ui.controls["cam.base_radius_mm"].value = 90.0  # the follower moves out: all new
    for name in ("face0", "pin1", "guide", "hub", "label0", "forces"):
        assert s.view.nodes[name] is not after[name], name


def test_a_single_roller_where_a_double_ones_idle_face_was_is_not_dimmed(tab):
    """A double follower dims its idle face; a single roller at the same place (its
    offset e_s equal to the double's e) must be drawn in full colour, not keep the dimmed
    node (a review found the reused node)."""
    s = tab
    s.ui.controls["follower.kind"].value = "double_roller"
    s.ui.controls["follower.single_offset_mm"].value = s.design.follower.offset_mm
    a = s.analysis
    k = int(np.flatnonzero(~a.in_contact[0])[0])  # S1 idle: face0 dimmed
    s.ui.angle_slider.value = float(np.degrees(a.theta[k]))
    assert tuple(s.view.nodes["face0"].color) == scene.IDLE_FACE_RGB
    s.ui.controls["follower.kind"].value = "single_roller"
    assert tuple(s.view.nodes["face0"].color) == scene.FOLLOWER_RGB


def test_compare_tab(tab):
    s = tab
    s.refine()
    md = s.ui.compare_view.md.content
    for label in ("single roller", "double roller", "single concave", "double concave"):
        assert label in md
    assert "67.297" in md  # Table 1 reference column
    # which follower fields each follower takes (a designer's review: the rollers ran
    # with the greyed roller radius, unsaid), and what the limits column counts
    f = s.design.follower
    assert f"rollers r_c = {f.roller_radius_mm:g} mm, concave faces r_f = -250 mm" in md
    assert "without the geometric check" in md
    # the paper's point in a row: the stress while both faces share the load, beside a
    # single follower's in its dwell (a teacher's review: the cycle's peaks, in the
    # one-face windows, had double concave no better than single concave)
    # (Eq. 42 by hand: 212.15, 150.4 and 32.96 MPa for the rollers and the shared pair,
    # tests/test_followers.py; the single face's 46.6 is 32.96 at twice the force)
    assert "| σ_H high dwell [MPa]¹ | 212.2 | 150.4 | 46.6 | 33.0 |" in md
    # each cam's size: 2 (r_b + h) = 190 mm where the follower's dwell contact sits at
    # r_b + h, 2R (Eq. 20, profile.dwell_radius) for the double followers' shared dwell
    from camcore.profile import dwell_radius

    two_r = [
        2e3 * dwell_radius(r * 1e-3, 0.080, 0.010, 0.015) for r in (8.0, -250.0)
    ]  # (the paper's r_c, r_f, e and h; SI in, SI out)
    cells = ("190.00", f"{two_r[0]:.2f}", "190.00", f"{two_r[1]:.2f}")
    assert f"| outer Ø [mm] | {' | '.join(cells)} |" in md
    view = s.ui.compare_view
    # the paper's column speaks of its own example only (a review saw it beside any cam)
    s.ui.controls["cam.base_radius_mm"].value = 90.0
    s.refine()
    assert "| 67.297 |" not in view.md.content and "that design only" in view.md.content
    s.ui.controls["cam.base_radius_mm"].value = 80.0
    s.refine()
    assert "| 67.297 |" in view.md.content
    # a row per figure, a column per follower (columns per figure overflowed the panel)
    assert "| | single roller | double roller | single concave | double concave |" in (
        view.md.content
    )
    data = view.fn.handle.data  # θ, the four followers, the stations, θ now
    assert len(data) == 7 and data[0].size > 100
    # one grid for the four followers: their curves are drawn at the same angles
    xs = [r["theta_deg"] for r in view.results.values()]
    assert all(np.array_equal(x, view.fn.x) for x in xs)
    assert all(d.shape == data[0].shape for d in data)
    assert np.all(np.isfinite(data[1])) and s.verified
    assert "geometric check max" in s.ui.status.content
    # the design's stations dashed and its cam angle marked, as on the Curves tab: a
    # teacher steps through the stations watching the four followers
    spikes = lambda col: np.sort(data[0][data[col] > 1.0])  # noqa: E731
    assert np.allclose(spikes(5), np.degrees(s.analysis.stations), atol=1e-4)
    s.goto_station(2)
    data = view.stress.handle.data
    assert np.allclose(spikes(6), np.degrees(s.analysis.stations[2]), atol=1e-4)


def test_compare_tab_with_no_follower_computable(tab):
    """A design none of the four followers can take: the table says so and the plots
    show this design's stations with no curve (a review: they had kept the previous
    design's curves and stations; and a curve of NaN leaves uPlot no range, a blank
    plot, so a follower without a curve is hidden, not NaN)."""
    import json

    s = tab
    s.refine()
    data = json.loads(design_to_json(load_preset("paper_example")))
    data["follower"].update(kind="flat_face", offset_mm=1000.0, single_offset_mm=1000.0)
    data["cam"]["base_radius_mm"] = 5.0
    data["motion"] = {"lift_mm": 3.0, "rise_deg": 100.0, "high_dwell_deg": 70.0, "fall_deg": 130.0}
    s.set_design(Design.model_validate(data))
    s.refine()
    view = s.ui.compare_view
    assert all(isinstance(r, str) for r in view.results.values())
    assert "not computable" in view.md.content
    for plot in (view.fn, view.stress):
        assert [ser.get("show", True) for ser in plot.handle.series[1:5]] == [False] * 4
        assert np.allclose(plot.stations, np.degrees(s.analysis.stations))
        assert all(np.isfinite(np.asarray(col, float)).all() for col in plot.handle.data)


def test_tabs_are_isolated_and_freed(app):
    def open_tab():
        before = set(app.sessions)
        t = FakeTab(app.port)
        assert wait_for(lambda: set(app.sessions) - before)
        (cid,) = set(app.sessions) - before
        return t, app.sessions[cid]

    (t1, s1), (t2, s2) = open_tab(), open_tab()
    s1.ui.controls["motion.lift_mm"].value = 30.0
    assert s1.design.motion.lift_mm == 30.0 and s2.design.motion.lift_mm == 15.0
    s1.ui.play_btn.value = True
    assert wait_for(lambda: s1.theta_deg > 1.0, 5.0)
    assert s2.theta_deg == 0.0
    n = len(app.sessions)
    t1.close()
    assert wait_for(lambda: len(app.sessions) == n - 1)
    assert s1.closed.is_set()
    assert wait_for(lambda: not any(t.is_alive() for t in s1.threads), 5.0)
    t2.close()
    assert wait_for(lambda: len(app.sessions) == n - 2)


@pytest.mark.parametrize("kind", ["flat_face", "knife_edge"])
def test_new_follower_kinds_render_and_offset(tab, kind):
    """The flat-faced tappet and the knife edge are drawn and animated; a single
    follower's axis offset is a live control (greyed out for double followers)."""
    s = tab
    s.ui.controls["follower.kind"].value = kind
    assert s.design.follower.kind.value == kind and s.error is None
    assert "face0" in s.view.nodes and "face1" not in s.view.nodes
    assert not s.ui.controls["follower.single_offset_mm"].disabled
    assert s.ui.controls["follower.face_radius_mm"].disabled
    assert s.ui.controls["follower.roller_radius_mm"].disabled
    s.ui.controls["follower.single_offset_mm"].value = 12.0
    assert s.design.follower.single_offset_mm == 12.0 and s.analysis.geo.stem_x < 0
    s.view.pose(len(s.analysis.theta) // 3)  # animate a frame
    s.ui.controls["follower.kind"].value = "double_concave"
    assert s.ui.controls["follower.single_offset_mm"].disabled


def test_a_multi_segment_program_loads_and_keeps_its_segments(tab):
    """The double-indexing preset is not rise-dwell-fall-dwell: the classic motion
    sliders leave (greyed, they had shown a stale program and taken typing), the panel
    says so, and editing another control keeps the segments."""
    s = tab
    s.load_preset("double_index")
    assert s.error is None and len(s.design.motion.segments) == 8
    classic = [h for p, h in s.ui.controls.items() if p.startswith("motion.")]
    assert len(classic) == 6 and not any(h.visible for h in classic)
    assert all(h.disabled for h in classic)
    s.ui.controls["motion.rise_deg"].value = 33.0  # a client may still send one: unused
    assert s.error is None and len(s.design.motion.segments) == 8
    assert "Program of 8 segments" in s.ui.low_dwell_md.content
    s.ui.controls["cam.base_radius_mm"].value = 90.0
    assert s.design.cam.base_radius_mm == 90.0 and len(s.design.motion.segments) == 8
    assert len(s.analysis.stations) == 12
    s.load_preset("paper_example")
    assert all(h.visible and not h.disabled for h in classic)


def test_a_dropdown_value_outside_the_presets_reads_no_file(tab, tmp_path):
    """viser does not check a dropdown's value against its options: '../..' names and
    absolute paths are refused before any lookup, and the message is escaped."""
    s = tab
    before = s.design
    (tmp_path / "x.json").write_text(before.model_dump_json())
    for name in ("../../x", str(tmp_path / "x"), "<b id=inj>x</b>"):
        s.load_preset(name)
        assert s.design == before and "No preset" in s.ui.files_md.content
        assert "<b" not in s.ui.files_md.content


def test_upload_guard_refuses_on_the_declared_and_the_received_size(app, tab):
    """app.uploads: a transfer declaring more than the cap is never buffered; one whose
    parts pass the cap (or their own declared size) is dropped at the first such part.
    The tab says why."""
    from viser import _messages

    from app import uploads

    s = tab
    gui_api = s.client.gui  # the tab's own GUI API holds its upload button
    button = s.ui.upload_btn._impl.uuid
    cid = s.client.client_id
    big = _messages.FileTransferStartUpload(
        source_component_uuid=button,
        transfer_uuid="t-big",
        filename="<i>big</i>.json",
        mime_type="application/json",
        part_count=50,
        size_bytes=45_000_000,
    )
    # the refusal runs on viser's event loop: it must not wait for a busy tab's lock
    # (a review: a refusal during a heavy analysis stalled the server for all tabs)
    held, release = threading.Event(), threading.Event()

    def busy():
        with s.lock:
            held.set()
            release.wait(10)

    worker = threading.Thread(target=busy)
    worker.start()
    held.wait(5)
    t0 = time.perf_counter()
    gui_api._handle_file_transfer_start(cid, big)
    waited = time.perf_counter() - t0
    release.set()
    worker.join()
    assert waited < 2.0  # (not the 10 s the lock is held)
    assert "t-big" not in gui_api._current_file_upload_states
    assert "refused" in s.ui.files_md.content and "<i>" not in s.ui.files_md.content
    assert "this one 45,000,000 bytes" in s.ui.files_md.content
    liar = _messages.FileTransferStartUpload(
        source_component_uuid=button,
        transfer_uuid="t-liar",
        filename="liar.json",
        mime_type="application/json",
        part_count=1,
        size_bytes=10,
    )
    gui_api._handle_file_transfer_start(cid, liar)
    assert "t-liar" in gui_api._current_file_upload_states
    part = _messages.FileTransferPart(
        source_component_uuid=button, transfer_uuid="t-liar", part_index=0, content=b"x" * 600_000
    )
    gui_api._handle_file_transfer_part(cid, part)
    assert "t-liar" not in gui_api._current_file_upload_states  # dropped, not buffered
    assert uploads.MAX_UPLOAD_BYTES == 1_000_000
    # a review announced 2^62 parts of a "1 MB" file and sent 300,000 empty ones, each
    # kept: a transfer announces at most one part per MIN_PART_BYTES, and an empty
    # part is never kept
    from dataclasses import replace

    many = replace(liar, transfer_uuid="t-many", part_count=2**62, size_bytes=1_000_000)
    gui_api._handle_file_transfer_start(cid, many)
    assert "t-many" not in gui_api._current_file_upload_states
    assert "announced 4,611,686,018,427,387,904 parts" in s.ui.files_md.content
    two = replace(many, transfer_uuid="t-two", part_count=2)  # as a browser sends it
    gui_api._handle_file_transfer_start(cid, two)
    state = gui_api._current_file_upload_states["t-two"]
    for i in range(5):
        gui_api._handle_file_transfer_part(
            cid,
            _messages.FileTransferPart(
                source_component_uuid=button, transfer_uuid="t-two", part_index=i, content=b""
            ),
        )
    assert state["parts"] == {}
    gui_api._current_file_upload_states.pop("t-two")


def test_browser_storage_values_are_untrusted():
    from app import storage
    from camcore.model import design_to_json

    d = load_preset("paper_example")
    assert storage.parse_working(design_to_json(d)) == d
    for junk in (None, "", "{", "[]", '{"cam": {"base_radius_mm": -1}}', "x" * 2_000_000):
        assert storage.parse_working(junk) is None
    many = {f"n{i}": design_to_json(d) for i in range(50)}
    many[""] = "x"
    many["y" * 100] = "x"
    saved = storage.parse_saved(__import__("json").dumps(many))
    assert len(saved) == storage.MAX_SAVED and all(0 < len(k) <= 60 for k in saved)
    assert storage.parse_saved("[1, 2]") == {} and storage.parse_saved("nonsense") == {}
    # what this version cannot read is kept, bounded (a review: 1.75 million tiny
    # entries had held 158 MB in the tab and cost 12 s at every save)
    text = __import__("json").dumps(many)
    unread = storage.unread_entries(text, storage.parse_saved(text))
    assert list(unread) == [f"n{i}" for i in range(20, 40)]  # the first MAX_SAVED
    flood = "{" + ",".join(f'"k{i}": "v"' for i in range(300_000)) + "}"
    assert len(storage.unread_entries(flood, {})) == storage.MAX_SAVED
    assert storage.unread_entries('{"x": {"format": 9}, "y": 5}', {}) == {
        "x": {"format": 9},
        "y": 5,
    }
    big = '{"x": "%s", "y": 1}' % ("z" * (storage.MAX_DESIGN_BYTES + 1))
    assert storage.unread_entries(big, {}) == {"y": 1}
    assert storage.parse_saved("{" + " " * storage.MAX_SAVED_CHARS + "}") == {}
    full = {f"n{i}": "{}" for i in range(storage.MAX_SAVED)}
    with pytest.raises(ValueError, match="delete one first"):
        storage.with_saved(full, "another", d)
    assert "n0" in storage.with_saved(full, "n0", d)  # replacing one is fine
    with pytest.raises(ValueError, match="1 to 60"):
        storage.with_saved({}, "   ", d)


def test_a_part_that_breaks_a_limit_comes_with_a_warning(tab, downloads):
    """A maker's review downloaded the G-code of a cusped cam and read only 'Sent': the
    download now says which limits it breaks and, for a cusp, not to make it as it is
    (the CLI's note), and the G-code carries it in its header. A valid design's does
    not."""
    s = tab
    s.ui.download_btns["toolpath"].value = True
    assert "Before you make it" not in s.ui.files_md.content
    assert "edited" not in s.ui.files_md.content  # the preset as shipped
    assert b"WARNING" not in downloads[-1][1]
    data = load_preset("paper_example").with_kind("single_concave").model_dump(mode="json")
    data["motion"].update(lift_mm=12.0, rise_deg=65.0)
    data["cam"]["speed_rpm"] = 100.0
    s.set_design(Design.model_validate(data))
    assert "curvature_convex" in {v.code for v in s.analysis.violations}
    for kind, quick in (("toolpath", False), ("stl", True)):
        if quick:
            s.ui.quick_stl_btn.value = True
        else:
            s.ui.download_btns[kind].value = True
        shown = s.ui.quick_md.content if quick else s.ui.files_md.content
        assert "Before you make it" in shown and "curvature\\_convex" in shown  # (escaped)
        assert "Do not make it as it is" in shown
        assert "(edited from preset paper\\_example: motion.segments, cam.speed\\_rpm)" in shown
    gcode = downloads[-2][1].decode()
    assert "(WARNING: the design breaks" in gcode and "Do not make it as it is)" in gcode


def test_a_keyway_is_edited_and_removed_in_the_tab(tab, downloads):
    """A maker opened a keyed design and could neither remove the keyway nor resize
    it: with the bore set to 0 the tab stayed invalid ('a keyway needs a bore') with
    no control to clear it. The keyway's width and depth are controls."""
    s = tab
    c = s.ui.controls
    c["cam.bore_diameter_mm"].value = 30.0
    c["cam.keyway_width_mm"].value = 8.0
    c["cam.keyway_depth_mm"].value = 3.3
    assert s.error is None and s.design.cam.keyway_width_mm == 8.0
    s.ui.download_btns["stl"].value = True
    assert "Sent" in s.ui.files_md.content and "no shaft bore" not in s.ui.files_md.content
    mesh = trimesh.load(io.BytesIO(downloads[-1][1]), file_type="stl")
    inner = mesh.vertices[np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 1]) < 20]
    assert inner[:, 1].max() == pytest.approx(15.0 + 3.3)  # the slot on the +Y ray
    c["cam.bore_diameter_mm"].value = 0.0
    assert s.error is not None and "keyway" in s.error
    c["cam.keyway_width_mm"].value = 0.0  # the way out: no keyway ...
    assert "give both, or neither" in s.error  # ... the message says how
    c["cam.keyway_depth_mm"].value = 0.0
    assert s.error is None and s.design.cam.bore_diameter_mm == 0.0
    # a D-flat bore instead (a maker's review): the 3D cam is cut again with it
    c["cam.bore_diameter_mm"].value = 5.0
    before = np.asarray(s.view.nodes["cam"].vertices).copy()
    c["cam.bore_flat_mm"].value = 4.5
    assert s.error is None and s.design.cam.bore_flat_mm == 4.5
    after = np.asarray(s.view.nodes["cam"].vertices)
    inner = after[np.hypot(after[:, 0], after[:, 1]) < 0.003]  # [m]
    assert inner[:, 1].max() == pytest.approx(0.002, abs=1e-6)  # the flat, 2 mm up +Y
    assert before.shape != after.shape or not np.allclose(before, after)


def test_an_export_that_fails_unexpectedly_says_so(tab, downloads, monkeypatch):
    """A defect in an exporter had left the button silent: the tab says what failed."""
    from dataclasses import replace

    from camcore import export

    def broken(a):
        raise RuntimeError("boom <b>")

    monkeypatch.setitem(export.EXPORTS, "stl", replace(export.EXPORTS["stl"], write=broken))
    tab.download("stl")
    assert not downloads
    md = tab.ui.files_md.content
    assert "Cannot export stl: an internal error (RuntimeError, in the server's log)" in md
    assert "boom" not in md


def test_download_names_say_which_design_they_hold(tab):
    from app.panels import file_stem

    s = tab
    stem = file_stem(s.design)
    # the name cut at a word (it had been "..._example_doubl-"), then the follower
    assert stem.startswith("chuang_hsu_chang_section_6_example-double_concave-")
    s.ui.controls["cam.base_radius_mm"].value = 85.0
    assert file_stem(s.design) != stem  # an edited design gets another name


def test_busy_port_is_an_error_that_says_so():
    """viser moves to the next port silently; camdesigner refuses and says why."""
    import socket
    import subprocess
    import sys

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen()
        port = sock.getsockname()[1]
        proc = subprocess.run(
            [sys.executable, "-m", "app.main", "--port", str(port)],
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert proc.returncode == 2 and f"port {port}" in proc.stderr and "busy" in proc.stderr


def test_a_port_just_left_by_a_stopped_server_is_free():
    """A server stopped while a tab was connected leaves its side of the connection in
    TIME_WAIT for ~60 s: a restart at once must not call the port busy (the server
    itself binds with SO_REUSEADDR); a listening port still is."""
    import socket

    from app.main import _port_free

    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]
    assert not _port_free("127.0.0.1", port)
    tab = socket.create_connection(("127.0.0.1", port))
    conn, _ = server.accept()
    conn.close()  # the server closes first: its side waits in TIME_WAIT
    server.close()
    tab.close()
    assert _port_free("127.0.0.1", port)


def test_a_table_edit_made_while_the_table_is_redrawn_counts(tab):
    """The session writing its values into the table (show) fires no edit; a user's
    edit arriving meanwhile on another thread counts, on the whole table as redrawn (a
    shared flag had dropped it; then a review found it read half old, half new rows, a
    351 deg program), unless the redraw wrote over that very widget: then the table
    shows what holds and the edit is dropped."""
    table = tab.ui.segments
    got: list[list[dict]] = []
    # (the session's handler is not what is tested here; it reads the table when the
    # edit's turn comes: here at once)
    table.on_change = lambda segs: got.append(table.current() if segs is None else segs)
    before = [g.model_dump(mode="json", exclude_none=True) for g in tab.design.motion.segments]
    shown = [dict(g) for g in before]
    shown[0]["angle_deg"], shown[1]["angle_deg"] = 90.0, 80.0  # written in place
    for row, value, counts in ((0, 55.0, True), (3, 55.0, False)):
        table.show(before)
        got.clear()
        inside, go = threading.Event(), threading.Event()
        writer = threading.Thread(target=table.show, args=(shown,))

        def hold(_e, writer=writer, inside=inside, go=go):  # held after row 1's write
            if threading.current_thread() is writer:
                inside.set()
                go.wait(5)

        table.rows[0]["angle"].on_update(hold)
        writer.start()
        assert inside.wait(5)
        widget = table.rows[row]["angle"]
        user = threading.Thread(target=lambda w=widget, v=value: setattr(w, "value", v))
        user.start()  # the user's edit, meanwhile: it waits for the redraw to end
        user.join(0.3)
        go.set()
        writer.join(5)
        user.join(5)
        table.rows[0]["angle"]._impl.update_cb.remove(hold)
        if counts:  # row 1, already redrawn: the edit, on the redrawn table
            assert got == [[{**shown[0], "angle_deg": 55.0}, *shown[1:]]]
        else:  # row 4, written over by the redraw: dropped, the screen shows the redraw
            assert got == [] and widget.value == shown[3]["angle_deg"]


def test_segment_values_past_the_boxes_are_refused_and_the_table_stays_whole(tab):
    """A hostile client's review: a lift of 5000 mm (past its box) left the table half
    built at the next move (viser refused the new box's start value): three of four
    rows, no Add button. And a NaN was dropped without a word (NaN != NaN read as an
    edit written over)."""
    s = tab
    table, good = s.ui.segments, s.design
    n_handles = len([h for r in table.rows for h in r.values()])
    table.rows[2]["lift"].value = 5000.0
    assert s.error is not None and "lift" in s.error and s.design == good
    table.act(3, "↑")  # rebuilds the rows: every one of them, and the Add button
    assert len(table.rows) == 4 and len(table._extra) == 2
    assert len([h for r in table.rows for h in r.values()]) == n_handles
    assert s.error is not None and s.design == good
    s.load_preset("paper_example")
    table.rows[0]["angle"].value = float("nan")
    assert s.error is not None and "angle" in s.error and s.design == load_preset("paper_example")


def test_segment_table_edits_the_program(tab):
    """The segment table (issue 10): rows follow the design; moving, adding, removing
    and editing rows re-analyses at once; a program that does not close says so and
    keeps the last valid design; the station buttons follow the program."""
    s = tab
    assert [r["kind"].value for r in s.ui.segments.rows] == ["rise", "dwell", "fall", "dwell"]
    # split the high dwell: shorten it and add a 0 deg dwell, then turn that into a
    # rise/fall pair by editing rows: first an invalid step (lifts do not close)
    s.ui.segments.act(4, "+")
    assert len(s.design.motion.segments) == 5 and len(s.ui.segments.rows) == 5
    s.ui.segments.rows[1]["angle"].value = 50.0  # the sum is 340: invalid, the design stays
    assert s.error is not None and "360" in s.error and len(s.design.motion.segments) == 5
    assert "340" in s.ui.segments.sums.content
    # another control's edit keeps the unfinished program (a review: it had snapped
    # back to the last valid one without a word) and the error with it
    s.ui.controls["cam.speed_rpm"].value = 900.0
    assert s.ui.segments.rows[1]["angle"].value == 50.0 and "340" in s.ui.segments.sums.content
    assert s.error is not None and "360" in s.error
    s.ui.segments.rows[4]["angle"].value = 20.0  # 360 again
    assert s.error is None and s.design.motion.segments[4].angle_deg == 20.0
    assert s.design.cam.speed_rpm == 900.0  # (the edit made meanwhile holds)
    s.ui.segments.rows[1]["kind"].value = "spin"  # a hostile value: refused, naming the field
    assert s.error is not None and "kind" in s.error
    s.ui.segments.rows[1]["kind"].value = "dwell"
    assert s.error is None
    # a dwell made a rise in place: its lift and law become editable (a review: they
    # stayed greyed, the program could not be finished), and greyed again as a dwell
    table = s.ui.segments
    row = table.rows[3]
    assert not (row["lift"].visible or row["law"].visible)  # a dwell has no lift, no law
    table.rows[3]["kind"].value = "rise"
    assert not table.rows[3]["lift"].disabled and not table.rows[3]["law"].disabled
    assert row["lift"].visible and row["law"].visible
    table.rows[3]["kind"].value = "dwell"
    assert table.rows[3]["lift"].disabled and table.rows[3]["law"].disabled
    assert not (row["lift"].visible or row["law"].visible)
    assert s.error is None
    # an error names the row as the table numbers it (from 1; the model counts from 0)
    fall = table.rows[2]["angle"].value
    table.rows[2]["angle"].value = 0.0
    assert "segments.2.angle_deg" in s.error and "segment 3 angle [°]" in s.ui.status.content
    table.rows[2]["angle"].value = fall
    assert s.error is None
    s.ui.segments.act(4, "↑")  # the new dwell before the low dwell... (4 -> 3)
    kinds = [g.kind.value for g in s.design.motion.segments]
    assert kinds == ["rise", "dwell", "fall", "dwell", "dwell"]
    assert s.design.motion.segments[3].angle_deg == 20.0
    s.ui.segments.act(3, "✕")  # 340 deg again: the table shows the edit, the design stays
    assert len(s.ui.segments.rows) == 4 and s.error is not None
    assert len(s.design.motion.segments) == 5
    s.load_preset("double_index")
    assert len(s.ui.segments.rows) == 8
    assert s.ui.stations_btn.options == tuple(str(i) for i in range(12))
    said = s.ui.stations_md.content  # each button's angle (a teacher's review)
    assert said.count("°") == 12 and f"11: {np.degrees(s.analysis.stations[11]):.1f}°" in said
    assert s.ui.stations_btn.hint is None  # (a hint covered the step buttons)
    s.goto_station("11")
    assert abs(s.theta_deg - 350.0) < 0.6
    s.goto_station("12")  # no such station: ignored
    assert abs(s.theta_deg - 350.0) < 0.6


def test_motion_per_second_curve(tab):
    """V, A and J also per second at the design speed (the issue 9 designer's view):
    the cycloid's peak velocity 2 h w / beta_r, and it follows the speed."""
    s = tab
    plot = next(c for c in s.ui.curves if c.title.startswith("Velocity, acceleration and jerk"))
    w = s.design.cam.speed_rpm * 2 * np.pi / 60
    h, beta = s.design.motion.lift_mm * 1e-3, np.radians(s.design.motion.rise_deg)
    assert np.nanmax(plot.handle.data[1]) == pytest.approx(2 * h * w / beta, rel=1e-3)
    s.ui.controls["cam.speed_rpm"].value = 600.0
    assert np.nanmax(plot.handle.data[1]) == pytest.approx(h * w / beta, rel=1e-3)


def test_running_machine_controls_and_curves(tab):
    """Issue 11 in the app: the elastic train switches on from 0 (rigid) to a stiffness,
    its dynamic jump is reported and shaded, the key numbers name the spring, jump speed,
    torque and wear, and back to 0 restores the rigid follower."""
    s = tab
    assert s.design.dynamics.train_stiffness_N_per_m is None
    assert s.ui.controls["dynamics.train_stiffness_N_per_m"].value == 0.0
    for text in ("spring rate min", "jump speed", "shaft torque", "wear depth max", "pitting life"):
        assert text in s.ui.summary_md.content
    s.ui.controls["dynamics.damping_ratio"].value = 0.02
    s.ui.controls["dynamics.train_stiffness_N_per_m"].value = 2e4
    assert s.design.dynamics.train_stiffness_N_per_m == 2e4
    assert "dynamic_jump" in {v.code for v in s.analysis.violations}
    train_plot = next(c for c in s.ui.curves if "elastic train" in c.handle.title)
    assert np.max(train_plot.shade) > 0  # the jump is shaded on its curve
    elastic, rigid = np.array(train_plot.handle.data[2]), np.array(train_plot.handle.data[1])
    assert np.nanmin(elastic) < 0 < np.nanmin(rigid)
    s.ui.controls["dynamics.train_stiffness_N_per_m"].value = 0.0
    assert s.design.dynamics.train_stiffness_N_per_m is None and s.analysis.train is None


def test_no_pressure_angle_construction_where_nothing_touches(tab):
    """A high dwell too short for both faces (Eq. 28 broken): where no face touches, the
    text says so and no pressure-angle construction pretends otherwise."""
    s = tab
    data = s.design.model_dump(mode="json")
    data["motion"]["high_dwell_deg"] = 3.0
    s.set_design(Design.model_validate(data))
    assert "contact_lost" in {v.code for v in s.analysis.violations}
    s.ui.angle_slider.value = 101.0
    assert f"In contact: <b>{panels.UNSUPPORTED}</b>" in s.ui.where_md.content
    assert not s.view.nodes["phi"].visible and not s.view.nodes["phi_label"].visible
    s.ui.angle_slider.value = 50.0
    assert s.view.nodes["phi"].visible


def test_camera_presets_front_by_default_and_a_close_up_that_follows(tab):
    s = tab
    cam = s.client.camera
    assert s.camera_view == "Front" and cam.fov < math.radians(10)  # a long, flat lens
    assert cam.position[0] == cam.look_at[0] > 0  # straight on, the cam left of the panel
    s.ui.view_btns.value = "Contact close-up"
    s.ui.angle_slider.value = 50.0
    S = float(np.interp(np.radians(50), s.analysis.theta, s.analysis.prog.S))
    assert cam.look_at[1] == pytest.approx(s.analysis.geo.r_b + S, abs=1e-4)
    s.set_camera_view("../../etc")  # anything else a client sends is ignored
    assert s.camera_view == "Contact close-up"
    s.ui.view_btns.value = "3D"
    assert cam.fov > math.radians(30)


@pytest.mark.parametrize("kind", ["double concave", "single roller"])
def test_labels_read_on_a_projector_in_every_preset_view(tab, kind):
    """At 720 px high (a projector) the labels (S1, S2, I23 = Q, phi) stand 18 px in
    each preset view: sized as a share of r_b they were 8 px in the Front view."""
    tab.ui.controls["follower.kind"].value = kind
    names = ["q_label", "phi_label", "label0"] + (["label1"] if kind == "double concave" else [])
    for view in ("Front", "Contact close-up", "3D"):
        tab.ui.view_btns.value = view
        cam = tab.client.camera
        seen = 2 * np.linalg.norm(np.subtract(cam.position, cam.look_at)) * math.tan(cam.fov / 2)
        for name in names:
            px = tab.view.nodes[name].font_scene_height / seen * 720
            assert 17 < px < 19, (view, name, px)


def test_markers_fit_the_close_up(tab):
    """In every preset view the contact points and the force arrows are sized to what
    the view shows (a teacher's review: in the close-up the spheres were 60 px across
    and a 137 N arrow ran off the top of the frame); the Front view keeps its own."""
    from app.scene import ARROW_SHARE, CONTACT_SHARE

    tab.goto_station(1)  # the cycle's largest force nearby
    sizes = {}
    for view in ("Front", "Contact close-up"):
        tab.ui.view_btns.value = view
        cam = tab.client.camera
        seen = 2 * np.linalg.norm(np.subtract(cam.position, cam.look_at)) * math.tan(cam.fov / 2)
        r = tab.view.nodes["contact0"].radius
        seg = np.asarray(tab.view.nodes["forces"].points)
        longest = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).max()
        assert r <= CONTACT_SHARE * seen * 1.001 and longest <= ARROW_SHARE * seen * 1.001
        sizes[view] = r
    assert sizes["Contact close-up"] < 0.5 * sizes["Front"]


def test_the_camera_reframes_when_the_cam_changes_size_a_lot(tab):
    """r_b 80 -> 5000 mm had left the camera inside the cam (a magenta blob); a small
    change keeps the user's own view."""
    cam = tab.client.camera
    tab.ui.controls["follower.kind"].value = "single roller"  # (|r_f| < 5000 mm)
    cam.position = (0.01, 0.2, 1.5)  # the user moved the camera
    tab.ui.controls["cam.base_radius_mm"].value = 90.0
    assert tab.design.cam.base_radius_mm == 90.0 and tuple(cam.position) == (0.01, 0.2, 1.5)
    tab.ui.controls["cam.base_radius_mm"].value = 5000.0
    assert tab.design.cam.base_radius_mm == 5000.0
    assert cam.position[2] > 30 * 1.5  # framed again, from far enough away
    far = cam.position
    tab.ui.controls["cam.base_radius_mm"].value = 80.0
    assert cam.position[2] < far[2] / 20
    near = cam.position  # a third larger (95 -> 135 mm): off a projected screen at 2x
    tab.ui.controls["cam.base_radius_mm"].value = 120.0
    assert cam.position[2] > 1.15 * near[2]  # framed again (it had stayed put)


def test_stations_diagram_in_the_view_tab(tab):
    """The paper's Fig. 4 for the design on screen: one panel per station, drawn on
    request and replaced on the next request."""
    s = tab
    assert s.ui.stations_fig_md.content == ""
    s.ui.stations_fig_btn.value = True  # click
    img = s.ui.stations_img
    # three panels a row, 1200 px wide: full size it fits a 1280 x 720 projector
    assert img is not None and img.image.ndim == 3 and img.image.shape[1] == 1200
    assert img.image.shape[0] <= 700
    assert "are below" in s.ui.stations_fig_md.content  # where to look (it can be off screen)
    assert "θ₃ = βᵣ + βₕ − 2ψₕ: the paper prints + 2ψₕ" in s.ui.stations_fig_md.content
    assert img.image.std() > 10  # something is drawn
    s.ui.stations_fig_btn.value = True
    assert s.ui.stations_img is img  # the same element, a new picture
    # the same geometry at another speed: its captions' F_N and sigma_H would be stale
    # (a teacher's review saw 136.8 N printed under a design of 161.4 N)
    s.ui.controls["cam.speed_rpm"].value = 1500.0
    assert s.design.cam.speed_rpm == 1500.0 and s.ui.stations_img is None
    assert s.ui.stations_fig_md.content == ""
    s.ui.stations_fig_btn.value = True
    img = s.ui.stations_img
    s.ui.controls["follower.kind"].value = "single roller"  # the diagram would be stale
    assert s.design.follower.kind.value == "single_roller" and s.ui.stations_img is None
    assert s.ui.stations_fig_md.content == ""
    s.ui.stations_fig_btn.value = True  # drawn again for the design on screen
    assert s.ui.stations_img is not None and s.ui.stations_img is not img
    assert "θ₃" not in s.ui.stations_fig_md.content  # a single follower: no such station


def test_the_touching_face_is_highlighted_and_the_idle_one_dimmed(tab):
    from app.scene import FOLLOWER_RGB, IDLE_FACE_RGB

    s = tab
    s.ui.angle_slider.value = 50.0  # the rise: S1 drives, S2 is off the cam
    assert tuple(s.view.nodes["face0"].color) == FOLLOWER_RGB
    assert tuple(s.view.nodes["face1"].color) == IDLE_FACE_RGB
    s.goto_station(2)  # both on the high-dwell arc
    assert tuple(s.view.nodes["face1"].color) == FOLLOWER_RGB


def test_explore_tab_sweeps_maps_and_loads_a_pareto_design(tab):
    """The Explore tab (issue 12): a small sweep of base radius x offset over the four
    followers runs in the background, shows the map, offers the Pareto front of cam
    size vs. stress, and loads a design of it into the tab."""
    from app.layout import NARROW_PANEL_PX

    s, e = tab, tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (70.0, 90.0), (25.0, 35.0)
    assert e.y_range.label == "y from, to [mm]"
    e.x.value = "Rise β_r [°]"
    assert e.x_range.label == "x from, to [°]"  # the range says its field's unit
    e.x.value = "Base radius r_b [mm]"
    e.x_range.value = (70.0, 90.0)
    e.steps.value = 2
    e.all_kinds.value = True
    e.fig_a.value, e.fig_b.value = (
        "cam size R (high-dwell radius)",
        "max contact stress σ_H",
    )
    sent: list[dict] = []  # the points analysed
    real = e._analyst.sweep_chunk
    e._analyst.sweep_chunk = lambda base, pts, *a: sent.extend(pts) or real(base, pts, *a)
    e.run_btn.value = True  # click
    assert wait_for(lambda: "on the Pareto front" in e.progress.content, 120.0), e.progress.content
    # single followers ignore the offset e: 16 points make 12 designs
    assert "**16 points**, 12 distinct designs" in e.progress.content
    assert len(sent) == 12  # ... so each of them is analysed once
    # the valid ones counted both ways (a review compared the app's distinct designs
    # with camcore sweep's rows, and found them apart)
    rows, seen, distinct_ok = e._ran.rows, set(), 0
    for r in rows:  # a design once: its kind and, for a double follower, its offset
        key = (
            r["grid.follower.kind"],
            r["grid.follower.offset_mm"] if "double" in r["grid.follower.kind"] else None,
            r["grid.cam.base_radius_mm"],
        )
        distinct_ok += r["valid"] and key not in seen
        seen.add(key)
    points_ok = sum(r["valid"] for r in rows)
    assert points_ok > distinct_ok
    assert f": {distinct_ok} valid ({points_ok} of the points), " in e.progress.content
    assert e.image is not None and e.image.image.shape[2] == 3
    # the map is drawn for the panel (twice its pixels): again when the panel widens
    assert e.image.image.shape[1] == 2 * NARROW_PANEL_PX
    s.ui.wide_box.value = True
    wide = 2 * s.panel_px
    assert s.panel_px > NARROW_PANEL_PX
    assert wait_for(lambda: e.image.image.shape[1] == wide, 30.0), e.image.image.shape
    s.ui.wide_box.value = False
    assert wait_for(lambda: e.image.image.shape[1] == 2 * NARROW_PANEL_PX, 30.0)
    offers = e.front_dd.options
    assert offers and offers[0].startswith("1. ") and not e.load_btn.disabled
    # the paper's claim over this little design space: the lowest stress is a concave face
    assert any("concave" in o for o in offers)
    e.front_dd.value = offers[-1]
    e.load_btn.value = True
    assert wait_for(lambda: s.design.cam.base_radius_mm in (70.0, 90.0), 10.0)
    assert "Loaded design" in e.progress.content
    # another design of the same front, of another follower, loads at the first click (a
    # review: the first load's swept values and its follower's name read as "edits")
    kind = offers[-1].split(". ", 1)[1].split(",")[0]
    other = next(o for o in offers if o.split(". ", 1)[1].split(",")[0] != kind)
    e.front_dd.value = other
    e.load_btn.value = True
    assert "Loaded design" in e.progress.content, e.progress.content
    assert s.design == sweep.design_at(e._ran.base, e._offers[other])
    # an edit after the sweep: loading would undo it, so the first click says so
    s.ui.controls["motion.lift_mm"].value = 25.0
    e.front_dd.value = offers[0]
    e.load_btn.value = True
    assert "earlier design" in e.progress.content
    assert "Lift h \\[mm\\]: 15.0 → 25.0" in e.progress.content  # (markdown-escaped)
    assert s.design.motion.lift_mm == 25.0
    e.load_btn.value = True  # the second click loads it
    assert wait_for(lambda: s.design.motion.lift_mm == 15.0, 10.0)
    loaded = s.design
    e.load("not an offer")  # a hostile value loads nothing, and says so
    assert s.design == loaded and "Choose a design of the front first" in e.progress.content
    e.x.value = e.y.value
    e.run_btn.value = True
    assert "two different fields" in e.progress.content


def test_explore_map_follows_a_width_change_during_its_drawing(tab, monkeypatch):
    """The panel widens while the sweep's map is being drawn: the map on show is then
    drawn again for the new width (not left at the width the drawing started with)."""
    e = tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (70.0, 90.0), (25.0, 35.0)
    e.steps.value, e.all_kinds.value = 2, False
    real, widths = e._analyst.explore_png, []

    def widening(*args):  # the tab's Wide panel ticked as the first map is drawn
        widths.append(args[-1])
        if len(widths) == 1:
            e.set_width(900)
        return real(*args)

    monkeypatch.setattr(e._analyst, "explore_png", widening)  # (the app's analyst)
    e.run_btn.value = True
    assert wait_for(lambda: widths[-1:] == [900] and e.image is not None, 60.0), widths
    assert wait_for(lambda: e.image.image.shape[1] == 1800, 30.0)
    assert wait_for(lambda: not e._map_busy, 10.0) and widths == [384, 900]
    e.set_width(900)  # no change: nothing drawn again
    assert widths == [384, 900] and not e._map_busy


def test_explore_says_what_it_runs_and_why_points_are_no_designs(tab, monkeypatch):
    """A designer's review: a step count out of range ran another count, a motion field
    of a segment program made every point "not a design" without a reason, points the
    model refuses said nothing of why, a cancel before the first designs left the last
    map loadable, and a loaded design took the sweep's value of a field its follower
    ignores."""
    s, e = tab, tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Roller radius r_c [mm]"
    e.all_kinds.value = False
    e.steps._impl.value = 0  # a box accepts what the slider does not
    e.run_btn.value = True
    assert "Steps per field: a whole number from 2 to 15" in e.progress.content
    e.steps.value = 2
    e.x_range.value, e.y_range.value = (-50.0, -10.0), (5.0, 6.0)  # no base radius < 0
    e.run_btn.value = True
    assert wait_for(lambda: "Pareto front" in e.progress.content, 60.0), e.progress.content
    text = e.progress.content
    assert "0 valid" in text and "No valid design" in text
    # one reason, though each point's message quotes its own value
    assert "2 are no design at all; the commonest reason (2), e.g.: cam.base\\_radius" in text
    e.cancel()  # nothing runs: nothing to cancel, and the summary stays
    assert e.progress.content == text
    # a concave face ignores the roller radius: its front designs keep the design's own
    assert s.design.follower.kind.value == "double_concave"
    e.x_range.value = (70.0, 90.0)
    e.run_btn.value = True
    assert wait_for(lambda: not e.load_btn.disabled, 60.0), e.progress.content
    assert all(", r_c –" in o for o in e.front_dd.options), e.front_dd.options
    roller = s.design.follower.roller_radius_mm
    e.load_btn.value = True
    assert wait_for(lambda: "Loaded design" in e.progress.content, 10.0)
    assert s.design.follower.roller_radius_mm == roller
    # cancelled before the first chunk: the last results go, not left as this run's
    cancel_first = lambda base, points: e._cancel.set() or list(range(len(points)))  # noqa: E731
    monkeypatch.setattr(e._analyst, "same_designs", cancel_first)  # (the app's analyst)
    e.run_btn.value = True
    assert wait_for(lambda: "Cancelled before" in e.progress.content, 10.0)
    assert e.image is None and e.load_btn.disabled and e.front_dd.options == ("–",)
    # a program of segments: its classic fields are no field of it, not offered, and
    # a client that sends one anyway is refused
    s.load_preset("double_index")
    assert "Lift h [mm]" not in e.x.options
    e.x.value = "Lift h [mm]"
    e.run_btn.value = True
    assert "Choose two different fields" in e.progress.content


def test_explore_hands_its_sweep_over_as_csv_and_as_a_spec(tab, downloads, monkeypatch):
    """After a sweep the tab sends its rows as CSV (the columns of camcore sweep's table)
    and as a SPEC that camcore sweep runs to the very same rows (--fast: the batched
    core, as the tab ran); before one, and after a cancelled one, it sends nothing."""
    import csv

    from camcore import sweep

    e = tab.ui.explore
    assert e.csv_btn.disabled and e.spec_btn.disabled
    e.download("csv")  # (a forged click: nothing on show)
    assert not downloads and "Run a sweep first" in e.files_md.content
    e.x.value, e.y.value = "Base radius r_b [mm]", "Roller radius r_c [mm]"
    e.x_range.value, e.y_range.value = (70.0, 85.0), (-5.0, 12.0)  # r_c < 0: no design
    e.steps.value, e.all_kinds.value = 3, True
    e.run_btn.value = True
    assert wait_for(lambda: not e.csv_btn.disabled, 120.0), e.progress.content
    rows = e._ran.rows
    assert len(rows) == 36 and any(r.get("error") for r in rows)
    e.csv_btn.value = True
    name, data = downloads[-1]
    assert name.startswith(panels.file_stem(tab.design)) and name.endswith("-sweep.csv")
    assert f"Sent **{panels.esc(name)}**" in e.files_md.content
    table = list(csv.DictReader(io.StringIO(data.decode())))
    assert len(table) == 36
    for got, want in zip(table, rows, strict=True):
        assert set(got) >= set(want)
        for k, v in want.items():  # floats exactly (repr), the rest as text
            assert got[k] == ("" if v is None else repr(v) if isinstance(v, float) else str(v))
    e.spec_btn.value = True
    name, data = downloads[-1]
    said = e.files_md.content
    assert name.endswith("-sweep.json") and f"camcore sweep {name} --out" in said
    assert "--fast` for these rows" in said
    spec = sweep.parse_spec(data)
    again = sweep.run_chunk(spec.base, list(spec.points()), fast=True)
    assert again == rows  # the same designs, figures and verdicts, in the same order
    # a figure that needs the profile: the tab ran the full analysis (no geometric
    # check), and the SPEC says the flag that gives those rows (--fast has no wear)
    e.steps.value, e.all_kinds.value = 2, False
    e.fig_c.value = "max wear depth"
    e.run_btn.value = True
    assert wait_for(lambda: not e._thread.is_alive() and len(e._ran.rows) == 4, 120.0)
    e.spec_btn.value = True
    assert "--no-verify` for these rows" in e.files_md.content, e.files_md.content
    spec = sweep.parse_spec(downloads[-1][1])
    assert sweep.run_chunk(spec.base, list(spec.points()), verify=False) == e._ran.rows
    # cancelled after its first chunk: the files say so
    e.fig_c.value, e.steps.value, e.all_kinds.value = "none", 5, True
    real = e._analyst.sweep_chunk
    first_only = lambda *a: e._cancel.set() or real(*a)  # noqa: E731
    monkeypatch.setattr(e._analyst, "sweep_chunk", first_only)
    e.run_btn.value = True
    assert wait_for(lambda: not e._thread.is_alive() and "cancelled" in e.progress.content, 60.0)
    n = len(e._ran.rows)
    assert 0 < n < 100 and e._ran.total == 100
    e.csv_btn.value = True
    assert f"cancelled after {n} of its 100 points" in e.files_md.content
    e.spec_btn.value = True
    assert "for all 100 points (the sweep was cancelled" in e.files_md.content
    # a sweep cancelled before its first designs has nothing to send
    cancel_first = lambda base, points: e._cancel.set() or list(range(len(points)))  # noqa: E731
    monkeypatch.setattr(e._analyst, "same_designs", cancel_first)  # (the app's analyst)
    e.run_btn.value = True
    assert wait_for(lambda: "Cancelled before" in e.progress.content, 10.0)
    assert e.csv_btn.disabled and e.spec_btn.disabled and e._ran is None


def test_explore_review_names_fields_and_refuses_early(tab):
    """A designer's review of Explore: the front's list names each field and figure
    ("r_b 70", "σ_H 52.4 MPa"); a signed field at 0 gets a range either side of it; a
    motion field of a segment program is refused when chosen (its box had kept the
    last field's range); and with the input invalid nothing runs (it had swept around
    the last valid design without a word)."""
    s, e = tab, tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (70.0, 90.0), (25.0, 35.0)
    e.steps.value, e.all_kinds.value = 2, False
    e.run_btn.value = True
    assert wait_for(lambda: not e.load_btn.disabled, 60.0), e.progress.content
    first = e.front_dd.options[0]
    assert re.match(r"1\. double concave, r_b \d+, e \d+ → R [\d.]+ mm, σ_H ", first), first
    assert wait_for(lambda: not e._thread.is_alive(), 30.0)  # (its map drawn)
    # the least cam size of the (one) follower swept: the front's first design
    least = first.split(" → ")[0][3:] + " → " + first.split(" → ")[1].split(",")[0]
    assert f"Least cam size R (high-dwell radius): {panels.esc(least)}" in e.progress.content
    e.y.value = "Axis offset e_s (single) [mm]"  # 0 in the paper example
    assert tuple(e.y_range.value) == (-10.0, 10.0)
    s.ui.controls["cam.base_radius_mm"].value = -5.0  # invalid input
    e.run_btn.value = True
    assert "input is invalid" in e.progress.content and not e._thread.is_alive()
    s.load_preset("double_index")  # a program of segments: no classic fields offered
    assert not {"Lift h [mm]", "Rise β_r [°]", "Fall β_f [°]"} & set(e.y.options)
    before = (e.y_range.label, tuple(e.y_range.value))
    e.y.value = "Rise β_r [°]"  # (a forged value: the range box is left alone)
    assert (e.y_range.label, tuple(e.y_range.value)) == before  # (not relabelled in °)


def test_explore_sweeps_a_segment_angle_against_the_dwell_that_takes_up_the_turn(
    tab, downloads, monkeypatch
):
    """A program made of segments offers each rise's and fall's angle (a designer's
    review: no field of an indexer's program could be swept in the tab); a dwell takes
    up the turn (camcore sweep's "balance"), the tab says which, each row has its
    angle, the SPEC runs to the same rows, and a front design loads whole. A classic
    program offers them no more."""
    from camcore import sweep

    s, e = tab, tab.ui.explore
    s.load_preset("double_index")  # rise 60, dwell 50, fall 60, dwell 10, twice
    assert "Segment 1 angle, rise [°]" in e.x.options and "Segment 7 angle, fall [°]" in e.y.options
    assert not any(o.startswith("Segment 2 ") for o in e.x.options)  # (a dwell)
    e.x.value, e.y.value = "Segment 1 angle, rise [°]", "Base radius r_b [mm]"
    assert tuple(e.x_range.value) == (42.0, 78.0) and e.x_range.label == "x from, to [°]"
    assert "Segment 2 (a dwell of 50°) takes up the turn" in e.progress.content
    e.x_range.value, e.steps.value, e.all_kinds.value = (40.0, 120.0), 3, False
    e.run_btn.value = True
    assert wait_for(lambda: not e.csv_btn.disabled, 120.0), e.progress.content
    rows = e._ran.rows
    rise, dwell = "grid.motion.segments.0.angle_deg", "grid.motion.segments.1.angle_deg"
    assert sorted({(r[rise], r[dwell]) for r in rows}) == [
        (40.0, 70.0),
        (80.0, 30.0),
        (120.0, -10.0),
    ]
    said = "Segment 2, a dwell, took up the turn (β2 in the list)"
    assert wait_for(lambda: said in e.progress.content, 30.0), e.progress.content
    assert all(r["error"] for r in rows if r[rise] == 120.0)  # no angle left: no design
    assert not any(r["error"] for r in rows if r[rise] < 120.0)
    e.spec_btn.value = True
    spec = sweep.parse_spec(downloads[-1][1])
    assert spec.balance == "motion.segments.1.angle_deg"
    assert sweep.run_chunk(spec.base, list(spec.points()), fast=True) == rows
    first = e.front_dd.options[0]
    assert re.match(r"1\. double concave, β1 \d+, r_b [\d.]+, β2 \d+ → ", first), first
    assert wait_for(lambda: not e._thread.is_alive(), 30.0)  # (its map drawn)
    e.load(first)
    segs = s.design.motion.segments
    beta1 = float(first.split("β1 ")[1].split(",")[0])
    assert segs[0].angle_deg == beta1 and sum(g.angle_deg for g in segs) == 360.0
    other = e.front_dd.options[-1]
    assert other != first
    e.load(other)  # the swept angles are the sweep's, not edits: no warning, one click
    assert e.progress.content.startswith("Loaded design"), e.progress.content
    assert f"r_b {s.design.cam.base_radius_mm:.4g}," in other
    # the design read, not the options last offered, says what a field is (a review:
    # a segment field left on a classic design had raised IndexError, or swept
    # segment 7 of a 4-segment program)
    e.x.value = "Segment 7 angle, fall [°]"
    with s.lock:
        kept, s.design = s.design, load_preset("paper_example")
        e._suggest(e.x, e.x_range, "x")  # (no error)
        assert e._job() is None and "Choose two different fields" in e.progress.content
        s.design = kept
    s.load_preset("paper_example")  # a classic program: its own fields, no segments
    assert not any(o.startswith("Segment ") for o in e.x.options)
    # ... and the sweep of the indexer's fields is gone, map, list and line
    assert e.image is None and e.load_btn.disabled and e.front_dd.options == ("–",)
    assert e.progress.content == "" and e._ran is None
    assert (e.x.value, e.y.value) == ("Offset e (double) [mm]", "Base radius r_b [mm]")
    assert tuple(e.x_range.value) == (7.0, 13.0)  # around the paper's e = 10 mm
    e.apply_setup({"x": "Segment 1 angle, rise [°]", "x_range": [1, 2]})  # kept, now stale
    assert e.x.value == "Offset e (double) [mm]" and tuple(e.x_range.value) == (7.0, 13.0)
    # a program without a dwell offers no segment's angle: nothing could take up the turn
    data = s.design.model_dump(mode="json")
    rise = {"kind": "rise", "angle_deg": 90, "lift_mm": 10}
    twice = [rise, {**rise, "kind": "fall"}]
    data["motion"] = {"segments": twice + twice}  # (not rise-dwell-fall-dwell)
    s.set_design(Design.model_validate(data))
    assert not any(o.startswith(("Segment ", "Lift h", "Rise β_r")) for o in e.x.options)
    s.load_preset("double_index")  # a kept setup names a segment's field: restored
    e.apply_setup({"x": "Segment 3 angle, fall [°]", "x_range": [50, 70]})
    assert (e.x.value, tuple(e.x_range.value)) == ("Segment 3 angle, fall [°]", (50.0, 70.0))
    # another kind of program loaded while the sweep runs: its results are dropped
    real, loaded = e._analyst.sweep_chunk, []

    def meanwhile(*a):
        if not loaded:
            loaded.append(s.load_preset("paper_example"))
        return real(*a)

    monkeypatch.setattr(e._analyst, "sweep_chunk", meanwhile)
    e.steps.value = 2
    e.run_btn.value = True
    assert wait_for(lambda: not e._thread.is_alive(), 60.0)
    assert "another kind of program now" in e.progress.content, e.progress.content
    assert e._ran is None and e.image is None and e.load_btn.disabled


def test_explore_sweeps_the_spring_against_the_speed(tab, monkeypatch):
    """The spring rate and the cam width are Explore fields too: the paper example's
    spring (k_min 2800 N/m at 1200 rpm, jump speed 1855 rpm) over speed x rate shows
    the follower leaving the cam where the spring is weak and the cam fast, and
    holding where it is stiff and slow."""
    e = tab.ui.explore
    e.x.value, e.y.value = "Cam speed [rpm]", "Spring rate k [N/m]"
    e.x_range.value, e.y_range.value = (600.0, 2400.0), (1000.0, 9000.0)
    e.steps.value, e.all_kinds.value = 3, False
    rows: list[dict] = []
    real = e._analyst.sweep_chunk
    monkeypatch.setattr(  # (the app's analyst: undone after the test)
        e._analyst,
        "sweep_chunk",
        lambda base, pts, *a: rows.extend(real(base, pts, *a)) or rows[-len(pts) :],
    )
    e.run_btn.value = True
    assert wait_for(lambda: "Pareto front" in e.progress.content, 120.0), e.progress.content
    assert "**9 points**, 9 distinct designs" in e.progress.content
    by = {(r["grid.cam.speed_rpm"], r["grid.dynamics.spring_rate_N_per_m"]): r for r in rows}
    assert "jump" in by[2400.0, 1000.0]["violations"]
    assert by[600.0, 9000.0]["valid"]


def test_explore_with_a_profile_figure_runs_the_full_analysis(tab):
    """Wear needs the profile, which the batched core does not build: a sweep that
    ranks by wear runs one full analysis per design, and its front shows wear."""
    e = tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (75.0, 85.0), (25.0, 30.0)
    e.steps.value, e.all_kinds.value = 2, False
    e.fig_a.value, e.fig_b.value = "cam size R (high-dwell radius)", "max wear depth"
    e.run_btn.value = True
    assert wait_for(lambda: "on the Pareto front" in e.progress.content, 120.0), e.progress.content
    assert e.front_dd.options and all("µm" in o for o in e.front_dd.options)


def test_explore_ranks_by_a_third_figure(tab):
    """A third figure joins the Pareto front: each offered design lists three values,
    the front of three holds the design least in the third; the same figure twice is
    refused."""
    from camcore.explore import FIGURES

    e = tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (60.0, 100.0), (10.0, 30.0)
    e.steps.value, e.all_kinds.value = 3, True
    e.fig_a.value, e.fig_b.value = "cam size R (high-dwell radius)", "max contact stress σ_H"
    e.fig_c.value = "cam size R (high-dwell radius)"
    e.run_btn.value = True
    assert "two or three different figures" in e.progress.content
    e.fig_c.value = "max pressure angle"
    rows: list[dict] = []
    real = e._analyst.sweep_chunk
    e._analyst.sweep_chunk = lambda base, pts, *a: (
        rows.extend(real(base, pts, *a)) or rows[-len(pts) :]
    )
    e.run_btn.value = True
    assert wait_for(lambda: "on the Pareto front" in e.progress.content, 120.0), e.progress.content
    offers = e.front_dd.options
    assert offers and all(o.count(" mm") >= 1 and "MPa" in o and "°" in o for o in offers)
    pa = FIGURES["pressure_angle"]
    least = min(pa.get(r) for r in rows if r["valid"])
    assert any(f"{least:.4g} °" in o for o in offers)


def test_explore_ranges_start_around_the_design_on_screen(app, monkeypatch):
    """A tab with no kept Explore setup proposes its two fields' ranges around the
    design it opens on, +-30 % (a designer's review: fixed 60-110 mm beside an 18 mm
    cam); a kept setup keeps its own."""
    from app import storage

    data = load_preset("paper_example").model_dump()
    data["cam"]["base_radius_mm"], data["follower"]["offset_mm"] = 30.0, 5.0
    stored = {storage.WORKING_KEY: design_to_json(Design.model_validate(data))}
    with restored_tab(app, monkeypatch, stored) as s:
        e = s.ui.explore
        assert s.design.cam.base_radius_mm == 30.0
        assert e.x.value == "Base radius r_b [mm]" and tuple(e.x_range.value) == (21.0, 39.0)
        assert e.y.value == "Offset e (double) [mm]" and tuple(e.y_range.value) == (3.5, 6.5)
    kept = {
        **stored,
        storage.EXPLORE_KEY: json.dumps({"x": "Base radius r_b [mm]", "x_range": [50, 60]}),
    }
    with restored_tab(app, monkeypatch, kept) as s:
        assert tuple(s.ui.explore.x_range.value) == (50.0, 60.0)


def test_explore_setup_round_trips_and_refuses_junk(tab):
    """The Explore setup kept in the browser: what setup() gives, apply_setup() puts
    back (the kept range wins over the one a restored field proposes); entries a
    tampered storage could hold are ignored one by one; the stored text is bounded."""
    from app import storage

    e = tab.ui.explore
    e.x.value, e.y.value = "Cam speed [rpm]", "Roller radius r_c [mm]"
    e.x_range.value, e.y_range.value = (900.0, 1500.0), (5.0, 12.5)
    e.steps.value, e.all_kinds.value = 5, False
    e.fig_c.value = "max pressure angle"
    kept = e.setup()
    e.x.value, e.y.value = "Lift h [mm]", "Rise β_r [°]"
    e.steps.value, e.all_kinds.value, e.fig_c.value = 9, True, "none"
    e.apply_setup(storage.parse_setup(__import__("json").dumps(kept)))
    assert e.setup() == kept
    e.x.value = "Lift h [mm]"  # a setup kept under the field's earlier label
    e.apply_setup({**kept, "x": "Speed [rpm]"})
    assert e.setup() == kept
    junk = {
        "x": "<b>not a field</b>",
        "x_range": ["a", 3],
        "y_range": [float("nan"), 1.0],
        "steps": 1000,
        "all_kinds": "yes",
        "figures": ["max wear depth", "nonsense", "none"],
    }
    e.apply_setup(junk)
    figures = ["max wear depth", kept["figures"][1], "none"]  # "none" is an option of 3
    assert e.setup() == {**kept, "figures": figures}
    for bad in ("[1, 2]", "nonsense", "{" + " " * storage.MAX_SETUP_BYTES + "}", None):
        assert storage.parse_setup(bad) is None
    e.apply_setup([1, 2])  # not a dict: nothing changes
    before = e.setup()
    for hostile in (
        {"x": [], "y": {}},  # unhashable where a label belongs
        {"x": "a field renamed since", "x_range": [1.0, 2.0]},  # a range for no field
        {"figures": [[], {}, None]},
    ):
        e.apply_setup(hostile)
        assert e.setup() == before, hostile
    rpm = tab.design.cam.speed_rpm  # a kept field with a refused range: the range the
    proposed = [round(0.7 * rpm, 1), round(1.3 * rpm, 1)]  # field proposes (±30 %)
    for hostile in (
        {"x": before["x"], "x_range": [10**400, 5]},  # no float holds it
        {"x": before["x"], "x_range": "59"},  # a string is no pair of numbers
    ):
        e.x_range.value = tuple(before["x_range"])
        e.apply_setup(hostile)
        assert e.setup() == {**before, "x_range": proposed}, hostile
    assert storage.parse_setup("[" * 2000 + "]" * 2000) is None  # nesting, under 4 kB
    e.steps.value = 4.0  # a client's float: kept as the integer it is
    e.apply_setup({"steps": e.setup()["steps"]})
    assert e.steps.value == 4


def test_a_bad_kept_setup_costs_nothing_else(app, monkeypatch):
    """A setup the browser kept that the panel cannot take (a tampered storage, a
    setup of a later version) is ignored: the kept design is still restored and the
    tab goes on saving its work (the restore thread had died and saved nothing)."""
    from app import storage
    from app.explore import ExplorePanel

    kept = load_preset("paper_example").model_copy(update={"name": "my kept cam"})
    stored = {storage.WORKING_KEY: design_to_json(kept), storage.EXPLORE_KEY: '{"x": []}'}
    writes: list[str] = []
    monkeypatch.setattr(storage.BrowserStore, "read", lambda self, key: stored.get(key))
    monkeypatch.setattr(storage.BrowserStore, "write", lambda self, key, v: writes.append(key))

    def broken(self, data):
        raise RuntimeError("a setup this version cannot apply")

    for apply in (ExplorePanel.apply_setup, broken):
        monkeypatch.setattr(ExplorePanel, "apply_setup", apply)
        before = set(app.sessions)
        t = FakeTab(app.port)
        try:
            assert wait_for(lambda b=before: set(app.sessions) - b)
            (s,) = [app.sessions[c] for c in set(app.sessions) - before]
            s._restorer.join(10)
            assert s.design.name == "my kept cam" and s._persist
            s.ui.explore.steps.value = 4  # and the setup is kept from now on
            assert storage.EXPLORE_KEY in writes
        finally:
            t.close()
        writes.clear()


def test_a_resized_view_resizes_the_wide_panel_and_reframes(app, monkeypatch):
    """A window made smaller had left the wide panel 1000 px wide over most of the cam.
    A camera message that keeps the pose and changes the size is a resize: the wide
    panel takes its share of the new width, and the preset view, if not moved, is
    framed again; after an orbit the user's view stays."""
    from viser._gui_handles import MainPanelHandle

    from app.layout import wide_panel_px

    widths: list[float] = []
    monkeypatch.setattr(MainPanelHandle, "set_width", lambda self, w: widths.append(w))
    before = set(app.sessions)
    t = FakeTab(app.port)
    try:
        assert wait_for(lambda: set(app.sessions) - before)
        (s,) = [app.sessions[c] for c in set(app.sessions) - before]
        s.ui.wide_box.value = True
        assert widths == [wide_panel_px(1000)]
        preset = s._preset_pose
        t.camera(preset[:3], preset[3:], 1000, 700)  # the browser's echo of the view
        assert wait_for(lambda: s._seen is not None and s._seen[0] == preset)
        t.camera(preset[:3], preset[3:], 1600, 900)  # the window grows
        assert wait_for(lambda: len(widths) == 2 and s._preset_pose != preset)  # reframed
        assert widths[-1] == wide_panel_px(1600)
        moved = (0.02, 0.2, 1.5)
        t.camera(moved, (0.0, 0.1, 0.0), 1600, 900)  # the user orbits
        assert wait_for(lambda: s._seen is not None and s._seen[0][:3] == moved)
        t.camera(moved, (0.0, 0.1, 0.0), 1200, 700)  # then shrinks the window
        assert wait_for(lambda: len(widths) == 3)
        assert widths[-1] == wide_panel_px(1200)
        assert tuple(s.client.camera.position) == pytest.approx(moved)  # their view stays
    finally:
        t.close()


def test_wide_panel_toggle(tab, monkeypatch):
    """The wide panel asks viser for the width (62 % of the viewer, at most 1000 px) and
    gives the panel its own back (the browser test sees the contents follow)."""
    from viser._gui_handles import MainPanelHandle

    from app.layout import NARROW_PANEL_PX, wide_panel_px

    widths: list[float] = []
    monkeypatch.setattr(MainPanelHandle, "set_width", lambda self, w: widths.append(w))
    narrow_x = tab.client.camera.position[0]
    tab.ui.wide_box.value = True
    wide_x = tab.client.camera.position[0]  # the mechanism moves left of the wider panel
    tab.ui.wide_box.value = False
    assert widths == [wide_panel_px(tab.client.camera.image_width), NARROW_PANEL_PX]
    assert wide_x > narrow_x > 0 and tab.client.camera.position[0] == narrow_x
    assert [wide_panel_px(w) for w in (0, 600, 1000, 1920)] == [793, 384, 620, 1000]


def test_explore_drops_a_sweep_of_another_program_published_meanwhile(tab, monkeypatch):
    """A review: the sweep checked that the design on screen was still the same kind of
    program, then published; a preset of another kind loaded in between found the sweep
    still running and left its results, so the old program's designs stayed offered,
    loadable, with their map. The check and the publish are one step, and a change of
    fields drops the results of other fields already published."""
    s, e = tab, tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (70.0, 90.0), (25.0, 35.0)
    e.steps.value, e.all_kinds.value = 2, False
    old_fields = dict(e._fields)
    real = type(e)._put_image
    loader: list[threading.Thread] = []

    def publish_while_a_preset_loads(self, png):
        if not loader:  # the user loads an indexer (a program of segments) right now
            t = threading.Thread(target=s.load_preset, args=("double_index",))
            t.start()
            loader.append(t)  # (started first: the test joins it once it is listed)
            # its fields offered meanwhile (the old code: at once; now that waits for
            # this publish to end, and then drops what was published)
            wait_for(lambda: e._fields != old_fields, 2)
        return real(self, png)

    monkeypatch.setattr(type(e), "_put_image", publish_while_a_preset_loads)
    e.run_btn.value = True
    assert wait_for(lambda: bool(loader), 120)
    loader[0].join(30)
    assert wait_for(lambda: not e._thread.is_alive(), 30)
    assert s.design.motion.classic is None  # the indexer on screen
    assert e.load_btn.disabled and e.image is None and e.front_dd.options == ("–",)


def test_a_closed_tab_s_sweep_draws_no_map(app):
    """A review: a tab closed mid-sweep still had its Pareto front and map computed, in
    the background worker all tabs share."""
    before = set(app.sessions)
    t = FakeTab(app.port)
    assert wait_for(lambda: set(app.sessions) - before)
    (cid,) = set(app.sessions) - before
    e = app.sessions[cid].ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (60.0, 100.0), (20.0, 40.0)
    e.steps.value, e.all_kinds.value = 6, True
    calls: list[str] = []
    real_png, real_chunk = e._analyst.explore_png, e._analyst.sweep_chunk

    class Spy:  # this tab's view of the shared analyst
        same_designs = app.analyst.same_designs

        def sweep_chunk(self, *a):
            calls.append("chunk")
            return real_chunk(*a)

        def explore_png(self, *a):
            calls.append("png")
            return real_png(*a)

    e._analyst = Spy()
    e.run_btn.value = True
    assert wait_for(lambda: "chunk" in calls, 60)
    t.close()  # the user closes the browser tab mid-sweep
    assert wait_for(lambda: cid not in app.sessions, 10)
    e._thread.join(60)
    assert "png" not in calls and not e._thread.is_alive()


def test_explore_refuses_hostile_ranges(tab):
    e = tab.ui.explore
    e.x_range._impl.value = ("a", 3)  # what a hostile client could send
    e.run_btn.value = True
    assert "two finite numbers" in e.progress.content
    e.x_range._impl.value = (float("nan"), 3.0)
    e.run_btn.value = True
    assert "two finite numbers" in e.progress.content
    for span in ((-1e308, 1e308), (1e308, 1.7e308), (0, 2e9)):  # finite, but absurd
        e.progress.content = ""
        e.x_range._impl.value = span
        e.run_btn.value = True
        assert "two finite numbers within ±1e+09" in e.progress.content, span
    # one number twice, or two its steps cannot tell apart: said, not a dead sweep (a
    # sweep's grid now refuses repeated values)
    for span, says in (((70.0, 70.0), "two different numbers"), ((70.0, 70.0 + 1e-14), "twice")):
        e.progress.content = ""
        e.x_range._impl.value = span
        e.run_btn.value = True
        assert says in e.progress.content, span


def test_a_typed_speed_or_angle_shows_what_the_animation_takes(tab):
    """A hostile client's speed that is no finite number changes nothing; an app
    review's typed speed of 1000 stayed in the box while the cam kept its old speed, a
    0 froze Play, and a typed angle of 400 stayed in the box beside theta = 40 deg (the
    browser later cut it to 360: the cam jumped to 0). A speed is brought into the
    slider's range, and the box shows the speed and the angle taken."""
    tab.ui.speed_slider.value = 90.0
    assert tab.speed == 90.0
    for bad in (float("nan"), float("inf")):
        tab.ui.speed_slider._impl.value = bad  # (as viser keeps a client's value)
        tab._set_speed(bad)
        assert tab.speed == 90.0 and tab.ui.speed_slider.value == 90.0
    tab._set_speed("fast")
    assert tab.speed == 90.0
    for typed, taken in ((1000.0, 360.0), (0.0, 5.0), (-5.0, 5.0), (45.0, 45.0)):
        tab.ui.speed_slider.value = typed
        assert tab.speed == taken and tab.ui.speed_slider.value == taken
    for typed, taken in ((400.0, 40.0), (-30.0, 330.0), (1e6, 280.0), (123.4, 123.4)):
        tab.ui.angle_slider.value = typed
        assert tab.theta_deg == pytest.approx(taken)
        assert tab.ui.angle_slider.value == pytest.approx(taken)


def test_the_wear_curve_reaches_the_wear_maximum_of_the_key_numbers(tab):
    """The wear plot shows the cam point's total (both faces' passes) beside each face's
    pass: its peak is the maximum Key numbers report (a reviewer saw 0.11 on the plot
    and 0.139 in the numbers)."""
    import re

    s = tab
    plot = next(c for c in s.ui.curves if c.handle.title.startswith("Cam wear"))
    total, face = np.nanmax(plot.handle.data[1]), np.nanmax(plot.handle.data[2])
    shown = re.search(r"wear depth max \(Archard\) \| ([0-9.]+) µm", s.ui.summary_md.content)
    assert shown is not None
    reported = float(shown.group(1))  # the key number as the user reads it (4 decimals)
    assert abs(total - reported) <= 5e-5 and face < 0.9 * reported  # one pass falls short


def test_the_design_name_is_edited_in_the_tab_and_names_the_downloads(tab, downloads):
    """An edited design can be named (a preset's name no longer labels every edit of
    it); the name is the user's text: escaped where shown, made safe in file names,
    and bounded by the model (200 characters)."""
    s = tab
    name = s.ui.controls["name"]
    assert name.value == s.design.name
    name.value = "Press <b>cam</b> 3"
    assert s.design.name == "Press <b>cam</b> 3" and s.error is None
    s.ui.download_btns["stl"].value = True
    assert downloads[-1][0].startswith("press_b_cam_b_3-")  # panels.slug
    assert "<b>cam</b>" not in s.ui.files_md.content
    name.value = "x" * 201
    assert s.error is not None and "name" in s.ui.status.content
    assert s.design.name == "Press <b>cam</b> 3"


def test_while_playing_the_slider_and_the_line_under_it_agree(tab):
    """The animation updates the angle slider and the text under it in the same frames
    (a reviewer saw 147.7 on the slider beside 'θ = 143.1°')."""
    s = tab
    for n in range(1, 30):  # frames driven by hand, without the ticker
        s.frame(0.033, n)
        if n % 3 == 0:
            assert f"θ = {s.ui.angle_slider.value:.1f}°" in s.ui.where_md.content, n


def test_pause_at_stations_stops_on_each_station_then_goes_on(tab):
    """A teacher's pause: a step that would pass a station stops on it (the line under
    the slider says what happens there), stays PAUSE_AT_STATION_S, then goes on; off,
    the animation runs through."""
    from app.layout import PAUSE_AT_STATION_S

    s = tab
    s.ui.angle_slider.value = 95.0  # station 1 (the rise ends) is at 100 deg
    s.ui.pause_box.value = True
    s.frame(0.2, 1)  # 45 deg/s: 9 deg, past 100
    assert s.theta_deg == pytest.approx(100.0) and "at station 1" in s.ui.where_md.content
    assert f"‖ paused {PAUSE_AT_STATION_S:g} s at station 1" in s.ui.where_md.content
    assert s.ui.angle_slider.value == 100.0
    steps = int(PAUSE_AT_STATION_S / 0.1)
    for n in range(steps):  # held for the pause
        s.frame(0.1, n)
        assert s.theta_deg == pytest.approx(100.0)
    s.frame(0.1, steps)  # (the last of the pause, or already on)
    if s.theta_deg == pytest.approx(100.0):
        s.frame(0.1, steps + 1)
    assert s.theta_deg == pytest.approx(104.5)  # on again, short of station 2
    assert "paused" not in s.ui.where_md.content
    # the line drops "paused" on the first step after a stop, whatever the step's
    # number (a review: only every third step rewrote it, and it lingered)
    s._held, s._resumed = 0.05, False
    s._goto(100.0)  # stopped at station 1, and said
    assert "paused" in s.ui.where_md.content
    s.frame(0.1, 31)  # the stop ends ...
    s.frame(0.1, 32)  # ... and the cam moves on a step that is not a third one
    assert s.theta_deg == pytest.approx(104.5) and "paused" not in s.ui.where_md.content
    s.frame(0.1, steps + 2)  # the next step would pass station 2: it stops there
    assert s.theta_deg == pytest.approx(math.degrees(s.analysis.stations[2]))
    s.ui.pause_box.value = False
    s.ui.angle_slider.value = 95.0
    s.frame(0.2, 1)
    assert s.theta_deg == pytest.approx(104.0)  # through station 1


def test_dropdowns_show_words_and_take_them(tab):
    """The follower and law dropdowns show words ("double concave", "3-4-5 polynomial"),
    not identifiers; a word picks its value, an identifier is taken as it is, and
    anything else a client sends is refused by the model with its reason."""
    s = tab
    kind, law = s.ui.controls["follower.kind"], s.ui.controls["motion.rise_law"]
    assert kind.value == "double concave" and "single roller" in kind.options
    assert "3-4-5 polynomial" in law.options and "poly_345" not in law.options
    kind.value = "single roller"
    assert s.design.follower.kind.value == "single_roller" and s.error is None
    law.value = "3-4-5 polynomial"
    assert s.design.motion.rise_law.value == "poly_345"
    kind.value = "double_roller"  # an identifier still works (scripts, tests)
    assert s.design.follower.kind.value == "double_roller"
    kind.value = "<b>tri-roller</b>"
    assert s.error is not None and "<b>tri-roller</b>" not in s.ui.status.content
    assert s.design.follower.kind.value == "double_roller"
    # the segment table's law boxes alike (they had shown "poly_345")
    kind.value = "double concave"
    row = s.ui.segments.rows[0]
    assert row["law"].value == "3-4-5 polynomial" and "poly_4567" not in row["law"].options
    row["law"].value = "modified sine"
    assert s.design.motion.segments[0].law.value == "modified_sine" and s.error is None
    assert s.ui.controls["motion.rise_law"].value == "modified sine"
    row["law"].value = "<i>sine</i>"  # anything else: refused by the model, escaped
    assert s.error is not None and "<i>sine</i>" not in s.ui.status.content
    assert s.design.motion.segments[0].law.value == "modified_sine"


def _inside_any(points: np.ndarray, meshes) -> bool:
    """Whether any of the XY ``points`` lies in the XY shadow of one of the meshes."""
    for m in meshes:
        tri = np.asarray(m.vertices)[np.asarray(m.faces)][:, :, :2]  # (T, 3, 2)
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        d = (b[:, 1] - c[:, 1]) * (a[:, 0] - c[:, 0]) + (c[:, 0] - b[:, 0]) * (a[:, 1] - c[:, 1])
        ok = np.abs(d) > 1e-18  # triangles seen edge-on cast no shadow
        a, b, c, d = a[ok], b[ok], c[ok], d[ok]
        p = points[:, None, :]
        w1 = (
            (b[:, 1] - c[:, 1]) * (p[..., 0] - c[:, 0])
            + (c[:, 0] - b[:, 0]) * (p[..., 1] - c[:, 1])
        ) / d
        w2 = (
            (c[:, 1] - a[:, 1]) * (p[..., 0] - c[:, 0])
            + (a[:, 0] - c[:, 0]) * (p[..., 1] - c[:, 1])
        ) / d
        if np.any((w1 > 0) & (w2 > 0) & (1 - w1 - w2 > 0)):
            return True
    return False


@pytest.mark.parametrize("kind", ["double_concave", "single_concave", "double_roller", "flat_face"])
def test_the_pressure_angle_label_is_clear_of_the_follower(tab, kind):
    """The φ label of the pressure-angle construction stands on the cam, not on the
    follower (a teacher's close-up showed it over the S1 pad): its box, about 0.55 em per
    character, never overlaps the follower's parts where they are at that angle."""
    from app.scene import follower_parts

    s = tab
    s.ui.controls["follower.kind"].value = kind
    a = s.analysis
    parts = [m for name, (m, _) in follower_parts(a).items() if name != "guide"]
    lab = s.view.nodes["phi_label"]
    views = ("Front", "Contact close-up")  # (labels of two sizes: scene.label_height)
    for view, deg in itertools.product(
        views, (0.0, 30.0, 50.0, 99.0, 101.0, 120.0, 200.0, 240.0, 300.0)
    ):
        s.ui.view_btns.value = view
        s.ui.angle_slider.value = deg
        k = s.view.k
        x, y, _ = lab.position
        h = lab.font_scene_height
        half_w = 0.55 * h * len(lab.text) / 2
        u, v = np.meshgrid(np.linspace(-half_w, half_w, 15), np.linspace(-h / 2, h / 2, 5))
        box = np.column_stack([x + u.ravel(), y - float(a.prog.S[k]) + v.ravel()])
        assert not _inside_any(box, parts), (kind, view, deg, lab.text)


def test_a_rejected_kept_range_is_proposed_around_the_restored_design(app, monkeypatch):
    """A kept Explore field whose kept range is refused gets the range the panel
    proposes (±30 %) around the restored design's value, not the default design's (the
    setup had been applied before the design was restored)."""
    from app import storage

    kept = load_preset("paper_example")
    data = kept.model_dump(mode="json")
    data["cam"]["base_radius_mm"] = 120.0
    data["motion"]["lift_mm"] = 20.0
    setup = {"x": "Base radius r_b [mm]", "x_range": "junk", "y": "Lift h [mm]"}
    stored = {
        storage.WORKING_KEY: design_to_json(Design.model_validate(data)),
        storage.EXPLORE_KEY: __import__("json").dumps(setup),
    }
    with restored_tab(app, monkeypatch, stored) as s:
        assert s.design.cam.base_radius_mm == 120.0
        e = s.ui.explore
        assert e.x.value == "Base radius r_b [mm]"  # the default field: no change fired
        assert tuple(e.x_range.value) == (84.0, 156.0)  # 0.7 and 1.3 x 120 mm
        assert tuple(e.y_range.value) == (14.0, 26.0)  # around the kept 20 mm lift


def test_a_cutter_that_gouges_is_said_before_the_download(tab, downloads):
    """A cutter too large for the cam's concave flank had been found only when the
    G-code was downloaded: the still tab's check says so in the status panel (with the
    largest cutter that fits, the download's own words), and a cutter that fits clears
    it."""
    s = tab
    data = load_preset("paper_example").with_kind("single_roller").model_dump(mode="json")
    data["cam"].update(base_radius_mm=40.0, cutter_diameter_mm=190.0)
    data["motion"].update(lift_mm=30.0, rise_deg=80.0)
    data["limits"]["max_pressure_angle_deg"] = 45.0
    s.set_design(Design.model_validate(data))
    assert not s.analysis.violations  # a valid design: only its cutter is wrong
    assert "⚠ G-code" not in s.ui.status.content  # the fast path does not know yet
    s.refine()
    status = s.ui.status.content
    assert "⚠ G-code:" in status and "a 190 mm cutter would gouge" in status
    s.ui.download_btns["toolpath"].value = True
    refusal = s.ui.files_md.content
    assert "gouge" in refusal and "always fits" in refusal
    s.ui.controls["cam.cutter_diameter_mm"].value = 20.0
    assert "⚠ G-code" not in s.ui.status.content  # the next design: not said before checked
    s.refine()
    assert "⚠ G-code" not in s.ui.status.content and s.verified
    # a pass depth the G-code cannot take is said too (a rule of that export only: the
    # design stays valid and its other files download)
    s.ui.controls["cam.pass_depth_mm"].value = 0.01
    s.refine()
    assert not s.analysis.violations
    assert "⚠ G-code:" in s.ui.status.content and "more than 100 passes" in s.ui.status.content


def test_a_new_follower_kind_renames_the_follower_the_name_mentions(tab, downloads):
    """A teacher's review: after switching the paper's example to a single roller, its
    name '... (double concave faces)' stayed on the downloads. The name follows the
    kind (its box too), unless the user wrote a name of their own."""
    s = tab
    s.ui.controls["follower.kind"].value = "single_roller"
    assert s.design.name == "Chuang, Hsu & Chang, Section 6 example (single roller)"
    assert s.ui.controls["name"].value == s.design.name
    s.ui.controls["cam.base_radius_mm"].value = 85.0  # the next edit keeps it
    assert s.design.name.endswith("(single roller)") and s.design.cam.base_radius_mm == 85.0
    s.ui.controls["name"].value = "Feeder cam"
    s.ui.controls["follower.kind"].value = "double_roller"
    assert s.design.name == "Feeder cam"


def test_the_curves_mark_the_stations_and_the_angle_now(tab):
    """A teacher's review: the curves had only the 'θ now' line, so a class could not
    find station 2 or 3 on the F_N or stress curves. Each plot has a dashed line at each
    station and the 'θ now' line, as vertical spikes on their own scale."""
    from app.plots import station_axes

    s = tab
    s.goto_station(3)
    stations = np.degrees(s.analysis.stations)
    for c in s.ui.curves:
        data = [np.asarray(col, float) for col in c.handle.data]
        x, st, now = data[0], data[-2], data[-1]
        assert np.all(np.diff(x) >= 0)  # still one x axis, in order
        np.testing.assert_allclose(np.sort(x[st == 2.0]), np.sort(stations), atol=1e-4)
        np.testing.assert_allclose(x[now == 2.0], [stations[3]], atol=1e-4)
        assert c.handle.series[-2]["label"] == "stations"
        low, high = c.handle.axes[-2:]  # numbered above the plot (a later review)
        assert (low, high) == station_axes(stations) and low["side"] == high["side"] == 0
        # (1, 2 and 3, 4 are 7.4 deg apart: two rows, each number over its line)
        assert low["values"] == ["0", "1", "3", "5"] and high["values"] == ["2", "4"]
    S = np.asarray(s.ui.curves[0].handle.data[1], float)  # S stays a curve through them
    x = np.asarray(s.ui.curves[0].handle.data[0], float)
    k = int(np.argmin(np.abs(x - stations[2])))
    assert S[k] == pytest.approx(s.design.motion.lift_mm, abs=1e-3)  # the high dwell


def test_two_axis_plots_share_the_level_of_zero(tab):
    """V and A on one plot: their axes' zeros at the same height (the ranges are set so;
    uPlot alone ranged each axis apart)."""
    s = tab
    va = next(c for c in s.ui.curves if len(c._scales) > 4)  # x, shade, marker + 2 axes
    ranges = [v["range"] for k, v in va.handle.scales.items() if k in set(va._scale_of)]
    assert len(ranges) >= 2
    fracs = [-lo / (hi - lo) for lo, hi in ranges]
    assert max(fracs) - min(fracs) < 1e-9


def test_every_value_axis_keeps_room_for_its_ticks(tab):
    """A designer's review read one tick ("0" of J, "50" of F_t) on a plot ~95 px high:
    uPlot's default 30 px between ticks left no second round number in range. Every
    value axis (side 1 or 3) asks 20 px at most. (Configuration only: the ticks
    themselves are drawn on a canvas; a screenshot showed -10, 0, 10 and ±200,000.)"""
    for c in tab.ui.curves:
        values = [ax for ax in c.handle.axes if ax.get("side") in (1, 3)]
        assert values and all(ax.get("space", 30) <= 20 for ax in values), c.handle.title


def test_an_edit_during_a_rename_is_not_lost(tab, monkeypatch):
    """A review: the rename wrote the name box from inside the kind's callback, which
    took a new edit ticket, so a user's edit waiting on the lock was dropped as
    superseded (the box said 90 mm, the design stayed 80 mm). The session's own writes
    take no ticket."""
    import threading

    from app import session as session_module

    s = tab
    real = session_module.name_follows_kind
    other: list[threading.Thread] = []

    def rename_while_the_user_edits(*args):
        if other:  # (the user's own edit passes through here too: once is the race)
            return real(*args)
        before = s._tickets["controls"]
        t = threading.Thread(
            target=lambda: s.ui.controls["cam.base_radius_mm"].__setattr__("value", 90.0)
        )
        t.start()
        other.append(t)
        assert wait_for(lambda: s._tickets["controls"] > before)  # the edit took its ticket, waits
        return real(*args)

    monkeypatch.setattr(session_module, "name_follows_kind", rename_while_the_user_edits)
    s.ui.controls["follower.kind"].value = "single_roller"
    other[0].join(10)
    assert s.design.follower.kind == "single_roller" and s.design.name.endswith("(single roller)")
    assert s.design.cam.base_radius_mm == 90.0


def test_a_burst_of_table_edits_or_button_clicks_costs_one_analysis(tab, monkeypatch):
    """A review: the program table's edits and the buttons that replace the design took
    no turns, so 40 law changes cost 37 analyses and 30 preset clicks 30, and while they
    queued on the tab's lock another tab waited 44 s for its connection. Now the newest
    of a burst is the one made, and the design on screen is not analysed again."""
    s = tab
    analysed: list = []
    real = s.analyst.fast
    monkeypatch.setattr(s.analyst, "fast", lambda d: analysed.append(d) or real(d))

    def burst(calls) -> None:
        threads = [threading.Thread(target=c) for c in calls]
        with s.lock:  # the tab is busy while the burst arrives
            for t in threads:
                t.start()
            assert wait_for(lambda: len(threads) <= sum(s._tickets.values()) - start)
        for t in threads:
            t.join(10)

    segs = [g.model_dump(mode="json") for g in s.design.motion.segments]
    edits = []
    for lift in np.linspace(10.0, 14.0, 20):
        program = [dict(g) for g in segs]
        program[0]["lift_mm"] = program[2]["lift_mm"] = float(lift)
        edits.append(lambda p=program: s.on_segments(p))
    start = sum(s._tickets.values())
    burst(edits)
    assert len(analysed) <= 2 and s.design.motion.segments[0].lift_mm == 14.0
    analysed.clear()
    start = sum(s._tickets.values())
    burst([lambda: s.load_preset("double_index")] * 20)
    assert len(analysed) == 1 and s.design == load_preset("double_index")
    analysed.clear()
    s.load_preset("double_index")  # the design on screen: said, not analysed again
    assert not analysed and "Loaded the preset" in s.ui.files_md.content


def test_a_tab_cannot_keep_many_uploads_unfinished(app, tab):
    """A review started 150 uploads of just under the cap and finished none: the server
    grew by 145 MB. A tab's unfinished uploads are capped (declared bytes), the
    refusal says why, and a file name is shown shortened."""
    from viser import _messages

    from app import uploads

    s = tab
    gui_api, button, cid = s.client.gui, s.ui.upload_btn._impl.uuid, s.client.client_id

    def start(i: int, name: str = "part.json") -> str:
        uid = f"t-{i}"
        gui_api._handle_file_transfer_start(
            cid,
            _messages.FileTransferStartUpload(
                source_component_uuid=button,
                transfer_uuid=uid,
                filename=name,
                mime_type="application/json",
                part_count=2,
                size_bytes=999_000,
            ),
        )
        return uid

    kept = [start(i) for i in range(uploads.MAX_IN_FLIGHT_BYTES // 999_000)]
    assert all(u in gui_api._current_file_upload_states for u in kept)
    extra = start(99, "x" * 900)
    assert extra not in gui_api._current_file_upload_states
    said = s.ui.files_md.content
    assert "are unfinished" in said and len(said) < 600  # the name shortened
    assert start(98, "x" * 10_000) not in gui_api._current_file_upload_states
    assert "name is too long" in s.ui.files_md.content
    assert "few kB" not in s.ui.files_md.content  # (an app review: read as too big)
    for uid in kept:  # and transfers that declare nothing count too (a second review)
        gui_api._current_file_upload_states.pop(uid)

    def empty(i: int) -> str:
        uid = f"z-{i}"
        gui_api._handle_file_transfer_start(
            cid,
            _messages.FileTransferStartUpload(
                source_component_uuid=button,
                transfer_uuid=uid,
                filename="z.json",
                mime_type="application/json",
                part_count=1,
                size_bytes=0,
            ),
        )
        return uid

    uids = [empty(i) for i in range(uploads.MAX_IN_FLIGHT + 3)]
    held = [u for u in uids if u in gui_api._current_file_upload_states]
    assert len(held) == uploads.MAX_IN_FLIGHT


def test_one_file_at_a_time_per_tab_and_made_outside_its_lock(tab, downloads, monkeypatch):
    """A review clicked *Report PDF* 50 times: 50 renders queued in the server and
    another tab's edit waited 24 s. A tab makes one file at a time (a second click says
    so at once), the reports in the background worker, outside the tab's lock: the tab
    can still be edited while its PDF is made."""
    import threading

    s = tab
    started, release = threading.Event(), threading.Event()

    said: list[str] = []

    def slow_document(kind, a):
        said.append(s.ui.files_md.content)  # what the tab shows while it is made
        started.set()
        assert release.wait(10)
        return b"%PDF-slow"

    monkeypatch.setattr(s.analyst, "document", slow_document)
    first = threading.Thread(target=s.download, args=("pdf",))
    first.start()
    assert started.wait(10)
    s.download("pdf")  # the second click, while the first is being made
    assert "one at a time" in s.ui.files_md.content
    s.ui.controls["motion.lift_mm"].value = 16.0  # the tab is not locked meanwhile
    assert s.design.motion.lift_mm == 16.0
    assert s._drawing.acquire(blocking=False)  # nor is the diagram (its own turn)
    s._drawing.release()
    release.set()
    first.join(10)
    assert downloads[-1][1] == b"%PDF-slow" and downloads[-1][0].endswith(".pdf")
    assert len([d for d in downloads if d[0].endswith(".pdf")]) == 1
    assert "Making the PDF report" in said[0]  # said at once: seconds on a busy server


def test_tampered_or_newer_storage_loses_nothing(app, monkeypatch):
    """A review: a deeply nested saved list killed the restore thread (RecursionError),
    after which no edit was ever kept; and a working design this version cannot open
    (one from a later version) was overwritten by the default design without a word.
    Now the bad list is ignored and never written back (a second review: a list that
    did not read must not be replaced), the tab keeps saving, and the unreadable design
    is set aside as it was, said in Files."""
    import json

    from app import storage

    newer = json.loads(design_to_json(load_preset("paper_example")))
    newer["schema_version"] = 3
    stored = {
        storage.WORKING_KEY: json.dumps(newer),
        storage.SAVED_KEY: "[" * 50_000 + "]" * 50_000,
    }
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, stored, writes) as s:
        assert s._persist and s._restorer is not None and not s._restorer.is_alive()
        assert writes[storage.UNREADABLE_KEY] == stored[storage.WORKING_KEY]
        assert storage.SAVED_KEY not in writes  # the list it could not read stays
        assert "cannot open" in s.ui.files_md.content and "newer" in s.ui.files_md.content
        s.ui.controls["motion.lift_mm"].value = 17.0  # and the tab keeps its work
        assert storage.parse_working(writes[storage.WORKING_KEY]).motion.lift_mm == 17.0


def test_a_number_no_float_holds_does_not_stop_the_tab_keeping_its_work(app, monkeypatch):
    """A security review: a stored design with a 400-digit width killed the restore
    thread (OverflowError while quoting the refused value), and from then on nothing was
    kept in that browser, with no message. It is now set aside like any unreadable
    design, and the tab keeps saving."""
    from app import storage

    bad = design_to_json(load_preset("paper_example")).replace(
        '"width_mm": 15.0', '"width_mm": ' + "9" * 400
    )
    assert "9" * 400 in bad
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {storage.WORKING_KEY: bad}, writes) as s:
        assert s._persist and writes[storage.UNREADABLE_KEY] == bad
        assert "cam.width\\_mm" in s.ui.files_md.content  # (escaped for Markdown)
        s.ui.controls["motion.lift_mm"].value = 17.0
        assert storage.parse_working(writes[storage.WORKING_KEY]).motion.lift_mm == 17.0


def test_a_set_aside_design_can_be_taken_out_of_the_browser(app, monkeypatch):
    """The working design this version could not open is set aside in the browser's
    storage; a button (shown only then, and on later visits while it is there) sends
    it back as the browser kept it, to open with the version that wrote it."""
    import json

    from app import storage

    newer = json.loads(design_to_json(load_preset("paper_example")))
    newer["schema_version"] = 3
    text = json.dumps(newer)
    with restored_tab(app, monkeypatch, {}) as s:  # nothing set aside: no button
        assert not s.ui.aside_btn.visible
    wide = "\U0001f600" * (storage.MAX_DESIGN_BYTES // 2)  # characters within, bytes not
    with restored_tab(app, monkeypatch, {storage.UNREADABLE_KEY: wide}) as s:
        assert not s.ui.aside_btn.visible  # nothing that large goes back out
    for stored in ({storage.WORKING_KEY: text}, {storage.UNREADABLE_KEY: text}):
        with restored_tab(app, monkeypatch, stored) as s:  # now, or on an earlier visit
            sent: list[tuple[str, bytes]] = []
            s.client.send_file_download = lambda name, data, _to=sent, **kw: _to.append(
                (name, data)
            )
            assert s.ui.aside_btn.visible
            s.ui.aside_btn.value = True  # click
            assert sent == [("camdesigner-set-aside.json", text.encode())]
            assert "Sent the design set aside" in s.ui.files_md.content


def test_a_kept_entry_this_version_cannot_open_says_why(app, monkeypatch):
    """Opening a kept design of a later version had said 'Choose a saved design first'."""
    import json

    from app import storage

    newer = json.loads(design_to_json(load_preset("paper_example")))
    newer["schema_version"] = 3
    stored = {storage.SAVED_KEY: json.dumps({"from the new version": json.dumps(newer)})}
    with restored_tab(app, monkeypatch, stored) as s:
        s.open_saved("from the new version")
        assert "Could not open" in s.ui.files_md.content and "newer" in s.ui.files_md.content


def test_a_clients_nan_camera_or_angle_stops_nothing(tab):
    """A review: a camera message with a NaN position made the close-up's camera moves
    raise (viser derives the new pose from the client's), and a NaN angle left the
    animation at NaN. Both are skipped; the tab animates on."""
    s = tab
    s.set_camera_view("Contact close-up")
    state = s.client.camera._state
    state.position, state.look_at = np.full(3, np.nan), np.full(3, np.nan)
    theta = s.theta_deg
    s._on_angle(float("nan"))
    assert s.theta_deg == theta
    s.reset_camera()  # no ValueError
    s._set_playing(True)
    s.frame(0.1, 1)
    assert math.isfinite(s.theta_deg) and s.theta_deg != theta


def test_two_quick_clicks_on_add_add_two_segments(tab, monkeypatch):
    """A review: a double click on 'Add a segment' added one row (both clicks read the
    same rows before either applied). The table's actions run under the tab's lock."""
    import threading

    s = tab
    table = s.ui.segments
    n = len(table.rows)
    real = table.as_dicts
    both_read = threading.Barrier(2, timeout=2)

    def slow_read():  # each click reads the rows; give the other click its chance
        rows = real()
        try:
            both_read.wait()  # (under the lock the second never gets here in time)
        except threading.BrokenBarrierError:
            pass
        return rows

    monkeypatch.setattr(table, "as_dicts", slow_read)
    clicks = [threading.Thread(target=table.act, args=(n, "+")) for _ in range(2)]
    for c in clicks:
        c.start()
    for c in clicks:
        c.join(10)
    assert len(s.design.motion.segments) == n + 2 and len(table.rows) == n + 2


def test_a_silent_browser_storage_is_never_written_over(app, monkeypatch):
    """A review: a read that timed out looked like an empty storage, so the tab wrote
    the default design over the kept one at once, and the first Save replaced the
    saved list with one entry. After a silent read nothing is written, Save says why."""

    def silent(self, key):
        self.silent = True
        return None

    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes, read=silent) as s:
        assert "did not answer" in s.ui.files_md.content
        assert "did not answer" in s.ui.quick_md.content  # above the tabs, in view
        s.ui.controls["motion.lift_mm"].value = 17.0
        assert "did not answer" in s.ui.quick_md.content  # and kept there
        s.save_named("new one")
        assert writes == {} and "Not saved" in s.ui.files_md.content


def test_two_tabs_of_one_browser_keep_each_others_saves(app, monkeypatch):
    """A review: each tab read the saved list once, at its restore, and wrote its copy
    back whole: a save or a delete in one tab erased what the other had saved
    meanwhile. A save or a delete reads the list first; one the browser does not
    answer then writes nothing."""
    import json

    from app import storage

    shared: dict[str, str] = {}  # one browser's storage, both tabs reading and writing
    with restored_tab(app, monkeypatch, shared, shared) as a:
        a.save_named("old")
    with restored_tab(app, monkeypatch, shared, shared) as a:
        with restored_tab(app, monkeypatch, shared, shared) as b:
            b.save_named("from B")
            a.ui.controls["cam.base_radius_mm"].value = 90.0
            a.save_named("from A")
            assert set(json.loads(shared[storage.SAVED_KEY])) == {"old", "from B", "from A"}
            assert set(a.ui.saved_dd.options) == {"old", "from B", "from A"}
            b.delete_saved("old")
            a.delete_saved("from B")
            assert set(json.loads(shared[storage.SAVED_KEY])) == {"from A"}
            before = shared[storage.SAVED_KEY]

            def silent(self, key):
                self.silent = True
                return None

            monkeypatch.setattr(storage.BrowserStore, "read", silent)
            a.save_named("not now")
            assert shared[storage.SAVED_KEY] == before
            assert "did not answer" in a.ui.files_md.content
            assert not a.store.silent  # (the tab keeps what it does as before)


def test_a_tab_beyond_the_limit_is_told_the_server_is_full():
    """A security review: nothing refused a tab, and one client's 60 connections took
    the server from 51 to 711 threads. Beyond ``max_tabs`` (camdesigner --max-tabs) a
    tab gets no Session, only a line saying the server is full; once a tab closes, a
    new one is served."""
    import asyncio

    from viser_client import ViserClient

    from app.main import App

    a = App(host="127.0.0.1", port=0, max_tabs=1)
    try:
        first = FakeTab(a.port)
        assert wait_for(lambda: len(a.sessions) == 1)

        async def turned_away() -> str:
            c = await ViserClient(f"ws://127.0.0.1:{a.port}", "second").connect()
            try:
                await c.wait_for(lambda: c.find_all(contains="server is full"), 20.0, what="full")
                return c.find(contains="server is full").text
            finally:
                await c.close()

        said = asyncio.run(turned_away())
        assert "it serves 1 tab at once" in said and "--max-tabs" in said
        assert len(a.sessions) == 1
        assert wait_for(lambda: not a._refused)  # (its leaving is no Session's)
        first.close()
        assert wait_for(lambda: not a.sessions)
        third = FakeTab(a.port)
        assert wait_for(lambda: len(a.sessions) == 1)
        third.close()
    finally:
        a.stop()


def test_a_burst_of_edits_parks_one_thread_and_the_last_value_is_taken(tab):
    """A security review: every update of a control parked one thread of viser's pool,
    which all tabs share, on the tab's lock until its turn; a few tabs sending 20 a
    second of a costly design took all 32 threads and froze every tab (17 s). One thread
    per kind of action waits; the others return at once, and the one waiting reads the
    controls as they are when its turn comes."""
    import threading

    from app.inbound import TabLanes

    s = tab
    assert isinstance(s.client.gui._thread_executor, TabLanes)  # (a tab's own lanes)
    box = s.ui.controls["cam.base_radius_mm"]
    returned: list[float] = []

    def edit(v: float) -> None:
        box.value = v  # (viser sets the value, then calls back in this thread)
        returned.append(v)

    threads = [threading.Thread(target=edit, args=(71.0 + i,)) for i in range(20)]
    with s.lock:
        for t in threads:
            t.start()
        assert wait_for(lambda: len(returned) >= 19, 10.0)
        time.sleep(0.2)
        assert len(returned) == 19  # one waits its turn
        last = box.value
    for t in threads:
        t.join(10)
    assert len(returned) == 20 and s.design.cam.base_radius_mm == last


def test_a_save_waits_for_the_browser_without_holding_the_tab(app, monkeypatch):
    """A security review: a save re-read the browser's list with the tab's lock held,
    so a client that never answered held it 20 s, and its queued edits took every
    thread of viser's shared pool: every tab froze (19 s). The re-read waits outside
    the lock: the tab's edits go on meanwhile, a second save or delete is told one
    waits already, and the save, once answered, keeps the design then on screen."""
    import json
    import threading

    from app import storage

    shared: dict[str, str] = {}
    hold, asked, answer = threading.Event(), threading.Event(), threading.Event()

    def read(self, key):
        if key == storage.SAVED_KEY and hold.is_set():
            asked.set()
            answer.wait(30)
        return shared.get(key)

    with restored_tab(app, monkeypatch, shared, shared, read=read) as s:
        hold.set()
        timer = threading.Timer(15, answer.set)  # (the old code: no deadlock, a failure)
        timer.start()
        save = threading.Thread(target=s.save_named, args=("kept",))
        save.start()
        try:
            assert asked.wait(10)
            s.ui.controls["cam.base_radius_mm"].value = 90.0
            assert not answer.is_set()  # the edit did not wait for the browser
            assert s.design.cam.base_radius_mm == 90.0
            s.delete_saved("kept")  # (refused at once: one waits for the browser)
            s.save_named("again")
            assert "last save or delete is still under way" in s.ui.files_md.content
        finally:
            answer.set()
            save.join(10)
            timer.cancel()
        kept = json.loads(shared[storage.SAVED_KEY])
        assert set(kept) == {"kept"}
        assert storage.parse_working(kept["kept"]).cam.base_radius_mm == 90.0


def test_saving_keeps_the_entries_this_version_cannot_read(app, monkeypatch):
    """A saved list with an entry this version leaves out (a later version's, a name
    too long) keeps it when a design is saved (it had been dropped)."""
    import json

    from app import storage

    other = {"x" * 100: "a design under a long name", "later": {"format": 9}}
    stored = {storage.SAVED_KEY: json.dumps(other)}
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, stored, writes) as s:
        s.save_named("mine")
        kept = json.loads(writes[storage.SAVED_KEY])
        assert set(kept) == {*other, "mine"} and kept["later"] == {"format": 9}
        assert tuple(s.ui.saved_dd.options) == ("mine",)


def test_the_headline_follows_every_edit_in_the_status(tab):
    """The headline figures sit in the always-visible status and follow an edit at
    once (the key numbers' table is below the Design tab's controls)."""
    s = tab
    rho = f"ρ ≥ {summary(s.analysis)['radius_of_curvature_mm']['convex_min']:.1f} mm"
    before = s.ui.status.content.replace("\u00a0", " ")
    assert "cam-headline" in before and rho in before
    s.ui.controls["cam.base_radius_mm"].value = 100.0
    after = s.ui.status.content
    assert "cam-headline" in after and rho not in after.replace("\u00a0", " ")
    assert panels.headline_html(summary(s.analysis)) in after


def test_an_unfinished_program_survives_a_reload(app, monkeypatch):
    """The segment table's unfinished program is kept in the browser beside the last
    valid design (a review: a reload had lost a half-typed program without a word), it
    comes back as it was left with the error, and once valid the key is emptied. A
    kept program that is not one (tampered, NaN) is ignored."""
    from app import storage

    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes) as s:
        s.ui.segments.act(4, "+")
        s.ui.segments.rows[1]["angle"].value = 50.0  # 340 deg: unfinished
        assert s.error is not None and "360" in s.error
        kept = writes[storage.PROGRAM_KEY]
        assert storage.parse_program(kept) == s._typed_program
    stored = {storage.WORKING_KEY: writes[storage.WORKING_KEY], storage.PROGRAM_KEY: kept}
    again: dict[str, str] = {}
    with restored_tab(app, monkeypatch, stored, again) as s:
        assert len(s.ui.segments.rows) == 5 and s.ui.segments.rows[1]["angle"].value == 50.0
        assert "340" in s.ui.segments.sums.content and "360" in s.error
        assert s.design.motion.segments[1].angle_deg == 70.0  # the last valid design
        assert "unfinished program is back" in s.ui.files_md.content
        s.ui.segments.rows[4]["angle"].value = 20.0  # finished: a valid design
        assert s.error is None and s.design.motion.segments[4].angle_deg == 20.0
        assert "unfinished" not in s.ui.files_md.content  # (a review: the note stayed)
        assert again[storage.PROGRAM_KEY] == ""
        assert storage.parse_working(again[storage.WORKING_KEY]) == s.design
    for bad in ('[{"kind": "rise", "angle_deg": NaN}]', "[]", "{}", "x" * 5000):
        with restored_tab(app, monkeypatch, {**stored, storage.PROGRAM_KEY: bad}) as s:
            assert s.error is None and s.ui.segments.rows[1]["angle"].value == 70.0


def test_a_greyed_control_takes_no_typing(app, monkeypatch):
    """A review: beside an unfinished program the classic sliders are greyed, but viser
    leaves a slider's number box enabled: a lift of 40 typed there changed nothing on
    screen, was kept as the working design, and a reload brought back a folded cam
    never shown. A greyed control's value stays the design's, and its box shows it;
    so for a field the follower does not use."""
    from app import storage

    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes) as s:
        s.ui.segments.rows[1]["angle"].value = 60.0  # 350 deg: unfinished
        lift = s.ui.controls["motion.lift_mm"]
        assert lift.disabled and s.error is not None
        lift.value = 40.0  # typed into the greyed slider's box
        assert lift.value == 15.0 and s.design.motion.lift_mm == 15.0
        assert storage.parse_working(writes[storage.WORKING_KEY]).motion.lift_mm == 15.0
        s.ui.controls["cam.speed_rpm"].value = 900.0  # another edit: kept, with 15 mm
        kept = storage.parse_working(writes[storage.WORKING_KEY])
        assert (kept.motion.lift_mm, kept.cam.speed_rpm) == (15.0, 900.0)
        s.ui.segments.rows[1]["angle"].value = 70.0  # finished
        assert s.error is None and s.design.motion.lift_mm == 15.0
        roller = s.ui.controls["follower.roller_radius_mm"]  # a concave face has none
        assert roller.disabled
        roller.value = 3.0
        assert roller.value == s.design.follower.roller_radius_mm != 3.0


def _left_unfinished(app, monkeypatch, edit=None) -> dict[str, str]:
    """What the browser holds after a tab left the table's program unfinished (the
    sum 350 deg), ``edit(session)`` done after that."""
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes) as s:
        s.ui.segments.rows[1]["angle"].value = 60.0
        assert s.error is not None and "360" in s.error
        if edit is not None:
            edit(s)
    return writes


def test_a_kept_program_never_outlives_the_design_it_was_typed_on(app, monkeypatch):
    """A review: the browser's copy of an unfinished program was emptied only when this
    tab had typed it, so one read but not restored (the working design unreadable, the
    user quicker than the restore, or valid by now) stayed, and replaced a later design
    at a later reload without a word. Now the copy follows the tab's own state."""
    from app import storage

    kept = _left_unfinished(app, monkeypatch)[storage.PROGRAM_KEY]
    # the working design unreadable: the program is not restored, and not kept
    writes: dict[str, str] = {}
    stored = {storage.WORKING_KEY: '{"format": 99}', storage.PROGRAM_KEY: kept}
    with restored_tab(app, monkeypatch, stored, writes) as s:
        assert s._typed_program is None and s.error is None
        assert writes[storage.PROGRAM_KEY] == ""
    # restored, then a preset replaces the whole design: emptied, the preset stays
    writes = {}
    stored = {storage.WORKING_KEY: design_to_json(load_preset("paper_example"))}
    with restored_tab(app, monkeypatch, {**stored, storage.PROGRAM_KEY: kept}, writes) as s:
        assert s._typed_program is not None
        s.load_preset("double_index")
        assert writes[storage.PROGRAM_KEY] == "" and s._typed_program is None
    with restored_tab(app, monkeypatch, {**stored, **writes}, {}) as s:
        assert len(s.design.motion.segments) == 8 and s.error is None
    # a program valid at the restore (another control had been invalid): used, said,
    # and emptied
    program = [g.model_dump(mode="json") for g in load_preset("paper_example").motion.segments]
    program[1]["angle_deg"], program[3]["angle_deg"] = 60.0, 70.0
    writes = {}
    with restored_tab(
        app, monkeypatch, {**stored, storage.PROGRAM_KEY: json.dumps(program)}, writes
    ) as s:
        assert s.error is None and s.design.motion.segments[1].angle_deg == 60.0
        assert "makes a valid design" in s.ui.files_md.content
        assert writes[storage.PROGRAM_KEY] == ""
        assert s.ui.controls["motion.high_dwell_deg"].value == 60.0  # the sliders follow


def test_an_edit_beside_an_unfinished_program_survives_a_reload(app, monkeypatch):
    """A review: another control's edit while the table was unfinished was lost at a
    reload (the working design is saved only when valid). The browser keeps it with
    the last valid program; after the reload both are back, and the program, once
    valid, comes with it. The classic sliders wait meanwhile (greyed): the table's
    program is the one being edited."""

    def edit(s):
        assert all(h.disabled for p, h in s.ui.controls.items() if p.startswith("motion."))
        s.ui.controls["cam.base_radius_mm"].value = 90.0
        assert s.error is not None

    writes = _left_unfinished(app, monkeypatch, edit)
    with restored_tab(app, monkeypatch, dict(writes), {}) as s:
        assert s.ui.controls["cam.base_radius_mm"].value == 90.0
        assert s.error is not None and s.ui.segments.rows[1]["angle"].value == 60.0
        s.ui.segments.rows[1]["angle"].value = 70.0
        assert s.error is None and s.design.cam.base_radius_mm == 90.0
        assert not any(h.disabled for p, h in s.ui.controls.items() if p.startswith("motion."))


@pytest.mark.parametrize(
    "number",
    ["1e400", "1" + "0" * 400, "-1e7", "-5", "361"],
    ids=["1e400", "400 digits", "-1e7", "-5", "361"],
)
def test_a_kept_program_with_numbers_no_table_sends_is_ignored(app, monkeypatch, number):
    """A review: 1e400 (read as infinity) and a 400-digit integer passed the kept
    program's parser; the integer killed the restore thread (OverflowError) and left
    the tab refusing every edit. Numbers the table's boxes do not take are not a
    program (a second review: a lift of 2000 mm had broken the table's rebuild)."""
    from app import storage

    writes = _left_unfinished(app, monkeypatch)
    text = writes[storage.PROGRAM_KEY].replace('"angle_deg": 60.0', f'"angle_deg": {number}')
    assert text != writes[storage.PROGRAM_KEY] and storage.parse_program(text) is None
    again: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {**writes, storage.PROGRAM_KEY: text}, again) as s:
        assert s.error is None and again[storage.PROGRAM_KEY] == ""
        s.ui.controls["cam.base_radius_mm"].value = 90.0
        assert s.error is None and s.design.cam.base_radius_mm == 90.0


def test_every_plot_sends_its_curves_as_float32_and_its_flags_as_int8(tab):
    """What a redraw sends: each plot's angle and curves float32, its shadings (where it
    has them) and its two vertical lines int8, in that order (app.plots.wire)."""
    s = tab
    plots = [*s.ui.curves, s.ui.compare_view.fn, s.ui.compare_view.stress]
    # (the Compare plots get their curves with the refinement, after s.verified is set)
    assert wait_for(lambda: all(len(c.handle.data[0]) > 2 for c in plots))
    for c in plots:
        kinds = [np.asarray(col).dtype for col in c.handle.data]
        flags = 2 + c.shading + c.shared_band  # the lines, limit and both-faces shading
        assert kinds == [np.float32] * (len(kinds) - flags) + [np.int8] * flags, c.title
        assert len(kinds) == c.nser


def test_a_kept_program_is_not_emptied_before_it_is_restored(app, monkeypatch):
    """A review: the working design's restore emptied the browser's copy of the
    unfinished program before the program's own restore wrote it back, so a reload
    between the two lost it. Until the program's restore, nothing is written there;
    a kept lift the table cannot take is not a program."""
    from app import storage
    from app.session import Session

    kept = _left_unfinished(app, monkeypatch)
    monkeypatch.setattr(Session, "_restore_program", lambda *a: None)  # the tab closes
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, dict(kept), writes) as s:
        assert s.design.motion.segments[1].angle_deg == 70.0  # the working design is back
        assert storage.PROGRAM_KEY not in writes
    lifted = kept[storage.PROGRAM_KEY].replace('"lift_mm": 15.0', '"lift_mm": 2000', 1)
    assert lifted != kept[storage.PROGRAM_KEY] and storage.parse_program(lifted) is None


def test_a_program_made_valid_by_another_control_shows_in_the_sliders(tab):
    """The table's program made valid by another control's edit: the classic sliders
    show it (a review: their stale values reverted it at the next, unrelated edit),
    and no other control is written (a user's next edit may already sit in one)."""
    s = tab
    s.ui.controls["cam.base_radius_mm"].value = 0.0  # invalid
    s.ui.segments.rows[1]["angle"].value = 60.0  # the table's program: 350 deg
    s.ui.segments.rows[3]["angle"].value = 70.0  # 360 deg, still refused by r_b
    assert s._typed_program is not None and s.error is not None
    width = s.ui.controls["cam.width_mm"]
    width._impl.value = 22.0  # as viser holds a user's edit before its callback runs
    s.ui.controls["cam.base_radius_mm"].value = 80.0  # valid: the table's program
    assert s.error is None and s.design.motion.segments[1].angle_deg == 60.0
    assert s.ui.controls["motion.high_dwell_deg"].value == 60.0
    assert width.value == 22.0
    s.ui.controls["cam.width_mm"].value = 16.0  # the next, unrelated edit
    assert s.design.motion.segments[1].angle_deg == 60.0 and s.design.cam.width_mm == 16.0


def test_a_table_edit_before_the_programs_restore_wins(app, monkeypatch):
    """A review: a table edit (still unfinished) arriving between the working design's
    restore and the program's was written to the browser, then the restore replayed
    the old kept program over it and believed the browser held that one: the screen
    and a later reload disagreed. The user's edit wins, on screen and in the browser."""
    from app import storage
    from app.session import Session

    kept = _left_unfinished(app, monkeypatch)
    real = Session._restore_program

    def user_first(self, text, typed, gen):
        self.ui.segments.rows[1]["angle"].value = 55.0  # the user's edit comes first
        return real(self, text, typed, gen)

    monkeypatch.setattr(Session, "_restore_program", user_first)
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, dict(kept), writes) as s:
        assert s.ui.segments.rows[1]["angle"].value == 55.0
        assert json.loads(writes[storage.PROGRAM_KEY])[1]["angle_deg"] == 55.0
        assert s._typed_program[1]["angle_deg"] == 55.0


def test_tabs_of_one_browser_leave_a_coherent_pair(app, monkeypatch):
    """The browser's tabs share the working design and the kept program. A Chromium
    review: tab B loaded a preset while tab A's unfinished program was kept, and a
    reload brought A's red table back over B's preset; and B's unfinished program was
    lost after A finished its own. Every tab writes its program beside the working
    design it writes, so the last writer leaves one coherent pair."""
    from app import storage

    shared: dict[str, str] = {}
    with (
        restored_tab(app, monkeypatch, shared, shared) as a,
        restored_tab(app, monkeypatch, shared, shared) as b,
    ):
        a.ui.segments.rows[1]["angle"].value = 80.0  # A: unfinished (370 deg)
        assert storage.parse_program(shared[storage.PROGRAM_KEY]) == a._typed_program
        b.load_preset("double_index")  # B: a whole design
        assert shared[storage.PROGRAM_KEY] == ""
    with restored_tab(app, monkeypatch, shared, shared) as c:
        assert c.error is None and len(c.design.motion.segments) == 8
        c.load_preset("paper_example")
    with (
        restored_tab(app, monkeypatch, shared, shared) as a,
        restored_tab(app, monkeypatch, shared, shared) as b,
    ):
        b.ui.segments.rows[1]["angle"].value = 80.0  # B: unfinished
        a.ui.segments.rows[1]["angle"].value = 60.0  # A: unfinished, then finished
        a.ui.segments.rows[3]["angle"].value = 70.0
        assert a.error is None and shared[storage.PROGRAM_KEY] == ""
        b.ui.controls["cam.base_radius_mm"].value = 85.0  # B edits last
    with restored_tab(app, monkeypatch, shared, shared) as c:
        assert c.ui.segments.rows[1]["angle"].value == 80.0 and c.error is not None
        assert c.ui.controls["cam.base_radius_mm"].value == 85.0


def test_acceleration_jumps_can_be_accepted_from_the_app_and_say_so(tab):
    """A teacher's review: the warning for a simple-harmonic rise said to set
    limits.require_continuous_acceleration = false, a field no control offered, and the
    preset that sets it showed the same law green without a word. The checkbox turns
    the warning into a line under the verdict that says what is accepted, and where."""
    s = tab
    s.ui.controls["motion.rise_law"].value = LABEL_OF_LAW["simple_harmonic"]
    assert "acceleration_jump" in {v.code for v in s.analysis.violations}
    assert "untick Require continuous acceleration (Material &amp; limits)" in (
        s.ui.status.content
    )  # the control's name, not the design path
    assert "accepted at theta" not in s.ui.status.content
    s.ui.controls["limits.require_continuous_acceleration"].value = False
    assert not s.analysis.violations and "All design limits met" in s.ui.status.content
    status = s.ui.status.content
    assert "acceleration jumps accepted at theta = 0.000, 100.000 deg" in status
    assert "Require continuous acceleration is off (Material &amp; limits)" in status
    s.ui.controls["limits.require_continuous_acceleration"].value = True
    assert "accepted at theta" not in s.ui.status.content


def test_the_pressure_angle_label_gives_its_size_as_the_paper(tab):
    """A teacher's review: the 3D label read 'φ = -7.3°' in the fall, where the paper
    says phi remains positive (Eq. 13); the label gives the size, the curve the sign."""
    s = tab
    s.ui.angle_slider.value = 235.0  # the fall: S2 drives, the signed angle is negative
    k = s._index()
    assert s.analysis.pressure_angle[:, k][s.analysis.in_contact[:, k]][0] < 0
    text = s.view.nodes["phi_label"].text
    assert text.startswith("φ = ") and "-" not in text and "−" not in text


def test_words_fit_the_follower_and_the_stations(tab):
    """A teacher's review: 'at station 1 and 2', 'F_N = 17.6 N per face' of rollers
    and '(one face: nothing to hand over)' of a single roller."""
    s = tab
    s.ui.controls["follower.kind"].value = "double roller"
    s.ui.stations_btn.value = "2"
    assert "N per roller" in s.ui.where_md.content and "per face" not in s.ui.where_md.content
    s.ui.controls["follower.kind"].value = "single roller"
    s.ui.stations_btn.value = "1"
    where = s.ui.where_md.content
    assert "at stations 1 and 2" in where and "at station 1 and" not in where
    assert "one contact: nothing to hand over" in where and "one face" not in where


def test_step_buttons_turn_the_cam_by_hand(tab):
    """A teacher's review: no way to step the animation but the slider's 0.1 deg arrow
    keys. The step buttons pause and turn the cam; round the turn too; a value that is
    not one of them is ignored."""
    s = tab
    s.speed = 0.0  # playing, but no frame turns the cam (under load a frame
    s.toggle_play()  # between the slider and the step had turned it 4.8 deg)
    assert s.playing and s.speed == 0.0

    def fire(label):  # a click on the button group, through its wiring
        s.ui.step_btns.value = label

    s.ui.angle_slider.value = 100.0
    fire("+5°")
    assert s.theta_deg == pytest.approx(105.0) and not s.playing
    assert s.ui.angle_slider.value == pytest.approx(105.0) and "θ = 105.0°" in s.ui.where_md.content
    fire("−1°")
    assert s.theta_deg == pytest.approx(104.0)
    s.ui.angle_slider.value = 358.0
    fire("+5°")
    assert s.theta_deg == pytest.approx(3.0)
    for junk in ("+90°", None, 5, "../x"):
        fire(junk)
        assert s.theta_deg == pytest.approx(3.0)


def test_the_name_to_keep_a_design_under_is_the_designs(tab):
    """A teacher's review: the 'Kept in this browser' name read 'my cam' whatever the
    design; it proposes the design's own name, to fit the saved names' 60 characters
    without its parenthesis, or cut at a word (a review: the paper's example was kept
    as "… (double concave faces", cut mid-parenthesis)."""
    from app.storage import proposed_name

    s = tab
    assert s.design.name.startswith("Chuang, Hsu & Chang, Section 6 example (double")
    assert s.ui.save_name.value == "Chuang, Hsu & Chang, Section 6 example"
    cut = proposed_name("word " * 20)
    assert len(cut) <= 60 and cut.endswith("word …") and proposed_name(" ") == "my cam"
    long_word = "packaging_line_station_3_cam_revision_B_final_for_customer_XYZ"
    assert proposed_name(long_word) == long_word[:58] + " …"  # (it had proposed "…")
    assert proposed_name("short (with a note)") == "short (with a note)"
    s.load_preset("valve_lift_roller")
    assert s.ui.save_name.value == proposed_name(load_preset("valve_lift_roller").name)
    # what the user typed stays through edits, a program-table edit too (a review:
    # it was replaced, and a save went under another name, over an earlier save)
    s.ui.save_name.value = "my version 2"
    s.ui.controls["cam.base_radius_mm"].value = 70.0
    s.ui.segments.act(0, "+")
    assert s.ui.save_name.value == "my version 2"
    s.ui.controls["name"].value = "Valve cam v3"  # (typed in the box: it stays)
    assert s.ui.save_name.value == "my version 2"
    # an app review: renamed on the Design tab, the design was kept under the
    # preset's name, which the box still proposed; it follows the design's name
    s.load_preset("valve_lift_roller")
    time.sleep(0.7)  # (changes less than 0.6 s apart are one step of the history)
    s.ui.controls["name"].value = "Valve cam v2 for press 7"
    assert s.ui.save_name.value == "Valve cam v2 for press 7"
    s.travel("↶ Undo")  # (a review of the change: Undo kept the box at the new name)
    assert s.design.name == load_preset("valve_lift_roller").name
    assert s.ui.save_name.value == proposed_name(s.design.name)


def test_saving_over_another_kept_design_asks_first(app, monkeypatch):
    """A maker's review: saving a variant under the proposed name replaced the design
    kept under it without a word. The first Save says so; a second replaces it; saving
    the same design again, or under a new name, just saves."""
    import json

    from app import storage

    writes: dict[str, str] = {}  # (the browser: what is written is read back)
    with restored_tab(app, monkeypatch, writes, writes) as s:
        s.save_named("mine")
        first = json.loads(writes[storage.SAVED_KEY])["mine"]
        s.save_named("mine")  # the same design: nothing to lose
        assert "Saved **mine**" in s.ui.files_md.content
        s.ui.controls["cam.base_radius_mm"].value = 95.0
        s.save_named("mine")
        assert "already keeps another design as **mine**" in s.ui.files_md.content
        assert json.loads(writes[storage.SAVED_KEY])["mine"] == first  # not replaced
        s.ui.controls["cam.base_radius_mm"].value = 96.0  # an edit between: asks again
        s.save_named("mine")
        assert "already keeps another design" in s.ui.files_md.content
        assert json.loads(writes[storage.SAVED_KEY])["mine"] == first
        s.save_named("mine")  # the second click on the same design replaces it
        assert "replaces the one kept before" in s.ui.files_md.content
        assert json.loads(writes[storage.SAVED_KEY])["mine"] != first
        s.ui.controls["cam.base_radius_mm"].value = 90.0
        s.save_named("mine 2")
        assert set(json.loads(writes[storage.SAVED_KEY])) == {"mine", "mine 2"}


def test_a_kept_design_opens_under_its_own_name(app, monkeypatch):
    """A review: opening the kept 'variant A' proposed the design's inner name."""
    import json

    from app import storage

    kept = {"variant A": design_to_json(load_preset("valve_lift_roller"))}
    with restored_tab(app, monkeypatch, {storage.SAVED_KEY: json.dumps(kept)}) as s:
        s.open_saved("variant A")
        assert s.design == load_preset("valve_lift_roller")
        assert s.ui.save_name.value == "variant A"


def test_a_reload_keeps_how_the_tab_looked_at_the_design(app, monkeypatch):
    """A teacher's review: a reload kept the design but not the cam angle, the pause at
    stations, the wide panel, the overlays or the camera preset. The tab writes them
    as they change and a new tab takes them back; a kept entry that is not one of the
    controls' values (a tampered storage) is left out, the others still count."""
    from app import storage

    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes) as s:
        assert storage.VIEW_KEY in writes  # the restore writes the tab's own at once
        s.goto_station(2)
        station_2 = s.theta_deg
        s.ui.pause_box.value = True
        s.ui.speed_slider.value = 90.0
        s.ui.overlay_boxes["wear"].value = True
        s.ui.overlay_boxes["forces"].value = False
        s.set_camera_view("Contact close-up")
        s.ui.wide_box.value = True
    kept = writes[storage.VIEW_KEY]
    with restored_tab(app, monkeypatch, {storage.VIEW_KEY: kept}) as s:
        assert s.theta_deg == pytest.approx(station_2, abs=1e-3)
        assert s.ui.angle_slider.value == pytest.approx(round(station_2, 1))
        assert s.ui.pause_box.value and s.speed == 90.0 and s.ui.speed_slider.value == 90.0
        assert s.view.show["wear"] and not s.view.show["forces"]
        assert s.camera_view == "Contact close-up" and s.ui.wide_box.value
        assert s.panel_px > __import__("app.layout").layout.NARROW_PANEL_PX
    hostile = json.dumps(
        {
            "theta_deg": 400,
            "speed_deg_s": float("nan"),
            "pause_at_stations": "yes",
            "camera_view": "../../etc",
            "overlays": {"wear": True, "nonsense": True},
            "wide_panel": True,
        }
    )
    assert storage.parse_view(hostile) == {"wide_panel": True}
    with restored_tab(app, monkeypatch, {storage.VIEW_KEY: hostile}) as s:
        assert s.theta_deg == 0.0 and s.speed == 45.0 and not s.ui.pause_box.value
        assert s.camera_view == "Front" and s.ui.wide_box.value
    for junk in ("[1]", "{", "x" * 5000, '{"overlays": {"wear": [1]}}'):
        assert storage.parse_view(junk) == {}


def test_the_users_own_view_change_wins_over_the_kept_one(app, monkeypatch):
    """A view change the user makes before the restore has read the browser's copy is
    not undone by it."""
    from app import storage

    kept = json.dumps({"theta_deg": 200.0, "camera_view": "3D"})
    gate = threading.Event()

    def slow_read(self, key):
        gate.wait(10)
        return {storage.VIEW_KEY: kept}.get(key)

    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes, read=slow_read, join=False) as s:
        s.save_named("early")  # the browser not read yet: not written over unseen
        assert "still reading" in s.ui.files_md.content and not writes
        s.step("+5°")
        gate.set()
        s._restorer.join(10)
        assert s.theta_deg == pytest.approx(5.0) and s.camera_view == "Front"
        assert json.loads(writes[storage.VIEW_KEY])["theta_deg"] == pytest.approx(5.0)


def test_the_proposed_spring_goes_in_with_one_click(tab, monkeypatch):
    """Dynamics' *Use the proposed spring rate*: k becomes the key numbers' proposal
    (n k_min rounded up: its margin k / k_min is then n at least), the control shows it,
    Undo takes it back; a design no spring holds, and invalid input, say why instead."""
    from app import history
    from camcore.report import summary as report_summary

    monkeypatch.setattr(history, "SETTLE_S", 0.0)  # each change a step
    s = tab
    first = s.design
    before = report_summary(s.analysis)
    proposal = before["spring_proposal"]["spring_rate_N_per_m"]
    assert proposal != first.dynamics.spring_rate_N_per_m  # (paper: 4201 against 6772.5)
    s.ui.spring_btn.value = True  # click
    assert s.design.dynamics.spring_rate_N_per_m == proposal
    assert s.ui.controls["dynamics.spring_rate_N_per_m"].value == proposal
    after_rpm = report_summary(s.analysis)["jump_speed_rpm"]
    before_rpm = before["jump_speed_rpm"]
    assert f"6772.5 → {proposal:g} N/m; jump speed {before_rpm:.1f} rpm → {after_rpm:.1f} rpm" in (
        s.ui.spring_md.content
    )
    after = report_summary(s.analysis)
    n = first.dynamics.spring_safety_factor
    assert n <= after["jump_margin"]["spring_rate"] < n * 1.001  # the rule, just met
    assert after["spring_proposal"]["spring_rate_N_per_m"] == proposal  # (a fixed point)
    s.use_proposed_spring()  # again: nothing to change, and it says so
    assert "the proposal already" in s.ui.spring_md.content
    s.travel("↶ Undo")
    assert s.design == first and s.ui.spring_md.content == ""  # (said of the other)
    s.ui.controls["dynamics.preload_mm"].value = 0.0
    s.ui.controls["dynamics.external_load_N"].value = -50.0  # pulls it off in the dwell
    assert s.proposed_rate is None
    s.use_proposed_spring()
    assert "No spring rate keeps contact" in s.ui.spring_md.content
    assert s.design.dynamics.spring_rate_N_per_m == first.dynamics.spring_rate_N_per_m
    # a proposal past the field's own limit (1e9 N/m) is said, not put on screen (a
    # review: the design on screen then failed its own validation at the next edit)
    s.ui.controls["dynamics.preload_mm"].value = 1e-6
    assert s.proposed_rate is not None and s.proposed_rate > 1e9
    kept = s.design
    s.use_proposed_spring()
    assert (
        "is no spring rate here" in s.ui.spring_md.content and "preload" in s.ui.spring_md.content
    )
    assert s.design == kept and Design.model_validate(s.design.model_dump()) == kept
    s.ui.controls["cam.base_radius_mm"].value = -5.0  # invalid input
    s.use_proposed_spring()
    assert "input is invalid" in s.ui.spring_md.content


def test_undo_and_redo_step_through_the_designs(tab, monkeypatch):
    """A designer tries a change and steps back: Undo gives the design before it,
    controls and program table with it; Redo gives it again; a slider dragged through
    several values is one step; a hostile label or an empty side does nothing."""
    from app import history

    s = tab
    first = s.design
    undo, redo = (lambda: s.travel("↶ Undo")), (lambda: s.travel("↷ Redo"))
    undo()
    assert s.design == first  # nothing to undo, and it says so (after a reload too)
    assert "Nothing to undo: the history keeps this tab's last" in s.ui.history_md.content
    redo()  # nothing either way: said, no counts to keep
    assert s.ui.history_md.content.startswith("Nothing to redo")
    assert "to undo" not in s.ui.history_md.content
    monkeypatch.setattr(history, "SETTLE_S", 60.0)  # (a loaded machine's slow drag too)
    for r_b in (82.0, 85.0, 90.0):  # a drag: one step
        s.ui.controls["cam.base_radius_mm"].value = r_b
    monkeypatch.setattr(history, "SETTLE_S", 0.0)  # from here each change is a step
    s.load_preset("double_index")
    preset = s.design
    assert "2 steps to undo, 0 to redo" in s.ui.history_md.content
    undo()
    assert s.design.cam.base_radius_mm == 90.0 and s.design.motion == first.motion
    assert s.ui.controls["cam.base_radius_mm"].value == 90.0
    assert len(s.ui.segments.rows) == len(first.motion.segments)
    undo()
    assert s.design == first and s.ui.controls["cam.base_radius_mm"].value == 80.0
    redo()
    redo()
    assert s.design == preset and len(s.ui.segments.rows) == len(preset.motion.segments)
    s.travel("../../etc/passwd")
    s.ui.history_btns._impl.value = "nonsense"
    assert s.design == preset
    undo()
    s.ui.controls["cam.width_mm"].value = 20.0  # a new change: nothing to redo
    redo()
    assert s.design.cam.width_mm == 20.0 and s.design.motion == first.motion
    assert s.ui.history_md.content.startswith("Nothing to redo")  # and the counts kept
    assert s.ui.history_md.content.endswith(f"{s.history.text()}.")
    # an input error on screen and nothing left to undo: Undo gives back the design on
    # screen, its values in the controls; the steps' line follows (a review)
    monkeypatch.setattr(history, "SETTLE_S", 60.0)
    s.history.clear()
    s.ui.controls["cam.width_mm"].value = 22.0
    s.ui.controls["cam.width_mm"].value = 20.0  # undone by hand in the same burst
    s.ui.controls["motion.lift_mm"].value = -3.0  # an input error
    assert s.error is not None
    undo()
    assert s.error is None and s.ui.controls["motion.lift_mm"].value == s.design.motion.lift_mm
    assert s.design.cam.width_mm == 20.0 and s.ui.history_md.content == ""
    # ... and with steps to undo, the first Undo drops only the typing: the valid
    # change before it stays (a designer's review: it went too, Redo alone gave it back)
    monkeypatch.setattr(history, "SETTLE_S", 0.0)
    s.ui.controls["limits.max_pressure_angle_deg"].value = 33.0
    valid = s.design
    s.ui.segments.rows[1]["angle"].value = 50.0  # an unfinished program: 340 deg
    assert s.error is not None and s._typed_program is not None
    undo()
    assert s.error is None and s._typed_program is None and s.design == valid
    assert [r["angle"].value for r in s.ui.segments.rows] == [
        g.angle_deg for g in valid.motion.segments
    ]
    undo()  # then the steps, as before: the pressure angle's limit first
    assert s.design.limits.max_pressure_angle_deg != 33.0


def test_a_table_edit_waiting_on_the_restore_still_wins(tab):
    """A review: the restore of the browser's unfinished program went through the
    ticketed entry point, so a user's table edit waiting on the lock was dropped as
    superseded and the kept program replaced it. The user's edit wins."""
    s = tab
    user = [g.model_dump(mode="json") for g in s.design.motion.segments]
    user[0]["lift_mm"] = user[2]["lift_mm"] = 12.0
    kept = [dict(g) for g in user]
    kept[1]["angle_deg"] = 50.0  # 340 deg: unfinished
    with s.lock:
        before = s._tickets["segments"]
        t = threading.Thread(target=s.on_segments, args=(user,))
        t.start()
        assert wait_for(lambda: s._tickets["segments"] > before)  # waits on the lock
        s._restore_program(json.dumps(kept), kept, s.gen)
    t.join(10)
    assert s._typed_program is None and s.error is None
    assert s.design.motion.segments[0].lift_mm == 12.0


def _kept_r_b_70() -> str:
    """What a browser kept from a last visit: the paper's example at r_b 70 mm."""
    data = load_preset("paper_example").model_dump()
    data["cam"]["base_radius_mm"] = 70.0
    return design_to_json(Design.model_validate(data))


def _slow_browser(app, monkeypatch, stored: dict, writes: dict):
    """A new tab whose browser answers its storage reads only when the returned event
    is set (a busy browser can take up to 20 s): (session, event, fake tab)."""
    from app import storage

    answer = threading.Event()
    monkeypatch.setattr(
        storage.BrowserStore, "read", lambda self, key: (answer.wait(30), stored.get(key))[1]
    )
    monkeypatch.setattr(storage.BrowserStore, "write", lambda self, k, v: writes.__setitem__(k, v))
    before = set(app.sessions)
    t = FakeTab(app.port)
    assert wait_for(lambda: set(app.sessions) - before)
    (s,) = [app.sessions[c] for c in set(app.sessions) - before]
    return s, answer, t


@pytest.mark.parametrize("edit", ["unfinished table", "invalid value", "valid value"])
def test_an_edit_made_while_the_browser_reads_is_not_wiped(app, monkeypatch, edit):
    """A review: the restore took "no design made yet" for "no edit yet", so an edit
    that left the input invalid (an unfinished program in the table, a lift of 0)
    while the browser took its time was wiped by the kept design, the error with it.
    Any edit begun, valid or not, keeps the tab's own work, and the design the browser
    kept is saved beside it (the next valid change replaces the working design)."""
    from app import storage

    kept = _kept_r_b_70()
    writes: dict[str, str] = {}
    s, answer, t = _slow_browser(app, monkeypatch, {storage.WORKING_KEY: kept}, writes)
    try:
        if edit == "unfinished table":
            s.ui.segments.rows[1]["angle"].value = 50.0  # 340 deg
        elif edit == "invalid value":
            s.ui.controls["motion.lift_mm"].value = 0.0
        else:
            s.ui.controls["cam.base_radius_mm"].value = 95.0
        answer.set()
        s._restorer.join(10)
        assert s.design.cam.base_radius_mm == (95.0 if edit == "valid value" else 80.0)
        if edit == "unfinished table":
            assert s.ui.segments.rows[1]["angle"].value == 50.0 and s._typed_program
        if edit == "invalid value":
            assert s.ui.controls["motion.lift_mm"].value == 0.0 and s.error is not None
        # what the browser kept is not lost: saved beside the user's work, and said
        from app.panels import esc

        name = storage.proposed_name(f"last visit: {storage.parse_working(kept).name}")
        saved = storage.parse_saved(writes[storage.SAVED_KEY])
        assert storage.parse_working(saved[name]).cam.base_radius_mm == 70.0
        said = s.ui.files_md.content
        assert "your edit stands" in said and esc(name) in said
    finally:
        t.close()


@pytest.mark.parametrize("click", ["open saved", "unreadable upload"])
def test_a_click_that_opens_nothing_does_not_cancel_the_restore(app, monkeypatch, click):
    """A review: Open, clicked before the browser had answered (the saved list still
    "–"), opened nothing but counted as an edit: the kept design was not restored and
    the tab said "your edit stands". Only an edit of the controls or the table, or a
    design opened, counts."""
    from app import storage

    kept = _kept_r_b_70()
    writes: dict[str, str] = {}
    s, answer, t = _slow_browser(app, monkeypatch, {storage.WORKING_KEY: kept}, writes)
    try:
        if click == "open saved":
            s.open_saved("–")
        else:
            s.upload("x.json", b"not a design")
        answer.set()
        s._restorer.join(10)
        assert s.design.cam.base_radius_mm == 70.0  # restored
        assert storage.SAVED_KEY not in writes  # (no "last visit" kept: no edit)
    finally:
        t.close()


def test_an_invalid_edit_before_the_restore_says_the_kept_program_goes(app, monkeypatch):
    """A review: the last visit's unfinished program went without a word when the user
    typed an invalid value before the browser answered (the design it was typed on is
    kept as "last visit"; a program that makes no design cannot be)."""
    from app import storage

    kept = _kept_r_b_70()
    program = [
        g.model_dump(mode="json", exclude_none=True)
        for g in load_preset("paper_example").motion.segments
    ]
    program[1]["angle_deg"] = 50.0  # 340 deg: unfinished
    stored = {storage.WORKING_KEY: kept, storage.PROGRAM_KEY: json.dumps(program)}
    writes: dict[str, str] = {}
    s, answer, t = _slow_browser(app, monkeypatch, stored, writes)
    try:
        s.ui.controls["cam.speed_rpm"].value = -5.0  # invalid
        answer.set()
        s._restorer.join(10)
        assert s.error is not None and s.ui.controls["cam.speed_rpm"].value == -5.0
        assert "unfinished program in its segment table is not kept" in s.ui.files_md.content
    finally:
        t.close()


def test_a_long_name_kept_twice_takes_a_number_within_the_limit():
    """A review: "last visit: NAME" for a name near the 60-character limit came back
    from shortening without its " (2)", so a second last visit was saved over the
    first. The number fits inside the limit; the same design keeps its name."""
    from app import storage
    from app.session import _free_name

    one, two = load_preset("paper_example"), load_preset("valve_lift_roller")
    long = "ab " * 30
    first = _free_name({}, f"last visit: {long}", one)
    saved = storage.with_saved({}, first, one)
    second = _free_name(saved, f"last visit: {long}", two)
    assert second != first and second.endswith(" (2)")
    assert len(first) <= storage.MAX_NAME and len(second) <= storage.MAX_NAME
    assert _free_name(saved, f"last visit: {long}", one) == first


def test_a_slider_edit_waiting_on_the_restore_wins(app, monkeypatch):
    """A review: the restore decided that the user had not edited yet while a slider
    edit waited on its lock, then set the kept design after letting go of the lock:
    the edit read the kept design's values back and the user's 95 mm was gone."""
    from app import storage
    from app.session import Session

    kept = _kept_r_b_70()
    user: list[threading.Thread] = []
    real = Session._show_saved

    def user_edits_now(self, saved, write=False):  # (the restore holds the lock here)
        if threading.current_thread() is self._restorer and not user:
            before = self._tickets["controls"]
            box = self.ui.controls["cam.base_radius_mm"]
            user.append(threading.Thread(target=lambda: setattr(box, "value", 95.0)))
            user[0].start()
            assert wait_for(lambda: self._tickets["controls"] > before)  # on the lock
        return real(self, saved, write)

    monkeypatch.setattr(Session, "_show_saved", user_edits_now)
    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {storage.WORKING_KEY: kept}, writes, join=False) as s:
        s._restorer.join(10)
        user[0].join(10)
        assert s.design.cam.base_radius_mm == 95.0
        assert s.ui.controls["cam.base_radius_mm"].value == 95.0
        assert storage.parse_working(writes[storage.WORKING_KEY]).cam.base_radius_mm == 95.0


def test_a_table_edit_takes_its_turn_before_it_reads_the_table(tab):
    """A review: a table edit read the rows, then took its turn; one preempted between
    the two took a turn newer than the edit after it and made its older rows the
    program, undoing that edit in the design and the table. The rows are read when
    the edit's turn comes."""
    s, table = tab, tab.ui.segments
    real = s.on_segments
    first = threading.Event()

    def preempted(segs):  # the first edit stops before its turn until the second took one
        if not first.is_set():
            first.set()
            before = s._tickets["segments"]
            assert wait_for(lambda: s._tickets["segments"] > before)
        real(segs)

    table.on_change = preempted
    t = threading.Thread(target=setattr, args=(table.rows[0]["law"], "value", "3-4-5 polynomial"))
    t.start()
    assert first.wait(5)
    table.rows[2]["law"].value = "modified sine"  # the second edit
    t.join(10)
    laws = [g.law.value if g.law else None for g in s.design.motion.segments]
    assert laws[0] == "poly_345" and laws[2] == "modified_sine"
    assert table.rows[2]["law"].value == "modified sine"


def test_the_file_opened_last_is_the_design_shown(tab, monkeypatch):
    """A review: a file's turn was taken after its parse, so an earlier file whose parse
    took longer replaced the one opened after it. The turn is taken first."""
    import time

    from app import session as sm

    real = sm.storage.open_untrusted
    first = design_to_json(load_preset("valve_lift_roller")).encode()

    def parse(content):
        if content == first:  # (a larger file, or a preempted thread)
            time.sleep(0.2)
        return real(content)

    monkeypatch.setattr(sm.storage, "open_untrusted", parse)
    t = threading.Thread(target=tab.upload, args=("first.json", first))
    t.start()
    time.sleep(0.05)
    tab.upload("second.json", design_to_json(load_preset("double_index")).encode())
    t.join(10)
    assert tab.design == load_preset("double_index") and "second.json" in tab.ui.files_md.content


def test_a_preset_clicked_after_an_edit_is_the_design_shown(tab):
    """A review: loading the preset on screen skipped writing its values into the
    controls, so a slider edit waiting on the lock ran afterwards and the design was
    not the preset the Files line named. The controls are written; the edit then
    reads the preset's values."""
    s = tab
    paper = load_preset("paper_example")
    with s.lock:
        before = s._tickets["controls"]
        t = threading.Thread(
            target=lambda: s.ui.controls["cam.base_radius_mm"].__setattr__("value", 95.0)
        )
        t.start()
        assert wait_for(lambda: s._tickets["controls"] > before)
        s.load_preset("paper_example")  # clicked after the edit, the design on screen
    t.join(10)
    assert s.design == paper and s.ui.controls["cam.base_radius_mm"].value == 80.0


def test_the_3d_cam_marks_its_datum(tab):
    """A teacher's review: the stations diagram marks the cam's theta = 0 ray, the 3D
    cam did not. A line on the cam's top face runs from the hub to the rim along the
    cam frame's +Y ray (under /cam: it turns with the cam), to the profile's radius
    there; the legend names it."""
    s = tab
    node = s.view.nodes["datum"]
    assert node.name.startswith("/cam/")
    (seg,) = np.asarray(node.points, float)
    r_b = s.analysis.geo.r_b
    assert seg[:, 0].tolist() == [0.0, 0.0] and seg[0, 1] == pytest.approx(0.1 * r_b)
    P = s.analysis.profile.points
    on_ray = P[(np.abs(P[:, 0]) < 2e-3) & (P[:, 1] > 0)]  # the profile where it crosses +Y
    assert seg[1, 1] == pytest.approx(float(np.hypot(*on_ray.T).mean()), abs=1e-4)
    assert "θ = 0 datum" in scene.legend_html()
    s.ui.controls["cam.bore_diameter_mm"].value = 30.0  # a bore and its keyway on the ray
    round_bore = np.asarray(s.view.nodes["cam"].vertices).copy()
    s.ui.controls["cam.keyway_width_mm"].value = 8.0
    s.ui.controls["cam.keyway_depth_mm"].value = 3.3
    assert s.error is None
    # the 3D cam is cut again with its keyway (it had kept the round bore)
    assert not np.array_equal(np.asarray(s.view.nodes["cam"].vertices), round_bore)
    (seg,) = np.asarray(s.view.nodes["datum"].points, float)
    assert seg[0, 1] == pytest.approx((15.0 + 3.3) * 1e-3)  # starts beyond the keyway


def test_the_force_and_stress_plots_shade_where_both_faces_touch(tab):
    """A teacher's wish: where the load is shared (Eqs. 36-38), at a glance. For the
    paper's program both faces touch from station 2 to 3 (the high dwell less 2 psi_h
    at each end) and from station 5 round to 0 (the low dwell): shaded in gold there
    and nowhere else; a single follower has no such band, nor its legend entry."""
    from app.plots import SHARED_LABEL

    s = tab
    st = np.degrees(s.analysis.stations)  # 0, 100, 107.4, 162.6, 170, 300
    for title in ("Contact force", "Contact (Hertz) stress"):
        c = next(c for c in s.ui.curves if c.title.startswith(title))
        inside = ((c.x > st[2] + 0.5) & (c.x < st[3] - 0.5)) | (c.x > st[5] + 0.5)
        outside = ((c.x > st[0] + 0.5) & (c.x < st[2] - 0.5)) | (
            (c.x > st[3] + 0.5) & (c.x < st[5] - 0.5)
        )
        assert c.shared[inside].min() == 1.0 and c.shared[outside].max() == 0.0, title
        (band,) = [x for x in c.handle.series if x["label"] == SHARED_LABEL]
        assert band.get("show", True)
    others = [c for c in s.ui.curves if not c.title.startswith(("Contact force", "Contact (H"))]
    assert not any(c.shared_band for c in others)
    s.set_design(s.design.with_kind("single_roller"))
    c = next(c for c in s.ui.curves if c.title.startswith("Contact force"))
    assert c.shared.max() == 0.0
    (band,) = [x for x in c.handle.series if x["label"] == SHARED_LABEL]
    assert band["show"] is False


def test_explore_says_when_the_design_is_outside_its_ranges(tab):
    """A teacher's review: ranges kept from an earlier design (r_b 28-52 mm) swept
    around the paper's 80 mm cam without a word, the design on screen off the map.
    The summary says so, and *Ranges around the design on screen* centres them."""
    from app.panels import esc

    e = tab.ui.explore
    e.x.value, e.y.value = "Base radius r_b [mm]", "Offset e (double) [mm]"
    e.x_range.value, e.y_range.value = (28.0, 52.0), (8.0, 12.0)
    e.steps.value, e.all_kinds.value = 2, False
    e.run_btn.value = True  # click
    assert wait_for(lambda: "on the Pareto front" in e.progress.content, 120.0), e.progress.content
    said = e.progress.content
    label = esc("Base radius r_b [mm]")  # (Markdown: shown as typed)
    assert f"⚠ The design on screen: {label} = 80 is outside its range 28 … 52" in said
    assert "Offset" not in said.partition("⚠")[2]  # (e = 10 mm is inside 8 … 12)
    e.centre_btn.value = True  # click
    r_b, offset = tab.design.cam.base_radius_mm, tab.design.follower.offset_mm
    assert tuple(e.x_range.value) == (round(0.7 * r_b, 1), round(1.3 * r_b, 1))
    assert tuple(e.y_range.value) == (round(0.7 * offset, 1), round(1.3 * offset, 1))
    assert e.setup()["x_range"] == list(e.x_range.value)  # kept in the browser too
    assert wait_for(lambda: not e._thread.is_alive(), 30.0)  # (its map drawn: a click
    e.run_btn.value = True  # while it draws runs nothing)
    done = lambda: "on the Pareto front" in e.progress.content and "⚠" not in e.progress.content  # noqa: E731
    assert wait_for(done, 120.0), e.progress.content


def test_a_reload_takes_only_the_steps_of_the_tab_that_wrote_the_design(app, monkeypatch):
    """A review: tabs of one browser share the working design and the Undo steps, and a
    tab that rewrote the design without a step of its own (the preset on screen clicked
    again) left the other tab's steps beside it: after a reload, Undo led into that
    tab's designs. Each tab's writes say which tab made them (storage.PAIR_KEY); a
    reload takes steps only from the tab that wrote the design, and carries them on
    as its own."""
    from app import history
    from app.layout import HISTORY_BUTTONS

    monkeypatch.setattr(history, "SETTLE_S", 0.0)  # each change a step
    shared: dict[str, str] = {}
    with restored_tab(app, monkeypatch, shared, shared) as a:
        with restored_tab(app, monkeypatch, shared, shared) as b:
            a.ui.controls["cam.base_radius_mm"].value = 90.0
            a.ui.controls["cam.base_radius_mm"].value = 95.0
            b.load_preset("paper_example")  # on screen already: no step of B's
    with restored_tab(app, monkeypatch, shared, shared) as c:
        assert c.design == load_preset("paper_example")  # B's design, the last written
        assert c.history.past == [] and c.history.future == []  # A's steps are A's
    with restored_tab(app, monkeypatch, shared, shared) as d:
        d.ui.controls["cam.base_radius_mm"].value = 85.0  # D's own step
    for _ in range(2):  # the steps come back, and a reloaded tab keeps them as its own
        with restored_tab(app, monkeypatch, shared, shared) as e:
            assert e.design.cam.base_radius_mm == 85.0
            e.travel(HISTORY_BUTTONS[0])
            assert e.design.cam.base_radius_mm == 80.0
            e.travel(HISTORY_BUTTONS[1])
            assert e.design.cam.base_radius_mm == 85.0


def test_undo_and_redo_survive_a_reload(app, monkeypatch):
    """Nothing the user made is lost: a reload had kept the design but not its steps
    back (Undo said "nothing to undo"). The tab writes Undo's and Redo's designs
    when a step is made or taken (not at each value of a drag, which joins one
    step), and a new tab takes them back, each parsed like a file: a tampered step is
    left out, the others still count."""
    from app import history, storage
    from app.layout import HISTORY_BUTTONS

    writes: dict[str, str] = {}
    with restored_tab(app, monkeypatch, {}, writes) as s:
        monkeypatch.setattr(history, "SETTLE_S", 0.0)  # each change a step
        lifts = (16.0, 17.0, 18.0)
        for h in lifts:
            s.ui.controls["motion.lift_mm"].value = h
        s.travel(HISTORY_BUTTONS[0])  # undo: 18 -> 17, one step to redo
        assert s.design.motion.lift_mm == 17.0
        keys: list[str] = []  # what is written, in order
        sink = storage.BrowserStore.write
        monkeypatch.setattr(
            storage.BrowserStore, "write", lambda st, k, v: keys.append(k) or sink(st, k, v)
        )
        monkeypatch.setattr(history, "SETTLE_S", 60.0)  # a drag: one step
        for h in (17.5, 17.6, 17.7):
            s.ui.controls["motion.lift_mm"].value = h
        kept = writes[storage.HISTORY_KEY]
        assert keys.count(storage.WORKING_KEY) == 3  # the design at each value ...
        assert keys.count(storage.HISTORY_KEY) == 1  # ... the steps once: the drag's
    past, future = storage.parse_history(kept)
    assert [d.motion.lift_mm for d in past] == [15.0, 16.0, 17.0]
    assert future == []  # (the drag's new step emptied Redo)
    stored = {storage.WORKING_KEY: writes[storage.WORKING_KEY], storage.HISTORY_KEY: kept}
    with restored_tab(app, monkeypatch, stored) as s:
        assert s.design.motion.lift_mm == 17.7
        assert "3 steps to undo" in s.ui.history_md.content
        s.travel(HISTORY_BUTTONS[0])
        assert s.design.motion.lift_mm == 17.0
        s.travel(HISTORY_BUTTONS[0])
        assert s.design.motion.lift_mm == 16.0
        s.travel(HISTORY_BUTTONS[1])  # redo
        assert s.design.motion.lift_mm == 17.0
    data = json.loads(kept)
    data["past"][1] = data["past"][1].replace('"lift_mm": 16.0', '"lift_mm": -4.0')
    data["past"].insert(0, {"not": "a design"})
    past, _ = storage.parse_history(json.dumps(data))
    assert [d.motion.lift_mm for d in past] == [15.0, 17.0]
    for junk in ("[1]", "{", '{"past": 3}', "x" * (storage.MAX_HISTORY_CHARS + 1)):
        assert storage.parse_history(junk) == ([], [])
