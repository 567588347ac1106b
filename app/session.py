"""One browser tab: its design, its analysis, and what it shows.

Data flows one way: controls -> Design -> camcore.analysis.analyze -> views. The
session owns the state of a tab and composes the parts that do the work:
app.layout (the widgets), app.segments (the program table), app.scene (the 3D
view), app.plots / app.compare (the curves), app.panels (the words), app.ticker
(animation and background loops), app.storage (the browser's own storage).

All state is guarded by one re-entrant lock: viser runs plain callbacks in a thread
pool, and a value the session writes into a widget calls that widget's callback
inline.
"""

from __future__ import annotations

import contextlib
import json
import logging
import math
import secrets
import threading
import time

from pydantic import ValidationError

from camcore import checks, export
from camcore.analysis import Analysis
from camcore.model import (
    MAX_DESIGN_BYTES,
    Design,
    DesignError,
    defaulted_fields,
    defaults_note,
    design_to_json,
    edited_note,
    format_validation_error,
    name_follows_kind,
    preset_names,
)
from camcore.model import load_preset as load_preset_design
from camcore.report import jump_speed_text

from . import controls, plots, storage
from .analyst import Analyst, Result
from .history import MOST as HISTORY_MOST
from .history import History
from .layout import (
    DEFAULT_PRESET,
    HISTORY_BUTTONS,
    NARROW_PANEL_PX,
    PAUSE_AT_STATION_S,
    SPEED_MAX_DEG_S,
    SPEED_MIN_DEG_S,
    STEP_DEG,
    Layout,
    build_layout,
    preset_labels,
    wide_panel_px,
)
from .panels import (
    WHERE_LINES,
    WIDE_WHERE_LINES,
    esc,
    file_stem,
    headline_html,
    in_words,
    low_dwell_text,
    nearest_index,
    status_html,
    summary_markdown,
    where_markdown,
)
from .scene import (
    CAMERA_VIEWS,
    DEFAULT_FRAME,
    SceneView,
    camera_for,
    closeup_extent,
    label_height,
)
from .ticker import Debouncer, Ticker
from .uploads import MAX_UPLOAD_BYTES

FPS = 30.0
# the design-changing actions that take turns (Session._take_ticket): the controls, the
# program table, and the buttons that replace the whole design
TICKETS = ("controls", "segments", "replace")
SILENT_NOTE = (
    "✖ This browser's storage did not answer: this tab's work is not kept in the "
    "browser, and designs cannot be saved in it. Reload the page to try again (download "
    "a design to keep it meanwhile)."
)
_UNREAD = "(not read yet)"  # Session._kept_program before the restore (never a program's JSON)
UNFINISHED_NOTE = (
    "The segment table's unfinished program is back as it was left (Design › Motion "
    "program › Program segments; not yet a valid design: the status says why, and the "
    "design on screen is the last valid one)."
)
# Background work (the verified analysis and the comparison: ~0.1 s each) waits until a
# tab has been still this long, and runs for one tab at a time across the server.
SETTLE_S = 0.6
# how soon after a value typed beyond a slider's end the same end arriving is taken for
# the browser's clamp (Session._note_arrival) [s]: a Tab follows a keystroke within it
CLAMP_WINDOW_S = 1.0
BACKGROUND = threading.BoundedSemaphore(1)
# Re-analyses of all tabs run one at a time. Many threads each making many short numpy
# calls (each releases and retakes the GIL) convoy: with 30 tabs at once every call
# waits a GIL switch interval, and the server did a third of the work it could. Taken
# last (inside a tab's lock, never the other way round), re-entrant for inline callbacks.
FOREGROUND = threading.RLock()


# for a class holding the paper (a teacher's review: "the paper says 177.4°")
STATION_3_NOTE = (
    " Where the rise face leaves the high-dwell arc (the paper's station 3) we use "
    "θ₃ = βᵣ + βₕ − 2ψₕ: the paper prints + 2ψₕ, which would put station 3 after "
    "station 4 (βᵣ + βₕ); its own geometry (A₃ = B₄, Eq. 24) gives − 2ψₕ (README, "
    "*Station 3*)."
)


class Session:
    """Everything one client sees. ``client`` is a viser ClientHandle; ``animate``
    False starts no background loops (tests and the bench drive them by hand)."""

    def __init__(
        self,
        client,
        design: Design | None = None,
        animate: bool = True,
        analyst: Analyst | None = None,
    ):
        self.client = client
        self.analyst = analyst or Analyst(processes=False)  # the physics (app.analyst)
        self.lock = threading.RLock()
        self.closed = threading.Event()
        self.base = design or load_preset_design(DEFAULT_PRESET)
        self.design = self.base
        first = self.analyst.fast(self.base)
        self.analysis: Analysis = first.analysis
        self.error: str | None = None  # the input's error; the last valid design stays
        # a file (upload, preset) that could not be opened: shown like an input error,
        # but the controls still describe the design on screen, so downloads go on
        self.file_error: str | None = None
        self.verified = False  # self.analysis is the geometrically checked one
        self.cutter_note: str | None = None  # the cutter gouges (found with the check)
        self.headline = ""  # the design's headline figures (panels.headline_html)
        self.proposed_rate: float | None = None  # [N/m] the key numbers' spring proposal
        self.jump_rpm: float | None = None  # their jump speed (None: it never jumps)
        self.gen = 0  # bumped by every new design: background results of older ones drop
        self.theta_deg = 0.0
        self.speed = 45.0  # animation, cam degrees per second
        self.camera_view = "Front"  # a preset of scene.CAMERA_VIEWS
        self.panel_px = NARROW_PANEL_PX  # the control panel's width (set_wide_panel)
        self._framed_size = _size(self.analysis)  # the cam's size the camera last framed
        self._diagram_of: Design | None = None  # the design of the stations diagram shown
        self._held = 0.0  # seconds the animation still stays at a station
        self._resumed = False  # the stop at a station has just ended
        self._seen: tuple | None = None  # the last camera message: (pose, width, height)
        self._preset_pose: tuple = ()  # where the preset view put the camera
        self._extent: tuple = (None, (0.0, 0.0))  # (analysis, its closeup_extent)
        self.station_events: list[str] = []  # what happens at each station, in words
        self.station_faces: list[list[str]] = []  # the faces touching just after each
        self.store = storage.BrowserStore(client)
        self.saved: dict[str, str] = {}  # name -> design JSON, kept in the browser
        self._tab_id = secrets.token_hex(8)  # (storage.PAIR_KEY)
        # (name, design): a Save of that design under that kept name replaces it
        self._replace_armed: tuple[str, Design] | None = None
        self._persist = False  # on once the browser's stored design has been read
        self._steps_read = False  # ... and its Undo and Redo steps taken back
        self._steps_written = -1  # the history's version last written to the browser
        self._view_edits = 0  # the user's view changes (a kept view never overrides one)
        self.history = History()  # the designs before and after the one on screen
        self._travelling = False  # True while undo or redo replaces the design
        self._syncing = False  # True while the session writes into its own widgets
        self._syncer: int | None = None  # the thread that does (_quiet)
        self._busy = threading.Lock()  # a download being made (one at a time)
        self._drawing = threading.Lock()  # the stations diagram being drawn (one at a time)
        self._unread: dict = {}  # saved-list entries this version could not read (kept)
        # held by the save or delete that re-reads the browser's list (outside the lock)
        self._storage_turn = threading.Lock()
        self._aside: str | None = None  # a working design set aside as unreadable
        # the program table's segments while they do not make a valid design: another
        # control's edit keeps them (it had dropped them for the last valid program)
        self._typed_program: list[dict] | None = None
        # the browser's copy of it (_keep_typed): _UNREAD until the restore has read it
        self._kept_program: str | None = _UNREAD
        self._ticket_lock, self._tickets = threading.Lock(), dict.fromkeys(TICKETS, 0)
        self._waiting: set[str] = set()  # the kinds of action with a thread waiting its turn
        # each slider's latest values as they arrived: (value, time.monotonic(), the
        # slider's min and max then)
        self._arrived: dict[str, list[tuple[float, float, float, float]]] = {}
        self._unclamp: dict[str, tuple[float, float]] = {}  # (typed, clamped)
        self.ticker = Ticker(self._tick, FPS, name=f"cam-animate-{id(self)}")
        self.refiner = Debouncer(self.refine, SETTLE_S, BACKGROUND, name=f"cam-refine-{id(self)}")
        with self.lock:
            self.ui: Layout = build_layout(client.gui, self.base, self.analysis, self.speed)
            self._wire(self.ui)
            self.view = SceneView(client.scene)
            client.scene.set_up_direction("+y")
            client.camera.on_update(self._on_camera)
            self._apply(self.base, first, reset_camera=True)
        self._restorer = threading.Thread(
            target=self._restore, daemon=True, name=f"cam-restore-{id(self)}"
        )
        self._restorer.start()
        if animate:
            self.ticker.start()
            self.refiner.start()

    def _wire(self, ui: Layout) -> None:
        """Connect the widgets to the session's actions."""
        ui.quick_stl_btn.on_click(lambda _: self.download("stl", quick=True))
        ui.play_btn.on_click(lambda _: self.toggle_play())
        ui.speed_slider.on_update(lambda e: self._set_speed(e.target.value))
        ui.angle_slider.on_update(lambda e: self._on_angle(e.target.value))
        ui.stations_btn.on_click(lambda e: self.goto_station(e.target.value))
        ui.step_btns.on_click(lambda e: self.step(e.target.value))
        ui.history_btns.on_click(lambda e: self.travel(e.target.value))
        for path, h in ui.controls.items():
            h.on_update(lambda _e, p=path: self.on_control(p))
        ui.segments.on_change, ui.segments.lock = self.on_segments, self.lock
        for name, cb in ui.overlay_boxes.items():
            cb.on_update(lambda e, n=name: self._set_overlay(n, e.target.value))
        ui.view_btns.on_click(lambda e: self.set_camera_view(e.target.value))
        ui.wide_box.on_update(lambda e: self.set_wide_panel(bool(e.target.value)))
        ui.pause_box.on_update(lambda _: self._end_pause())
        ui.camera_btn.on_click(lambda _: self.reset_camera())
        ui.stations_fig_btn.on_click(lambda _: self.show_stations_diagram())
        presets = preset_labels()  # label shown -> shipped name (load_preset checks it)
        ui.preset_btn.on_click(
            lambda _: self.load_preset(presets.get(ui.preset_dd.value, str(ui.preset_dd.value)))
        )
        ui.upload_btn.on_upload(lambda e: self.upload(e.target.value.name, e.target.value.content))
        ui.save_btn.on_click(lambda _: self.save_named(ui.save_name.value))
        ui.open_saved_btn.on_click(lambda _: self.open_saved(ui.saved_dd.value))
        ui.delete_saved_btn.on_click(lambda _: self.delete_saved(ui.saved_dd.value))
        ui.aside_btn.on_click(lambda _: self.download_set_aside())
        ui.spring_btn.on_click(lambda _: self.use_proposed_spring())
        for kind, b in ui.download_btns.items():
            b.on_click(lambda _, k=kind: self.download(k))
        ui.explore.bind(
            self.analyst,
            lambda: self.design,
            self.set_design,
            lambda name, data: self.client.send_file_download(name, data, save_immediately=True),
            lambda: self.error is not None,
        )

    # --- design changes -------------------------------------------------------------
    def on_control(self, path: str | None = None) -> None:
        """Any design control changed (``path``: which): rebuild the design from all
        controls.

        Changes coalesce: each callback takes a ticket, and only the newest ticket
        redraws (it reads every control's latest value), so a burst of slider events
        queued on the lock costs one analysis, not one per event.
        """
        if self._syncing and self._syncer == threading.get_ident():
            return  # our own write into a control (no ticket: a waiting edit stays newest)
        if path is not None:
            self._note_arrival(path)
        if not self._queue("controls"):
            return  # (the one waiting reads this change too)
        with self.lock:
            self._turn("controls")
            if self._syncing or self.closed.is_set():
                return
            undone = self._undo_clamps()
            self._widen_sliders()
            values = self._greyed_back(self._values())
            # an unfinished program in the table stays (with this edit) until it is valid
            design, err = controls.try_design(self.base, values, self._typed_program)
            if design is None:
                self._show_error(err)
                self.ui.low_dwell_md.content = low_dwell_text(values)  # e.g. "negative"
                self._keep_edit_beside_program(values)
                self._tell_undone(undone)
                return
            self.error = self.file_error = None
            if self._typed_program is not None:  # the table's program, valid at last:
                self.base = design  # the program from now on
                self._keep_typed(None)
                # the classic sliders show this program (their stale values had
                # reverted it at the next edit); no other control: a user's next edit
                # may already sit in one
                self._sync_controls(design, prefix="motion.")
            design = self._renamed_for_kind(design)
            self._follow_name(self.design.name, design.name)
            self._apply(design)
            self._tell_undone(undone)

    def _tell_undone(self, undone: list[str]) -> None:
        """Say, under the quick download button at the top (after the redraw, which
        clears it), which clamps _undo_clamps took back. Lock held."""
        if undone:
            self.ui.quick_md.content = "ℹ " + " ".join(undone)

    def use_proposed_spring(self) -> None:
        """Put the spring rate the key numbers propose (machine.spring's proposal, at
        the design's preload) into the design, as an edit Undo takes back; or say why
        there is none to put."""
        with self.lock:
            say, rate, d = self.ui.spring_md, self.proposed_rate, self.design
            if self.error is not None:
                say.content = "✖ The input is invalid (see the red panel): fix it first."
                return
            if rate is None:
                say.content = (
                    "✖ No spring rate keeps contact at this preload: where the follower "
                    "is pulled off, the spring has no force to hold it. Raise the preload "
                    "s_p (or lessen what pulls it off)."
                )
                return
            if rate == d.dynamics.spring_rate_N_per_m:
                say.content = f"The spring rate is the proposal already: {rate:g} N/m."
                return
            none = " (no spring is needed: nothing pulls the follower off)" if rate == 0 else ""
            data = d.model_dump()
            data["dynamics"]["spring_rate_N_per_m"] = rate
            try:  # (validated: a review's proposal of 7.3e10 N/m passed the field's 1e9)
                design = Design.model_validate(data)
            except ValidationError as exc:
                why = esc(format_validation_error(exc))
                say.content = (
                    f"✖ The proposal, {rate:g} N/m, is no spring rate here: {why}. A "
                    "larger preload s_p needs a smaller rate."
                )
                return
            before = jump_speed_text(self.jump_rpm)
            self.set_design(design, reset_camera=False)
            say.content = (
                f"Spring rate k: {d.dynamics.spring_rate_N_per_m:g} → {rate:g} N/m{none}; "
                f"jump speed {before} → {jump_speed_text(self.jump_rpm)} (Undo takes it back)."
            )

    def travel(self, label: str) -> None:
        """Undo or redo (layout.HISTORY_BUTTONS) a change of the design: the whole
        design as it was, controls and program table with it. Anything else (a hostile
        client's value) and a step with nothing to go to do nothing."""
        if label not in HISTORY_BUTTONS:
            return
        with self.lock:
            pending = self.error is not None or self._typed_program is not None
            if label == HISTORY_BUTTONS[0] and pending:
                # an input error or an unfinished program undone: the design on screen,
                # the last valid one, and no step of the history (a designer's review:
                # Undo had also taken back the valid change made before the typing)
                self.history.drop_same(self.design)
                design: Design | None = self.design
            else:
                step = self.history.undo if label == HISTORY_BUTTONS[0] else self.history.redo
                design = step(self.design)
            self.ui.history_md.content = self.history.text()  # (also when none is left)
            if design is None:  # said, not silent (a teacher's review after a reload)
                self.ui.history_md.content = _nothing_to(label, self.history.text())
                return
            self._travelling = True
            try:
                self.set_design(design, reset_camera=False)
            finally:
                self._travelling = False
            self.ui.history_md.content = self.history.text()

    def _take_ticket(self, kind: str) -> int:
        """A turn of the design-changing action ``kind`` (TICKETS); only the newest of a
        kind redraws when the lock comes free: each one reads, or carries, everything
        its older ones did. Taken before the lock is waited for."""
        with self._ticket_lock:
            self._tickets[kind] += 1
            return self._tickets[kind]

    def _queue(self, kind: str) -> bool:
        """Take a ticket of ``kind`` (TICKETS, or "camera", which counts no edit),
        and whether this thread is to wait for the lock: False if one of this
        tab's threads already waits its turn for the same kind of action, which reads the
        widgets' values as they are once it holds the lock, this change with them. So a
        burst of events is one turn, not one per event (a security review: tabs sending
        20 updates a second of a costly design had parked all 32 threads of viser's
        shared pool, and every other tab waited 17 s; a tab's callbacks now also wait in
        its own lane, app.inbound.TabLanes). ``_turn`` once the lock is held."""
        with self._ticket_lock:
            self._tickets[kind] = self._tickets.get(kind, 0) + 1
            if kind in self._waiting:
                return False
            self._waiting.add(kind)
            return True

    def _turn(self, kind: str) -> None:
        """The lock is held: a later action of ``kind`` waits for a turn of its own."""
        with self._ticket_lock:
            self._waiting.discard(kind)

    def _edits(self) -> int:
        """How many edits of the controls or the program table the user has begun in
        this tab (their tickets, taken before the lock is waited for), valid or not. A
        file, preset or saved design counts only once it replaces the design (``gen``):
        a click that opened nothing is no edit (a review: it had cancelled the restore)."""
        with self._ticket_lock:
            return self._tickets["controls"] + self._tickets["segments"]

    def _superseded(self, kind: str, mine: int) -> bool:
        """Whether a newer action of ``kind`` came while ticket ``mine`` waited."""
        with self._ticket_lock:
            return self._tickets[kind] != mine

    def _greyed_back(self, values: dict[str, object]) -> dict[str, object]:
        """``values`` with each greyed control's as the design on screen has it, and
        that control shown so: a greyed slider takes no edit, but viser leaves its
        number box enabled (a review typed a lift of 40 beside an unfinished program:
        nothing changed on screen, and a reload brought back a folded cam never
        shown). Lock held."""
        back = {}
        for spec in controls.SPECS:
            h = self.ui.controls[spec.path]
            if h.disabled:
                v = controls.control_value(self.design, spec)
                if v is not None and values[spec.path] != v:
                    back[spec.path] = v
        if back:
            with self._quiet():
                for path, v in back.items():
                    self.ui.controls[path].value = v
        return {**values, **back}

    def _keep_edit_beside_program(self, values: dict[str, object]) -> None:
        """An edit of another control while the table's program is unfinished: the
        browser keeps it with the last valid program as the working design, so that a
        reload brings back both the edit and the unfinished program (a review: the edit
        was lost). Lock held."""
        if self._typed_program is None or not self._persist:
            return
        kept, _ = controls.try_design(self.base, values)
        if kept is not None:
            self.store.write(storage.WORKING_KEY, design_to_json(kept))
            self._pair_program()

    def _renamed_for_kind(self, design: Design) -> Design:
        """A new follower kind renames the follower the design's name mentions ("...
        (double concave faces)" -> "... (single roller)", camcore.model.renamed_for_kind),
        unless the name was edited too; the name box follows. Lock held."""
        renamed = name_follows_kind(design, self.design.follower.kind, self.design.name)
        if renamed.name != design.name:
            with self._quiet():  # (the box's own change must not start another edit)
                self.ui.controls["name"].value = renamed.name
        return renamed

    def on_segments(self, segs: list[dict] | None) -> None:
        """The program table changed: the program is its segments (None: the table as
        it stands when this edit's turn comes, read after its ticket), every other
        control as it is. Invalid input keeps the last valid design and shows the
        user's edit. The newest edit of a burst is the one made (a review's 40 law
        changes had cost 37 analyses, and another tab its connection)."""
        if self._syncing and self._syncer == threading.get_ident():
            return
        if segs is None:  # (the table as it stands at its turn: one waiting reads all)
            if not self._queue("segments"):
                return
        else:
            mine = self._take_ticket("segments")
        with self.lock:
            if segs is None:
                self._turn("segments")
            elif self._superseded("segments", mine):
                return  # (a newer change came while this one waited its turn)
            if self._syncing or self.closed.is_set():
                return
            self._segments(self.ui.segments.current() if segs is None else segs)

    def _segments(self, segs: list[dict]) -> None:
        """on_segments' work, lock held and no ticket taken (the restore's kept program
        must not supersede a user's table edit waiting on the lock: a review)."""
        design, err = controls.try_design(self.base, self._values(), segs)
        if design is None:
            self._keep_typed(segs)  # kept through other edits until it is valid
            self.ui.segments.show(segs)
            self._show_error(err)
            return
        self.set_design(design, reset_camera=False)

    def _keep_typed(self, segs: list[dict] | None) -> None:
        """The table's unfinished program (None: there is none), kept in the browser
        too, so that a reload brings it back (the working design is the last valid
        one). The browser's copy follows whatever it held (``_kept_program``, read at
        the restore): a review found an old one left there, replacing a later design
        at a later reload. The classic sliders wait while the table is unfinished (the
        table's program, not theirs, is the one being edited). Lock held."""
        if segs is None and self.ui.files_md.content == UNFINISHED_NOTE:
            self.ui.files_md.content = ""  # (it is finished now)
        text = None if segs is None else json.dumps(segs)
        unread = self._kept_program == _UNREAD  # (then nothing is emptied: not seen yet)
        if self._persist and text != self._kept_program and not (unread and text is None):
            self._write_program(text)
        self._typed_program = segs
        classic = self.base.motion.classic is not None
        for path, h in self.ui.controls.items():
            if path.startswith("motion."):
                h.disabled = segs is not None or not classic

    def set_design(
        self, design: Design, reset_camera: bool = True, save_as: str | None = None
    ) -> None:
        """Replace the whole design (preset, upload, program table): controls follow.
        ``save_as``: the name to propose for keeping it in this browser (a design
        opened from a file, a preset, a save), in place of what the box holds; None
        keeps what the user typed there (an edit, a design loaded from Explore)."""
        with self.lock:
            old_name = self.design.name
            self.base, self.error, self.file_error = design, None, None
            self._keep_typed(None)
            self._sync_controls(design)
            if design == self.design:  # on screen already: everything but the analysis
                self._reshow(design, reset_camera)  # (a review: 30 clicks, 30 analyses)
            else:
                self._apply(design, reset_camera=reset_camera)
            if save_as is not None:  # (the box had read "my cam" whatever the design)
                self._propose_name(save_as)
            else:  # (an Undo of a rename: a review)
                self._follow_name(old_name, design.name)

    def _reshow(self, design: Design, reset_camera: bool) -> None:
        """The design on screen set again (a preset or file reloaded, an input error
        undone): the controls are written already; the table, the kind's controls, the
        status and the browser's copy follow, as after an analysis. Lock held."""
        ui = self.ui
        with self.client.atomic():
            self._enable_for_kind(design)
            ui.segments.show(design.motion.segments)
            ui.low_dwell_md.content = low_dwell_text(self._values(), design)
            self._show_status()
        self._save_working()
        if reset_camera:
            self.reset_camera()

    def _follow_name(self, old: str, new: str) -> None:
        """The Save box follows the design's name while it proposes the old one (a
        review renamed a design, and Save kept it under the preset's name); a name the
        user typed there stays. Lock held."""
        if new != old and self.ui.save_name.value == storage.proposed_name(old):
            self._propose_name(new)

    def _propose_name(self, name: str) -> None:
        """The name the Save box proposes for the design on screen. Lock held."""
        self.ui.save_name.value = storage.proposed_name(name)

    def _note_arrival(self, path: str) -> None:
        """Note a slider's value as it arrives, before any wait for the lock (a later
        edit may supersede this one's turn). A value on the slider's own end that comes
        within CLAMP_WINDOW_S of one typed beyond that end is the browser's number box
        cutting it back as it loses focus, before the widened range (_widen_sliders)
        reached it: a review typed a lift of 70 on a 60 mm slider and tabbed away at
        once, and the 60 mm cam was drawn without a word (2 tries of 4). Marked to undo,
        and the undo is said (_tell_undone): a user who went back to the end at once (a
        typo's 600 taken back to 60, a review) reads to type it again. Both cases look
        alike from here, and the other choice would leave the clamp silent whenever the
        slider's end is the last value typed beyond it (a widened range ends there). A
        value typed on purpose passes through others ("6", "60")."""
        spec, h = controls.SPEC_BY_PATH.get(path), self.ui.controls[path]
        if spec is None or spec.widget != "slider" or not isinstance(h.value, int | float):
            return
        v, now = float(h.value), time.monotonic()
        with self._ticket_lock:
            seen = self._arrived.get(path, [])
            self._arrived[path] = [*seen[-7:], (v, now, h.min, h.max)]
            # the arrivals within the window, each with the range it met: the browser
            # clamps to one of those (the newest may not have reached it yet)
            recent = [x for x in seen if now - x[1] <= CLAMP_WINDOW_S]
            if not recent or recent[-1] is not seen[-1]:
                return
            typed = recent[-1][0]
            beyond = (typed > v and v in {x[3] for x in recent}) or (
                typed < v and v in {x[2] for x in recent}
            )
            if beyond:
                self._unclamp[path] = (typed, v)
            else:
                self._unclamp.pop(path, None)

    def _undo_clamps(self) -> list[str]:
        """Put back the values the browser cut back (_note_arrival), into the controls
        and so into the tab's boxes; returns a sentence for each, to show. Lock held."""
        with self._ticket_lock:
            undo, self._unclamp = self._unclamp, {}
        said = []
        with self._quiet():
            for path, (typed, clamped) in undo.items():
                h = self.ui.controls[path]
                if h.value == clamped:  # (not changed again since)
                    h.value = typed
                    said.append(
                        f"{controls.SPEC_BY_PATH[path].label}: {typed:g} stands. The "
                        f"{clamped:g} that came just after it, as the box lost focus, "
                        "was taken for the browser cutting it back to the slider's end; "
                        f"to have {clamped:g}, type it again."
                    )
        return said

    def _widen_sliders(self) -> None:
        """A value typed into a slider's box beyond its range widens the range: the
        browser would otherwise cut it back to the end at its next redraw and send that,
        changing the design silently (70 mm typed for a 60 mm slider became 60 mm at
        the next, unrelated edit). The same rule as for a loaded design (_sync_controls);
        once the value is back inside, the slider returns to its own range."""
        for spec in controls.SPECS:
            h, v = self.ui.controls[spec.path], self.ui.controls[spec.path].value
            if spec.widget != "slider" or not isinstance(v, int | float) or not math.isfinite(v):
                continue
            assert spec.lo is not None and spec.hi is not None  # (every slider has a range)
            lo, hi = min(spec.lo, v), max(spec.hi, v)  # back to its own range once fixed
            if (h.min, h.max) != (lo, hi):
                h.min, h.max = lo, hi

    @contextlib.contextmanager
    def _quiet(self):
        """While the session writes into its own widgets: their callbacks, which viser
        runs at once in this thread, do nothing. (They must not take an edit's ticket
        either: a user's edit waiting on the lock would be dropped as superseded.)
        Lock held."""
        self._syncing, self._syncer = True, threading.get_ident()
        try:
            yield
        finally:
            self._syncing, self._syncer = False, None

    def _values(self) -> dict[str, object]:
        return {p: h.value for p, h in self.ui.controls.items()}

    def _sync_controls(self, design: Design, prefix: str = "") -> None:
        """Write the design's values into the controls (firing no change); only those
        whose path starts with ``prefix``."""
        with self._quiet():
            classic = design.motion.classic is not None
            for spec in controls.SPECS:
                if not spec.path.startswith(prefix):
                    continue
                h, v = self.ui.controls[spec.path], controls.control_value(design, spec)
                if spec.path.startswith("motion."):
                    # other programs are edited as segments: the classic sliders go
                    # (greyed, they had shown a stale program and still taken typing)
                    h.disabled, h.visible = not classic, classic
                if v is None:
                    continue
                if spec.widget == "slider":
                    h.min, h.max = min(h.min, v), max(h.max, v)
                h.value = v

    def _apply(self, design: Design, r: Result | None = None, reset_camera: bool = False) -> None:
        """Analyse (fast path, no verification; in the analyst's worker, so that other
        tabs redraw meanwhile) and redraw everything. Lock held."""
        r = self.analyst.fast(design) if r is None else r
        with FOREGROUND:
            self._redraw(design, r, reset_camera)
        self.refiner.poke()

    def _redraw(self, design: Design, r: Result, reset_camera: bool) -> None:
        a, s = r.analysis, r.summary
        if design != self.design and not self._travelling:
            self.history.record(self.design, time.monotonic())
        self.design, self.analysis = design, a
        self.gen += 1
        self.verified, self.cutter_note = False, None
        k = self._index()
        ui = self.ui
        with self.client.atomic():
            ui.explore.offer_fields(design)  # (a program of segments: their angles)
            self.view.build(a)
            self.view.pose(k)
            self._show_curves(r.curves, k)
            plots.relabel_limits(ui.curves, a)
            self._enable_for_kind(design)
            ui.segments.show(design.motion.segments)
            self._show_station_buttons(a)
            if ui.stations_img is not None and design != self._diagram_of:
                ui.stations_img.remove()  # of another design: the button draws it again
                ui.stations_img = None
                ui.stations_fig_md.content = ""
            ui.low_dwell_md.content = low_dwell_text(self._values(), design)
            if ui.spring_md.content:  # (said of an earlier design; use_proposed_spring
                ui.spring_md.content = ""  # writes its line after this redraw)
            if ui.quick_md.content and ui.quick_md.content != SILENT_NOTE:
                ui.quick_md.content = ""  # it spoke of the design before this one
            self._show_summary(s)
            ui.where_md.content = self._where(k)
            ui.history_md.content = self.history.text()
            self._show_status()
        self._save_working()
        if reset_camera or not 1 / REFRAME < _size(a) / self._framed_size < REFRAME:
            self.reset_camera()  # (r_b 80 -> 5000 mm had put the camera inside the cam)

    def _show_curves(self, data: plots.CurveData, k: int) -> None:
        at = math.degrees(self.analysis.theta[k])
        for c, ys, shade in zip(self.ui.curves, data.ys, data.shades, strict=True):
            c.show(data.x, ys, shade, at, data.stations, data.shared)

    def _enable_for_kind(self, design: Design) -> None:
        k, c = design.follower.kind, self.ui.controls
        for name in ("face_radius_mm", "roller_radius_mm", "offset_mm", "single_offset_mm"):
            c[f"follower.{name}"].disabled = not k.uses(name)

    def _show_error(self, err: str | None) -> None:
        self.error = err
        self._show_status()

    def _show_file_error(self, err: str | None) -> None:
        self.file_error = err
        self._show_status()

    def _file_error_seen(self) -> None:
        """The user went on to another file action: a refused file's box goes (a
        review: it stayed through downloads, their answer under it). Lock held."""
        if self.file_error is not None:
            self._show_file_error(None)

    def _show_status(self) -> None:
        a = self.analysis
        self.ui.status.content = status_html(
            self.error,
            list(a.violations),
            a.lift_error,
            self.verified,
            self.view.mesh_error,
            self.file_error,
            self.cutter_note,
            self.headline,
            checks.accepted_jumps(a.design),
        )

    def _show_summary(self, s: dict) -> None:
        """Key numbers, and what happens at each station in words (for where_md)."""
        self.ui.summary_md.content = summary_markdown(s)
        self.headline = headline_html(s)  # shown with the status (_show_status)
        self.proposed_rate = s["spring_proposal"]["spring_rate_N_per_m"]  # (None: inf)
        self.jump_rpm = s["jump_speed_rpm"]
        self.station_events = [st["event"] for st in s["stations"]]
        self.station_faces = [st["contacts"] for st in s["stations"]]

    def _show_station_buttons(self, a: Analysis) -> None:
        names = tuple(str(i) for i in range(len(a.stations)))
        if tuple(self.ui.stations_btn.options) != names:
            self.ui.stations_btn.options = names
        # each station's angle (a teacher's review: the buttons said nothing of where
        # they go), under them, not as their hint (it covered the step buttons)
        text = (
            '<div style="font-size: 0.7em; line-height: 1.2; margin-top: -0.6em">at θ = '
            + " · ".join(f"{i}: {math.degrees(t):.1f}°" for i, t in enumerate(a.stations))
            + "</div>"
        )
        if self.ui.stations_md.content != text:
            self.ui.stations_md.content = text

    # --- background: the verified analysis and the comparison ------------------------
    def refine(self) -> None:
        """Verify the design on screen and compare the four followers (run by the
        refiner once the tab is still; results of a design changed meanwhile drop)."""
        with self.lock:
            design, gen = self.design, self.gen
        r = self.analyst.refined(design)
        with self.lock, FOREGROUND:
            if self._stale(gen):
                return
            old = [(v.code, v.ranges_deg) for v in self.analysis.violations]
            self.analysis, self.verified, self.cutter_note = r.analysis, True, r.cutter
            if [(v.code, v.ranges_deg) for v in r.analysis.violations] != old:
                self.view.build(r.analysis)
                self._show_curves(r.curves, self._index())
            self._show_summary(r.summary)
            self._show_status()
            self.ui.compare_view.update(
                r.compare,
                r.analysis.design,
                math.degrees(self.analysis.theta[self._index()]),
                r.curves.stations,
            )

    def _stale(self, gen: int) -> bool:
        with self.lock:
            return gen != self.gen or self.closed.is_set()

    # --- files: presets, uploads, downloads ----------------------------------------
    def load_preset(self, name: str) -> None:
        # viser does not check a dropdown's value against its options: only a shipped
        # name is looked up (camcore.model.load_preset never joins it onto a path)
        if name not in preset_names():
            return self._say(f"✖ No preset {esc(str(name)[:60])}.")
        mine = self._take_ticket("replace")
        try:
            d = load_preset_design(name)
        except DesignError as exc:
            with self.lock:
                return self._show_file_error(f"preset {name}: {exc}")
        self._replace(d, d.name, f"Loaded the preset *{esc(d.name)}* ({esc(name)}).", mine)

    def upload(self, name: str, content: bytes) -> None:
        mine = self._take_ticket("replace")  # (before the parse: see _replace)
        name = _short(name)  # (a client's file name: shown, so bounded)
        d = storage.open_untrusted(content)
        if isinstance(d, str):
            with self.lock:
                if self._superseded("replace", mine):
                    return  # (a file opened after this one is on screen)
                self._show_file_error(f"{name or 'the upload'}: {d}")
            return self._say(f"✖ Could not open **{esc(name)}**: {esc(d)}")
        left_out = defaulted_fields(content, d)
        note = f" ⚠ {esc(defaults_note(left_out))}." if left_out else ""
        self._replace(d, d.name, f"Opened **{esc(name)}** ({esc(d.name)}).{note}", mine)

    def _replace(self, design: Design, save_as: str, said: str, mine: int) -> None:
        """Replace the whole design from a button (a preset, a file, a saved design) and
        say ``said``; ``mine``: the "replace" ticket the action took when it began,
        before it read its file (a review: a slow parse of an earlier file took the
        newer ticket and replaced the file opened after it). The newest of a burst is
        the one made, and the design on screen is not analysed again (set_design;
        viser runs a button's callback at every message: a review's 30 clicks had cost
        30 analyses, and another tab its connection)."""
        with self.lock:
            if self.closed.is_set() or self._superseded("replace", mine):
                return
            self.set_design(design, save_as=save_as)
            self._say(said)

    def upload_refused(self, name: str, size: int, why: str) -> None:
        """The upload guard (app.uploads) dropped a transfer: too large, larger than it
        said, or too many unfinished from this tab (``why``).

        Called on viser's event loop, so it must not wait for the tab's lock (a review:
        a refusal while the tab analysed a heavy design stalled the whole server, and
        another tab's connection timed out): the line is written without it, as one
        message that can only race with another line's, never with the design."""
        big = size > MAX_UPLOAD_BYTES  # (the size named only where it is the reason:
        size_note = f"; a design file is a few kB, this one {size:,} bytes" if big else ""
        self.ui.files_md.content = (  # a review's long file name had read as too big)
            f"✖ **{esc(_short(name))}** refused: {esc(why)}{size_note}."
        )
        # an earlier file's red box is about that file, not this one (it had stayed,
        # under this refusal); cleared only if the lock is free at once (see above)
        if self.lock.acquire(blocking=False):
            try:
                self._file_error_seen()
            finally:
                self.lock.release()

    def download(self, kind: str, quick: bool = False) -> None:
        """Send the export ``kind`` of the design on screen, or say why not: under the
        Files tab's buttons, or (``quick``: the button above the tabs) under that button,
        where the user is looking. One file at a time per tab, made outside the tab's
        lock (the documents in the background worker): a review's 50 clicks on
        *Report PDF* had queued 50 renders in the server, and another tab's edit waited
        24 s."""
        say = self._say_quick if quick else self._say
        if not self._busy.acquire(blocking=False):
            return say("… Still making the previous file: one at a time, please.")
        try:
            with self.lock:
                self._file_error_seen()
                a, d = self.analysis, self.design
                if self.error is not None:  # the controls no longer describe d: say so
                    return say(
                        "✖ Download refused: the input is invalid (see the red "
                        "panel). Fix it, or load a design, and the files will hold "
                        "what you see."
                    )
            if kind in DOCUMENTS:  # seconds, more on a busy server: say it is coming
                say(f"… Making the {esc(kind.upper())} report of *{esc(d.name)}*.")
            made = self._export(kind, a, d, say)
            if made is None:
                return
            name, data = made
            note = export.warning(a)
            mount = export.mounting_note(a) if kind in export.PART_KINDS else None
            edited = edited_note(d)  # as the files say it
            say(
                f"Sent **{esc(name)}** ({len(data):,} bytes) of *{esc(d.name)}*"
                + ("" if edited is None else f" ({esc(edited)})")
                + f", {d.follower.kind.label}."
                + ("" if note is None else f"<br>⚠ **Before you make it:** {esc(note)}.")
                + ("" if mount is None else f"<br>ℹ {esc(in_words(mount))} (Design → Cam).")
            )
            self.client.send_file_download(name, data, save_immediately=True)
        finally:
            self._busy.release()

    def _export(self, kind: str, a: Analysis, d: Design, say) -> tuple[str, bytes] | None:
        """(file name, bytes) of export ``kind`` of ``a``, or None having said why not."""
        try:
            spec = export.EXPORTS[kind]  # a fixed table: the client's value is only a key
            data = self.analyst.document(kind, a) if kind in DOCUMENTS else spec.write(a)
            return f"{file_stem(d)}{spec.suffix}", data
        except (KeyError, export.ExportError) as exc:
            say(f"✖ Cannot export {esc(kind)}: {esc(exc)}")
        except Exception as exc:  # a defect of ours: said, not silent (and logged)
            logging.getLogger(__name__).exception("export %r failed", kind)
            say(  # (the type only: its text may name the server's files)
                f"✖ Cannot export {esc(kind)}: an internal error "
                f"({esc(type(exc).__name__)}, in the server's log). Please report it; "
                "the other files may still work."
            )
        return None

    def _say(self, markdown: str) -> None:
        """A line in the Files tab, under its Kept-in-this-browser buttons and above the
        download list (user strings already escaped)."""
        with self.lock:
            self.ui.files_md.content = markdown

    def _say_quick(self, markdown: str) -> None:
        """The quick download's answer, under its button (cleared at the next redraw)."""
        with self.lock:
            self.ui.quick_md.content = markdown

    # --- the browser's storage ---------------------------------------------------------
    def _restore(self) -> None:
        """Read this browser's working design and saved list (a reload, or a server
        restart, brings the user back to them). Until the read returns nothing is
        written, so the default design never overwrites what the browser kept."""
        gen0, edits0 = self.gen, self._edits()
        stored = self.store.read_all(storage.KEYS)
        raw = stored[storage.WORKING_KEY]
        working = storage.parse_working(raw)
        saved_text = stored[storage.SAVED_KEY]
        saved, self._unread = storage.read_saved(saved_text)
        setup = storage.parse_setup(stored[storage.EXPLORE_KEY])
        typed_text = stored[storage.PROGRAM_KEY]
        typed = storage.parse_program(typed_text)
        view = storage.parse_view(stored[storage.VIEW_KEY])
        # Undo's and Redo's steps, if the tab that wrote the working design wrote them
        steps = storage.parse_history(stored[storage.HISTORY_KEY], stored[storage.PAIR_KEY])
        aside = stored[storage.UNREADABLE_KEY]  # set aside by an earlier visit?
        if self.closed.is_set():
            return
        if self.store.silent:  # nothing is written over what the tab could not read
            self._say(SILENT_NOTE)
            # where the user looks, and kept there (a teacher's review; a redraw clears
            # the other lines under the download button)
            return self._say_quick(SILENT_NOTE)
        why = storage.working_error(raw) if working is None else None
        kept = why is not None and raw is not None and len(raw) <= MAX_DESIGN_BYTES
        if kept and raw is not None:  # (never the saved list here: a failed read is {})
            self.store.write(storage.UNREADABLE_KEY, raw)
            aside = raw
        if isinstance(aside, str) and 0 < len(aside.encode()) <= MAX_DESIGN_BYTES:
            with self.lock:  # the user can take it out of the browser, to a later version
                self._aside = aside
                self.ui.aside_btn.visible = True
        with self.lock:
            self._show_saved(saved)
            # no edit of the user's yet: no new design, and no edit begun, valid or not
            # (a review: a value typed invalid, or an unfinished table, while the browser
            # took its time, was wiped by the kept design; so was a slider edit waiting on
            # this lock)
            mine = working is not None and self.gen == gen0 and self._edits() == edits0
            restore = mine and working != self.design
            self._persist = True
            if not restore:
                if mine:  # the kept steps lead to the design on screen
                    self._restore_steps(steps)
                elif working is not None and working != self.design:
                    self._keep_last_visit(working, typed is not None)  # (the user's came first)
                self._steps_read = True
                self._save_working()
            elif working is not None:  # (in the same hold of the lock: no edit between)
                self.set_design(working, save_as=working.name)
                self._restore_steps(steps)  # the default it replaced was no step of the user's
                self._steps_read = True
                self._save_history()
        if working is not None and restore:
            note = f"Restored the design last edited in this browser: *{esc(working.name)}*"
            # where the user looks (above the tabs, short: a teacher's review at 1280x720)
            # and in Files, with why
            self._say(f"{note} (its tabs share one working design: the browser keeps it per site).")
            self._say_quick(f"{note}.")
        self._restore_program(
            typed_text, typed if working is not None else None, (gen0 + restore, edits0)
        )
        try:  # a view the browser kept must never cost the rest of the restore
            self._restore_view(view)
        except Exception:
            logging.getLogger(__name__).exception("a kept view failed; ignored")
        if why is not None:  # what the browser kept is not lost without a word
            where = (
                f"it is set aside in this browser's storage as it was "
                f"(`{storage.UNREADABLE_KEY}`), not overwritten"
                if kept
                else "it is too long to set aside"
            )
            self._say(
                f"✖ This browser kept a working design this version cannot open "
                f"({esc(_short(why))}); {where}. The tab starts on the default design."
            )
        # after the design: a kept field whose range the setup cannot give gets one
        # around the restored design's value, not the default's
        try:  # a setup the browser kept must never cost the design or the saved list
            if setup is None:
                self.ui.explore.suggest_ranges()  # around the design on screen
            else:
                self.ui.explore.apply_setup(setup)
        except Exception:
            logging.getLogger(__name__).exception("a kept Explore setup failed; ignored")
        self.ui.explore.keep_setup_with(
            lambda data: self.store.write(storage.EXPLORE_KEY, json.dumps(data))
        )

    def _keep_last_visit(self, working: Design, unfinished: bool) -> None:
        """The design this browser kept from the last visit, when an edit of the user's
        came before the browser answered (the edit stands, and the next valid change
        replaces the browser's working design): kept among the saved designs as "last
        visit: NAME", and said, so that nothing the user made is lost without a word
        (``unfinished``: the last visit also left the table's program unfinished, which
        makes no design to keep: said). Lock held."""
        name = _free_name(self.saved, f"last visit: {working.name}", working)
        lost = (
            " (the unfinished program in its segment table is not kept: it makes no design)"
            if unfinished
            else ""
        )
        try:
            saved = storage.with_saved(self.saved, name, working)
        except ValueError as exc:
            return self._say(
                f"⚠ You edited before this browser's storage answered, so your edit "
                f"stands; the design kept at your last visit (*{esc(working.name)}*) could "
                f"not be saved beside it ({esc(exc)}), and your next change replaces it"
                f"{lost}."
            )
        self._show_saved(saved, write=True)
        self._say(
            f"You edited before this browser's storage answered, so your edit stands; "
            f"the design kept at your last visit is saved as **{esc(name)}** (*Kept in "
            f"this browser*){lost}."
        )

    def _restore_program(
        self, text: str | None, typed: list[dict] | None, before: tuple[int, int]
    ) -> None:
        """Bring back the table's unfinished program the browser kept (``text``, read as
        ``typed``) if this tab has not been edited meanwhile (``before``: the design
        generation and the count of edits begun, as the restore left them); the browser
        then holds this tab's own (none, once the program makes a valid design, or when it
        is not restored). Only from here does the tab empty the browser's copy: the
        working design's restore before it must not (a reload between the two had lost
        the program). A program the user typed meanwhile wins over the kept one, even
        unfinished (it is what the browser holds then: a review)."""
        with self.lock:
            if self._kept_program == _UNREAD:  # (else this tab has written its own)
                self._kept_program = text or None
            mine = self._typed_program is not None
            if typed is not None and (self.gen, self._edits()) == before and not mine:
                try:  # what the browser kept must never cost the tab its restore
                    self._segments(typed)
                except Exception:  # the tab goes on with its design's own program
                    logging.getLogger(__name__).exception("a kept program failed; ignored")
                    self._typed_program, self.error = None, None
                    self.ui.segments.show(self.design.motion.segments)
                    self._show_status()
                else:
                    self._say(
                        UNFINISHED_NOTE
                        if self._typed_program is not None
                        else "The segment table's program being edited at the last "
                        "visit is back; with the other controls it makes a valid design."
                    )
            self._keep_typed(self._typed_program)

    def _restore_view(self, view: dict) -> None:
        """Look at the design as the tab last did (storage.parse_view's entries): the
        cam angle, play speed, pause at stations, wide panel, overlays and camera
        preset. Not if the user has changed any of them since the tab opened."""
        with self.lock:
            if self.closed.is_set():
                return
            if self._view_edits or not view:  # the tab's own view, now the copy was read
                return self._keep_view()
            ui = self.ui
            for name, on in view.get("overlays", {}).items():
                ui.overlay_boxes[name].value = on  # (each box's callback applies it)
            if "speed_deg_s" in view:
                ui.speed_slider.value = view["speed_deg_s"]
            if "pause_at_stations" in view:
                ui.pause_box.value = view["pause_at_stations"]
            if view.get("wide_panel"):
                ui.wide_box.value = True
            if "camera_view" in view:
                self.set_camera_view(view["camera_view"])
            if "theta_deg" in view:
                self._goto(view["theta_deg"])
            self._keep_view()

    def _keep_view(self) -> None:
        """Write how the tab looks at the design (storage.VIEW_KEY) once the restore
        has read the browser's copy; counted as the user's view change. Lock held."""
        self._view_edits += 1
        if not self._persist:
            return
        ui = self.ui
        view = {
            "theta_deg": round(self.theta_deg, 3),
            "speed_deg_s": self.speed,
            "pause_at_stations": bool(ui.pause_box.value),
            "wide_panel": bool(ui.wide_box.value),
            "camera_view": self.camera_view,
            "overlays": {name: bool(box.value) for name, box in ui.overlay_boxes.items()},
        }
        self.store.write(storage.VIEW_KEY, json.dumps(view))

    def download_set_aside(self) -> None:
        """Send the working design this version could not open, as the browser kept it
        (its own text, back to its own browser; at most MAX_DESIGN_BYTES)."""
        with self.lock:
            aside = self._aside
        if aside is None:
            return self._say("Nothing is set aside in this browser.")
        if not self._busy.acquire(blocking=False):  # one download at a time, as the others
            return self._say("… Still sending the previous file: one at a time, please.")
        try:
            data = aside.encode()
            self.client.send_file_download(
                "camdesigner-set-aside.json", data, save_immediately=True
            )
            self._say(
                f"Sent the design set aside ({len(data):,} bytes): open it with the version "
                "that wrote it."
            )
        finally:
            self._busy.release()

    def _save_working(self) -> None:
        if self._persist and self.error is None:
            self.store.write(storage.WORKING_KEY, design_to_json(self.design))
            self.store.write(storage.PAIR_KEY, self._tab_id)
            self._pair_program()
        self._save_history()

    def _restore_steps(self, steps: tuple[list[Design], list[Design]]) -> None:
        """Undo's and Redo's designs as the browser kept them (storage.parse_history).
        Lock held."""
        self.history.restore(*steps)
        self.ui.history_md.content = self.history.text()

    def _save_history(self) -> None:
        """Write Undo's and Redo's designs (storage.HISTORY_KEY) when their steps have
        changed (not at each value of a slider's drag, which joins one step); not
        before the restore has read the kept ones (they must not be replaced unseen).
        Lock held."""
        if not (self._persist and self._steps_read):
            return
        if self.history.version != self._steps_written:
            self.store.write(
                storage.HISTORY_KEY,
                storage.history_text(self.history.past, self.history.future, self._tab_id),
            )
            self._steps_written = self.history.version

    def _pair_program(self) -> None:
        """Write this tab's unfinished program (or none) beside the working design it
        just wrote: the browser's tabs share both keys, and a pair from two tabs (a
        preset loaded in one, another's unfinished program) had come back as a red
        table over the preset at a reload. Not before the restore has read the copy
        (_UNREAD: it must not be emptied unseen). Lock held."""
        if self._persist and self._kept_program != _UNREAD:
            typed = self._typed_program
            self._write_program(None if typed is None else json.dumps(typed))

    def _write_program(self, text: str | None) -> None:
        """The browser's copy of the unfinished program (None: none, written ""), and
        what this tab knows it holds. Lock held."""
        self.store.write(storage.PROGRAM_KEY, text or "")
        self._kept_program = text

    def _show_saved(self, saved: dict[str, str], write: bool = False) -> None:
        self.saved = saved
        if write:  # with the entries this version could not read, as they were
            self.store.write(storage.SAVED_KEY, json.dumps({**self._unread, **saved}))
        names = tuple(saved) or ("–",)
        self.ui.saved_dd.options = names
        if self.ui.saved_dd.value not in names:
            self.ui.saved_dd.value = names[0]

    def _reread_saved(self) -> bool:
        """Show the browser's saved list as it is now, before a save or a delete writes
        it whole: another tab of this browser may have saved or deleted meanwhile (a
        review: one tab's save erased what the other had saved). False, and nothing to
        write, if the browser did not answer. Called with ``_storage_turn`` held and
        the tab's lock not: the browser may take READ_TIMEOUT_S to answer, and a tab
        that never does had held its lock that long, so its queued edits took every
        thread of viser's pool and froze every tab (a security review: 19 s)."""
        answered, text = self.store.fresh(storage.SAVED_KEY)
        saved, unread = storage.read_saved(text) if answered else ({}, {})
        with self.lock:
            if not answered:
                self._say("✖ Not done: this browser's storage did not answer. Try again.")
                return False
            self._unread = unread
            self._show_saved(saved)
            return True

    def _saving(self, what: str) -> bool:
        """Take this tab's turn to re-read and write its saved list, or say that a save
        or delete is under way (one waits for the browser at a time)."""
        if self._storage_turn.acquire(blocking=False):
            return True
        with self.lock:
            self._say(f"… Not {what}: this tab's last save or delete is still under way.")
        return False

    def save_named(self, name: str) -> None:
        if not self._saving("saved"):
            return
        try:
            with self.lock:
                if not self._persist and not self.store.silent:  # (the first read waits 20 s)
                    return self._say(
                        "… Not saved yet: this tab is still reading this browser's storage "
                        "(its saved designs must not be written over unseen). Try again in a "
                        "moment."
                    )
                if not self._persist:  # the browser's list was never read: do not replace it
                    return self._say(
                        "✖ Not saved: this browser's storage did not answer when the tab "
                        "opened. Reload the page, or download the design."
                    )
            if self._reread_saved():
                with self.lock:
                    self._save_named(name)
        finally:
            self._storage_turn.release()

    def _save_named(self, name: str) -> None:
        """save_named once the browser's list is read. Lock held."""
        self._file_error_seen()
        name = str(name).strip()
        # another design under that name (one this version cannot open counts too):
        # the first click says so, a second one on the same design replaces it
        replaced = name in self.saved and (storage.parse_working(self.saved[name]) != self.design)
        if replaced and self._replace_armed != (name, self.design):
            self._replace_armed = (name, self.design)  # (a review: a variant went
            return self._say(  # without a word)
                f"⚠ This browser already keeps another design as **{esc(name)}**: "
                "click *Save in this browser* again to replace it, or change the name."
            )
        self._replace_armed = None
        try:
            saved = storage.with_saved(self.saved, name, self.design)
        except ValueError as exc:
            return self._say(f"✖ Not saved: {esc(exc)}.")
        replaced_note = " (it replaces the one kept before)" if replaced else ""
        self._show_saved(saved, write=True)
        self.ui.saved_dd.value = name
        self._say(f"Saved **{esc(name)}** in this browser{replaced_note}.")

    def open_saved(self, name: str) -> None:
        text = self.saved.get(name) if isinstance(name, str) else None
        if text is None:  # (no turn taken: a click on nothing replaces no file opening)
            return self._say("✖ Choose a saved design first.")
        mine = self._take_ticket("replace")
        design = storage.parse_working(text)
        if design is None:  # kept, but not a design this version opens: say why
            why = storage.working_error(text) or "not a design"
            return self._say(f"✖ Could not open **{esc(name)}**: {esc(_short(why))}.")
        self._replace(design, name, f"Opened **{esc(name)}** from this browser.", mine)

    def delete_saved(self, name: str) -> None:
        if not self._saving("deleted"):
            return
        try:
            with self.lock:
                if not isinstance(name, str) or name not in self.saved or not self._persist:
                    return self._say("✖ Choose a saved design first.")
            if not self._reread_saved():  # (then nothing is written over it)
                return
            with self.lock:
                if name not in self.saved:  # (another tab deleted it meanwhile)
                    return self._say("✖ Choose a saved design first.")
                self._show_saved({k: v for k, v in self.saved.items() if k != name}, write=True)
                self._say(f"Deleted **{esc(name)}** from this browser.")
        finally:
            self._storage_turn.release()

    # --- angle, stations, animation ------------------------------------------------
    def _index(self) -> int:
        return nearest_index(self.analysis.theta, self.theta_deg)

    def _goto(self, theta_deg: float, markers: bool = True, slider: bool = True) -> None:
        """Show the mechanism at theta_deg: pose, slider, close-up camera and (with
        ``markers``) the text and curve markers, in one atomic update. Lock held."""
        self.theta_deg = theta_deg % 360.0
        k = self._index()
        with self.client.atomic():
            self.view.pose(k)
            if slider:
                with self._quiet():
                    self.ui.angle_slider.value = round(self.theta_deg, 1)  # as the text
            if self.camera_view == "Contact close-up":  # follow the contacts as S changes
                pos, look, _ = self._camera(k)
                self._set_camera(pos, look)
                self._preset_pose = (*pos, *look)
            if markers:
                self._show_markers(k)

    def _show_markers(self, k: int, compare: bool = True) -> None:
        """The line under the slider and the curves' markers at grid index k; the
        Compare tab's too unless ``compare`` is False (while playing: ~35 kB each)."""
        self.ui.where_md.content = self._where(k)
        for c in self.ui.curves:
            c.marker(math.degrees(self.analysis.theta[k]))
        if compare:
            self.ui.compare_view.marker(math.degrees(self.analysis.theta[k]))

    def _on_angle(self, value) -> None:
        """The user moved the angle slider to ``value`` [deg]. Each event is applied
        in turn (not coalesced: a frame, a step or a station written meanwhile would
        replace the user's angle); a tab's events wait in its own lane
        (app.inbound.TabLanes), not on the server's pool."""
        try:
            value = float(value)
        except (TypeError, ValueError):
            return
        if not math.isfinite(value):  # a client's NaN had stopped Play for good
            return
        with self.lock:
            if not self._syncing:
                self._held = 0.0  # the user's own angle: no pause left to wait out
                # (the slider itself is not written while dragged: it would jitter; a
                # typed angle beyond 0-360 is, as the angle shown: an app review's 400
                # had stayed in the box beside 40 deg, and the browser later cut it to
                # 360, turning the cam to 0)
                self._goto(value, slider=not 0.0 <= value <= 360.0)
                self._keep_view()

    def step(self, label: str) -> None:
        """Pause and turn the cam by one of layout.STEP_DEG's steps; anything else (a
        hostile client's value) is ignored."""
        delta = STEP_DEG.get(label) if isinstance(label, str) else None
        if delta is None:
            return
        with self.lock:
            self._set_playing(False)
            self._held = 0.0
            self._goto(round(self.theta_deg + delta, 6))
            self._keep_view()

    def goto_station(self, i: int | str) -> None:
        """Jump to station i; anything else (a hostile client's value) is ignored."""
        with self.lock:
            n = len(self.analysis.stations)
            if str(i) not in {str(k) for k in range(n)}:
                return
            self._set_playing(False)
            self._held = 0.0
            self._goto(math.degrees(float(self.analysis.stations[int(i)])))
            self._keep_view()

    def _set_speed(self, value) -> None:
        """The animation speed [deg/s], brought into the slider's range, and the box
        showing the speed taken (an app review: a typed 1000 stayed in the box while the
        cam kept its old speed, and a typed 0 froze Play); what is not a finite number
        (a hostile client) changes nothing, and the box shows the speed kept."""
        try:
            v = float(value)
        except (TypeError, ValueError):
            v = math.nan
        with self.lock:
            if self._syncing:
                return
            if math.isfinite(v):
                self.speed = min(max(v, SPEED_MIN_DEG_S), SPEED_MAX_DEG_S)
                self._keep_view()
            if self.ui.speed_slider.value != self.speed:
                with self._quiet():
                    self.ui.speed_slider.value = self.speed

    def _set_overlay(self, name: str, on: bool) -> None:
        with self.lock:
            self.view.set_overlay(name, bool(on))
            self._keep_view()

    @property
    def playing(self) -> bool:
        return self.ticker.running

    def _set_playing(self, on: bool) -> None:
        self.ticker.run(on)
        # (‖, not ⏸: a font without U+23F8, common, showed an empty box)
        self.ui.play_btn.label = "‖ Pause" if on else "▶ Play"
        self.ui.play_btn.color = "orange" if on else "green"

    def toggle_play(self) -> None:
        with self.lock:
            self._set_playing(not self.playing)
            if not self.playing:
                self._held = 0.0  # (a stop at a station under way ends with Pause)
                self._goto(self.theta_deg)
            self._keep_view()  # (at play and pause, not while playing: 30 a second)

    def _tick(self, dt: float, n: int) -> None:
        """The ticker's step: a frame, unless paused meanwhile (a step that waited for
        the lock while the user pressed pause must not move the cam)."""
        with self.lock:
            if self.playing:
                self.frame(dt, n)

    def frame(self, dt: float, n: int = 0) -> None:
        """One animation step of dt seconds, the n-th since play (the ticker's step).
        With *Pause at stations* a step that would pass a station stops on it, and the
        next PAUSE_AT_STATION_S seconds of steps stay there."""
        with self.lock:
            if self.closed.is_set():
                return
            if self._held > 0:  # stopped at a station
                self._held -= dt
                self._resumed = self._held <= 0
                return
            # angle slider and the line under it at 10 Hz, together; and on the first
            # step after a stop, whose "paused" the line must not keep (a review)
            slow, self._resumed = n % 3 == 0 or self._resumed, False
            to = self.theta_deg + self.speed * dt
            stop = self._station_within(self.speed * dt) if self.ui.pause_box.value else None
            if stop is not None:
                to, slow, self._held = stop, True, PAUSE_AT_STATION_S
            self._goto(to, markers=stop is not None, slider=slow)
            k = self._index()
            if n % 15 == 0:  # curve markers at 2 Hz: each one resends the plot data
                self._show_markers(k, compare=False)  # (Compare's at stops and pauses)
            elif slow:
                self.ui.where_md.content = self._where(k)

    def _where(self, k: int) -> str:
        """The block under the angle slider at grid index k, in the room it keeps."""
        wide = self.panel_px > NARROW_PANEL_PX
        return where_markdown(
            self.analysis,
            k,
            self.station_events,
            self.station_faces,
            WIDE_WHERE_LINES if wide else WHERE_LINES,
            PAUSE_AT_STATION_S if self._held > 0 else 0.0,
        )

    def _end_pause(self) -> None:
        """Pause at stations ticked or unticked: a pause under way ends."""
        with self.lock:
            self._held = 0.0
            self._keep_view()

    def _station_within(self, step_deg: float) -> float | None:
        """The first station angle [deg] after the current angle and at most
        ``step_deg`` on (turning on from a station: the next one), else None."""
        ahead = [(math.degrees(s) - self.theta_deg) % 360.0 for s in self.analysis.stations]
        ahead = [d for d in ahead if 1e-9 < d <= step_deg]
        return self.theta_deg + min(ahead) if ahead else None

    # --- view ----------------------------------------------------------------------
    def show_stations_diagram(self) -> None:
        """The mechanism at every station side by side (camcore.document), under the
        button; drawn from the design on screen, replaced on each click, and taken
        away when the design changes (_redraw: a diagram of another follower beside
        the 3D view had misled, and its captions' F_N and sigma_H follow the speed, the
        spring and the material too: a teacher's review saw 136.8 N under a design of
        161.4 N)."""
        say = self.ui.stations_fig_md
        if not self._drawing.acquire(blocking=False):
            return  # one at a time (a review's 60 clicks drew 60 diagrams at once)
        try:
            with self.lock:
                a, drawn = self.analysis, self.design
            # a user saw nothing happen for 18 s (the picture came in below the fold)
            say.content = "… Drawing the stations diagram: it appears below this line."
            try:
                image = self.analyst.stations_image(a)  # ~0.5 s of matplotlib, in a worker
            except Exception:  # a defect of ours, or the server stopping: logged, not raised
                logging.getLogger(__name__).exception("stations diagram failed")
                say.content = "✖ The diagram could not be drawn (in the server's log)."
                return
            with self.lock:
                if self.design != drawn:  # the design changed meanwhile
                    say.content = "The design changed while drawing: click again."
                    return
                self._diagram_of = drawn
                say.content = (
                    f"The stations of *{esc(self.design.name)}* are below "
                    "(the image's ⤢ shows it full size, 1200 px wide: to project)."
                    + (STATION_3_NOTE if self.design.follower.kind.is_double else "")
                )
                if self.ui.stations_img is not None:
                    self.ui.stations_img.image = image
                else:
                    with self.ui.view_folder:
                        self.ui.stations_img = self.client.gui.add_image(image, format="png")
        finally:
            self._drawing.release()

    def set_wide_panel(self, on: bool) -> None:
        """Widen the control panel for the curves, or give it back its width: through
        viser's own panel width (a CSS width on the panel's frame had left its contents
        at their own width, 34 px past the frame's right edge on a 1920 px screen)."""
        try:
            drawn = self.client.camera.image_width  # the 3D view's drawing width [px]
        except AssertionError:  # no camera message yet
            drawn = 0
        with self.lock:
            self.panel_px = wide_panel_px(drawn) if on else NARROW_PANEL_PX
            self.client.gui.main_panel.set_width(self.panel_px)
            self.ui.explore.set_width(self.panel_px)  # (its map is drawn for the panel)
            self.ui.where_md.content = self._where(self.view.k)  # its room follows
            if self.camera_view != "3D":  # the mechanism beside the panel's new width
                self.reset_camera()
            self._keep_view()

    def _on_camera(self, cam) -> None:
        """A camera message from the browser. One that keeps the pose and changes the
        view's size is a resize (an orbit moves the pose, and may carry a size that
        viser scaled down for the frame rate): the wide panel takes its share of the
        new width, and a preset view the user has not moved is framed again."""
        if not self._queue("camera"):
            return
        with self.lock:
            self._turn("camera")
            try:  # (the camera as it is now: later messages waited for this turn)
                w, h = cam.image_width, cam.image_height
                pose = (*map(float, cam.position), *map(float, cam.look_at))
            except AssertionError:  # (no message yet)
                return
            last, self._seen = self._seen, (pose, w, h)
            if last is None or (w, h) == last[1:] or not _near(pose, last[0]):
                return
            if self.ui.wide_box.value:
                self.panel_px = wide_panel_px(w)
                self.client.gui.main_panel.set_width(self.panel_px)
                self.ui.explore.set_width(self.panel_px)
            if self.camera_view != "3D" and _near(pose, self._preset_pose):
                self.reset_camera()

    def _camera(self, k: int) -> tuple[tuple, tuple, float]:
        """The preset view's (position, look_at, fov) at grid index k, for this tab's
        view and panel; the close-up's extent kept per analysis (it follows every
        frame of the animation, and the extent costs ~1 ms)."""
        extent = None
        if self.camera_view == "Contact close-up":
            if self._extent[0] is not self.analysis:
                self._extent = (self.analysis, closeup_extent(self.analysis))
            extent = self._extent[1]
        return camera_for(self.camera_view, self.analysis, k, self._frame(), extent)

    def _frame(self) -> tuple[float, float]:
        """(aspect, panel share) of this tab's 3D view (scene.camera_for): its drawing
        size, and the panel's width over the drawing width. The drawing width is in
        device pixels, scaled down to 0.75 while viser saves frames, the panel's in CSS
        pixels: on a high-DPI screen the share is read smaller than it is, and the
        mechanism sits between the middle of the view and that of its uncovered part."""
        try:
            w, h = self.client.camera.image_width, self.client.camera.image_height
        except AssertionError:  # no camera message yet
            return DEFAULT_FRAME
        if not (w > 0 and h > 0 and math.isfinite(w / h)):  # (also NaN from a client)
            return DEFAULT_FRAME
        return w / h, min(self.panel_px / w, 0.6)

    def set_camera_view(self, view: str) -> None:
        """A preset view (Front by default; the close-up follows the animation)."""
        if view not in CAMERA_VIEWS:  # a client may send anything
            return
        with self.lock:
            self.camera_view = view
            self.reset_camera()
            self._keep_view()

    def reset_camera(self) -> None:
        """The preset view's camera and label size (also the Reset button's, which
        runs in a callback thread of its own: hence the lock)."""
        with self.lock:
            self._framed_size = _size(self.analysis)
            pos, look, fov = self._camera(self.view.k)
            self.view.set_label_height(label_height(pos, look, fov))
            self._set_camera(pos, look, fov)
            self._preset_pose = (*pos, *look)

    def _set_camera(self, pos: tuple, look: tuple, fov: float | None = None) -> None:
        """Move this tab's camera. viser derives the new orientation from the client's
        last camera state, and refuses (ValueError) when the client sent a non-finite
        one (a hostile client's NaN pose had killed the animation thread for good): the
        move is skipped; the client's next sane camera message makes it work again."""
        cam = self.client.camera
        try:
            if fov is not None:
                cam.up_direction = (0.0, 1.0, 0.0)
                cam.fov = fov
            cam.position = pos
            cam.look_at = look
        except ValueError:
            logging.getLogger(__name__).debug("camera not moved: the client's pose is bad")

    @property
    def threads(self) -> tuple[threading.Thread, ...]:
        """The tab's own threads (all end on close)."""
        return self._restorer, self.ticker.thread, self.refiner.thread

    def close(self) -> None:
        self.closed.set()
        self.ui.explore.close()
        self.ticker.close()
        self.refiner.close()
        for t in self.threads:
            if t.is_alive() and t is not threading.current_thread():
                t.join(timeout=2.0)


DOCUMENTS = ("html", "pdf")  # exports made in the documents' worker (~1 s of matplotlib)
NAME_SHOWN = 80  # characters of a client's file name that a message repeats


def _short(name: str) -> str:
    """A client's file name as messages show it: at most NAME_SHOWN characters (an 8 MB
    name had been echoed twice, into Files and the status panel)."""
    return name if len(name) <= NAME_SHOWN else name[: NAME_SHOWN - 1] + "…"


REFRAME = 4 / 3  # the cam grew or shrank this much since it was framed: frame it again
# (at 2, r_b 80 -> 164 mm ran the cam off a projected screen: a teacher's review)


def _size(a: Analysis) -> float:
    """The cam's largest radius [m]: the preset views frame the mechanism by it."""
    return float(a.geo.r_b + a.prog.S.max())


def _near(p: tuple, q: tuple) -> bool:
    """Two camera poses (position and look-at, 6 numbers [m]) alike to float32 round-off
    (what the browser echoes of a pose the server set); any orbit moves them more."""
    if len(p) != len(q):
        return False
    tol = 1e-5 * (1.0 + max(abs(v) for v in p + q))
    return all(abs(a - b) <= tol for a, b in zip(p, q, strict=True))


def _nothing_to(label: str, counts: str) -> str:
    """The line under the history buttons when ``label`` has no step to go to: why,
    with the steps the other way (``counts``, History.text) kept in view."""
    if label == HISTORY_BUTTONS[0]:
        why = f"Nothing to undo: the history keeps this tab's last {HISTORY_MOST} changes."
    else:
        why = "Nothing to redo: Redo steps forward again after an Undo."
    return f"{why} {counts}." if counts else why


def _free_name(saved: dict[str, str], wanted: str, design: Design) -> str:
    """A name of at most storage.MAX_NAME characters to keep ``design`` under in
    ``saved``: ``wanted`` (shortened), or with " (2)", " (3)", ... where another design
    holds it (the number fits inside the limit: a long name had been cut back to the
    taken one, and saved over it, a review); the name the design is kept under already,
    if it is."""
    base = storage.proposed_name(wanted)
    for i in range(1, storage.MAX_SAVED + 2):
        suffix = "" if i == 1 else f" ({i})"
        name = base[: storage.MAX_NAME - len(suffix)].rstrip() + suffix
        old = saved.get(name)
        if old is None or storage.parse_working(old) == design:
            return name
    return name  # (more than MAX_SAVED taken: with_saved refuses a full list anyway)
