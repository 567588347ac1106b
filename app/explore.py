"""The Explore tab: sweep two design fields (and, optionally, the four followers)
around the design on screen, in the background, and show which limit fails where and
the Pareto front of two or three figures the user picks; a design of the front loads
with one click.

The sweep is camcore.sweep's (rows equal ``report --json``), in chunks on the
analyst's background worker, which only uses CPU time no tab's edit wants. It runs on
the batched core (camcore.batch: the paper's limits and the fixed-size figures, about
three times faster) unless a chosen figure needs the profile (wear); the profile's own
checks and the geometric check run when a design is loaded. One sweep per tab, at
most MAX_DESIGNS designs, cancellable between chunks.
"""

from __future__ import annotations

import re
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from camcore.explore import (
    FIGURES,
    OFFERED,
    PANEL_PX,
    PROFILE_FIGURES,
    balance_for,
    best_per_kind,
    distinct,
    figure_values,
    grid_points,
    ignored_fields,
    offered,
    pareto,
    segment_angle_paths,
    spec_document,
    sweep_grid,
)
from camcore.model import PAPER_FOLLOWERS, Design, DesignError, FollowerKind, set_field
from camcore.sweep import csv_text, design_at, with_point

from .controls import SPECS, control_value, get_path
from .panels import esc, file_stem

# label -> design path of the fields a sweep may vary (numbers only)
PARAMETERS = {
    "Base radius r_b [mm]": "cam.base_radius_mm",
    "Offset e (double) [mm]": "follower.offset_mm",
    "Axis offset e_s (single) [mm]": "follower.single_offset_mm",
    "Face radius r_f [mm]": "follower.face_radius_mm",
    "Roller radius r_c [mm]": "follower.roller_radius_mm",
    "Lift h [mm]": "motion.lift_mm",
    "Rise β_r [°]": "motion.rise_deg",
    "Fall β_f [°]": "motion.fall_deg",
    "Cam speed [rpm]": "cam.speed_rpm",
    # the machine's own trade-offs (a designer sizes the spring against the speed, the
    # width against the stress): not batched fields, each value its own batch
    "Cam width w [mm]": "cam.width_mm",
    "Spring rate k [N/m]": "dynamics.spring_rate_N_per_m",
    "External load F_e [N]": "dynamics.external_load_N",
}
# how the list of front designs names each field ("r_b 12")
SYMBOLS = {
    "follower.kind": "",
    "cam.base_radius_mm": "r_b",
    "follower.offset_mm": "e",
    "follower.single_offset_mm": "e_s",
    "follower.face_radius_mm": "r_f",
    "follower.roller_radius_mm": "r_c",
    "motion.lift_mm": "h",
    "motion.rise_deg": "β_r",
    "motion.fall_deg": "β_f",
    "cam.speed_rpm": "speed",
    "cam.width_mm": "w",
    "dynamics.spring_rate_N_per_m": "k",
    "dynamics.external_load_N": "F_e",
}
SIGNED = {"follower.single_offset_mm", "dynamics.external_load_N"}  # either side of 0


def segment_parameters(design: Design) -> dict[str, str]:
    """label -> path of the angle of each rise and fall of a program made of segments
    (camcore.explore.segment_angle_paths), offered beside PARAMETERS: a designer's
    review could sweep no field of an indexer's program in the tab (a dwell takes up
    the turn: balance_for)."""
    return {
        f"Segment {i + 1} angle, {kind.value} [°]": path
        for path, (i, kind) in segment_angle_paths(design).items()
    }


def fields_of(design: Design) -> dict[str, str]:
    """label -> path of every field a sweep around ``design`` may vary: PARAMETERS
    (their lift, rise and fall only for a classic program: a user's review was
    offered them for an indexer's, each refused when chosen) and its segments'
    angles (segment_parameters)."""
    classic = design.motion.classic is not None
    own = {k: p for k, p in PARAMETERS.items() if classic or not p.startswith("motion.")}
    return {**own, **segment_parameters(design)}


def segment_number(path: str) -> int | None:
    """The segment (counted from 1, as the tab names it) whose angle ``path`` is, or None."""
    m = re.fullmatch(r"motion\.segments\.(\d+)\.angle_deg", path)
    return int(m[1]) + 1 if m else None


def symbol(path: str) -> str:
    """How the list of designs names a field: SYMBOLS', "β3" for segment 3's angle."""
    n = segment_number(path)
    return f"β{n}" if n is not None else SYMBOLS.get(path, path)


# labels of earlier versions, as a kept setup may hold them
OLD_LABELS = {"Speed [rpm]": "Cam speed [rpm]"}
FIGURE_LABELS = {f.label: name for name, f in FIGURES.items()}
MAX_STEPS = 15  # per axis
MAX_RANGE_ABS = 1e9  # of a range's ends: far beyond every field's own limits
MAX_DESIGNS = MAX_STEPS * MAX_STEPS * len(PAPER_FOLLOWERS)
CHUNK = 12  # designs per background job: ~0.1 s, the cancel latency
_PLAIN_NAME = re.compile(r"[A-Za-z0-9_.-]{1,120}")  # a file name shown as code as is
MAX_FILE_BYTES = 16 << 20  # a sweep's CSV or SPEC sent to the browser
MAX_FRONT = OFFERED  # designs of the front offered for loading (spread along it)
NO_FIGURE = "none"  # the third figure is optional


@dataclass(frozen=True)
class Ran:
    """A sweep on show: what the downloads send."""

    base: dict  # the design it ran around (Design JSON data)
    grid: dict  # its SPEC grid (camcore.explore.sweep_grid)
    rows: list[dict]  # the rows of the points analysed (all, unless cancelled)
    batched: bool  # the batched core (else the full analysis, no geometric check)
    total: int  # the grid's points
    balance: str | None = None  # the segment angle that took up the turn (SPEC's)


class ExplorePanel:
    """The tab's widgets and its one background sweep. ``bind`` connects it to the
    session: the analyst, the design on screen, and how to load a design."""

    def __init__(self, gui):
        self.gui = gui
        labels = tuple(PARAMETERS)
        gui.add_markdown(
            "Sweep two fields around the design on screen; each point is a whole analysis "
            "(the paper's limits; the profile and geometric checks run when you load a "
            "design). The map is drawn for the panel's width: *Curves → Wide panel* "
            "puts the followers' maps side by side; the image's ⤢ shows it twice as large."
        )
        self.x = gui.add_dropdown("x field", labels, initial_value=labels[0])
        self.x_range = gui.add_vector2(_range_label("x", labels[0]), (60.0, 110.0), step=0.5)
        self.y = gui.add_dropdown("y field", labels, initial_value=labels[1])
        self.y_range = gui.add_vector2(_range_label("y", labels[1]), (20.0, 40.0), step=0.5)
        self.centre_btn = gui.add_button("Ranges around the design on screen")
        self.steps = gui.add_slider("Steps per field", 2, MAX_STEPS, 1, 8)
        self.all_kinds = gui.add_checkbox("All four followers (the paper's claim)", True)
        figs = tuple(FIGURE_LABELS)
        self.fig_a = gui.add_dropdown("Figure 1 (Pareto x)", figs, initial_value=figs[0])
        self.fig_b = gui.add_dropdown("Figure 2 (Pareto y)", figs, initial_value=figs[1])
        self.fig_c = gui.add_dropdown(
            "Figure 3 (colour)", (NO_FIGURE, *figs), initial_value=NO_FIGURE
        )
        self.run_btn = gui.add_button("Run the sweep", color="green")
        self.cancel_btn = gui.add_button("Cancel", disabled=True)
        self.progress = gui.add_markdown("")
        self.front_dd = gui.add_dropdown("Pareto designs", ("–",), initial_value="–")
        self.load_btn = gui.add_button("Load this design", disabled=True)
        self.csv_btn = gui.add_button("Download the results (CSV)", disabled=True)
        self.spec_btn = gui.add_button("Download the sweep (SPEC for camcore)", disabled=True)
        self.files_md = gui.add_markdown("")
        self.image: Any = None
        self._folder = gui.add_folder("Map", expand_by_default=True)
        self._analyst: Any = None
        self._design: Callable[[], Design] | None = None
        self._load: Callable[[Design], None] | None = None
        self._lock = threading.Lock()
        self._closed = threading.Event()  # the tab is gone (close)
        # (the sweep on show, the design on screen that load took from it) or None
        self._loaded: tuple[Ran | None, Design] | None = None
        self._cancel = threading.Event()
        self._thread: threading.Thread | None = None
        self._offers: dict[str, dict] = {}  # dropdown label -> grid point
        self._armed: str | None = None  # the offer a second click loads despite edits
        self._drawing = False  # the sweep's results are being drawn (no Cancel)
        self._base: dict = {}
        self.shown_px = PANEL_PX  # the panel's width: the map is drawn for it
        self._drawn: tuple | None = None  # (rows, x, y, names, front, limits, px) on show
        self._map_busy = False  # a thread draws the map (a sweep's end or a new width)
        self._map_lock = threading.Lock()  # held while one draws: never two at once
        self._write: Callable[[dict], None] | None = None  # keeps the setup (storage)
        self._ran: Ran | None = None  # the sweep on show
        self._send: Callable[[str, bytes], None] | None = None  # a file to the browser
        self._invalid: Callable[[], bool] | None = None  # the tab's input is invalid
        self._fields = dict(PARAMETERS)  # what x and y offer now (offer_fields)

    def bind(
        self,
        analyst,
        design: Callable[[], Design],
        load: Callable[[Design], None],
        send: Callable[[str, bytes], None],
        invalid: Callable[[], bool],
    ):
        """``invalid``: whether the tab's input is invalid now (the design on screen is
        then the last valid one, not what the controls say)."""
        self._analyst, self._design, self._load, self._send = analyst, design, load, send
        self._invalid = invalid
        for widget in self._setup_widgets():
            widget.on_update(lambda _: self._keep_setup())
        self.run_btn.on_click(lambda _: self.start())
        self.centre_btn.on_click(lambda _: self.centre())
        self.cancel_btn.on_click(lambda _: self.cancel())
        self.load_btn.on_click(lambda _: self.load(self.front_dd.value))
        self.csv_btn.on_click(lambda _: self.download("csv"))
        self.spec_btn.on_click(lambda _: self.download("spec"))
        self.x.on_update(lambda _: self._suggest(self.x, self.x_range, "x"))
        self.y.on_update(lambda _: self._suggest(self.y, self.y_range, "y"))

    # --- the setup, kept in the browser --------------------------------------------
    def _setup_widgets(self) -> tuple:
        return (
            self.x,
            self.x_range,
            self.y,
            self.y_range,
            self.steps,
            self.all_kinds,
            self.fig_a,
            self.fig_b,
            self.fig_c,
        )

    def setup(self) -> dict:
        """The sweep the widgets describe, as JSON-ready data (apply_setup's input)."""
        return {
            "x": self.x.value,
            "x_range": list(self.x_range.value),
            "y": self.y.value,
            "y_range": list(self.y_range.value),
            "steps": self.steps.value,
            "all_kinds": self.all_kinds.value,
            "figures": [self.fig_a.value, self.fig_b.value, self.fig_c.value],
        }

    def apply_setup(self, data) -> None:
        """Put a setup (from the browser's storage: untrusted) on the widgets, each entry
        only if it is one the widget offers; a kept range only with its own field."""
        if not isinstance(data, dict):
            return
        for dd, rng, axis in ((self.x, self.x_range, "x"), (self.y, self.y_range, "y")):
            label = data.get(axis)
            label = OLD_LABELS.get(label, label) if isinstance(label, str) else label
            if not isinstance(label, str) or label not in self._fields:
                continue
            dd.value = label  # proposes a range, replaced by the kept one below
            pair = _kept_pair(data.get(f"{axis}_range"))
            if pair is not None:
                rng.value = pair
            else:  # around the design's value (dd.value proposes only when it changes)
                self._suggest(dd, rng, axis)
        steps = data.get("steps")
        if isinstance(steps, int | float) and not isinstance(steps, bool):
            if steps in range(2, MAX_STEPS + 1):  # an integer of the slider's range
                self.steps.value = int(steps)
        if isinstance(data.get("all_kinds"), bool):
            self.all_kinds.value = data["all_kinds"]
        figs = data.get("figures")
        if isinstance(figs, list) and len(figs) == 3:
            for dd, label in zip((self.fig_a, self.fig_b, self.fig_c), figs, strict=True):
                if isinstance(label, str) and label in dd.options:
                    dd.value = label

    def keep_setup_with(self, write: Callable[[dict], None] | None) -> None:
        """From now on each change of the setup goes to ``write`` (None: nowhere)."""
        self._write = write

    def _keep_setup(self) -> None:
        if self._write is not None:
            self._write(self.setup())

    def offer_fields(self, design: Design) -> None:
        """The fields x and y offer for ``design`` (fields_of). When they change (another
        kind of program), a finished sweep's results go, and a field no longer offered
        gives way to the first one the other axis has not (its range proposed anew)."""
        fields = fields_of(design)
        if fields == self._fields:
            return
        with self._lock:  # (with _show's check and publish: one or the other first)
            self._fields = fields
            running = self._thread is not None and self._thread.is_alive()
            stale = (
                self._ran is not None and fields_of(Design.model_validate(self._ran.base)) != fields
            )
        if not running or stale:  # a sweep of another program's fields: gone
            self._clear()  # (a user's review loaded another preset and still had its
        if not running:  # map, loadable; a review found one published meanwhile)
            self.progress.content = ""
        labels = tuple(fields)
        for dd, other in ((self.x, self.y), (self.y, self.x)):
            keep = dd.value in fields
            dd.options = labels  # (viser: a value not among them becomes the first)
            if not keep:
                dd.value = next(label for label in labels if label != other.value)

    def _suggest(self, dd, rng, axis: str) -> None:
        """A range around the design's value of a newly chosen field (±30 %), labelled
        with the field's unit; for a segment's angle, which dwell takes up the turn."""
        if self._design is None:
            return
        design = self._design()
        path = fields_of(design).get(dd.value)  # (the design's own: offer_fields may
        if path is None:  # not have run for it yet)
            return
        rng.label = _range_label(axis, dd.value)
        v = get_path(design, path)
        if isinstance(v, int | float):
            zero = (-10.0, 10.0) if path in SIGNED else (0.0, 10.0)
            lo, hi = sorted((0.7 * v, 1.3 * v)) if v else zero
            rng.value = (round(lo, 1), round(hi, 1))
        balance = self._balance(design)
        if balance is not None:
            self.progress.content = _balance_note(design, balance)

    def suggest_ranges(self) -> None:
        """Both fields' ranges around the design on screen (a tab with no kept setup:
        a designer's review found fixed ranges far from a small cam's)."""
        self._suggest(self.x, self.x_range, "x")
        self._suggest(self.y, self.y_range, "y")

    def centre(self) -> None:
        """Both ranges around the design on screen, kept (a teacher's review: ranges kept
        from an earlier design left the one on screen out of the sweep)."""
        self.suggest_ranges()
        self._keep_setup()

    # --- the sweep ----------------------------------------------------------------
    def start(self) -> None:
        """Run the sweep the widgets describe, unless one runs already (one per tab)."""
        with self._lock:
            if self._thread is not None and self._thread.is_alive():
                return
            job = self._job()
            if job is None:
                return
            self._cancel.clear()
            self._drawing = False
            self.run_btn.disabled, self.cancel_btn.disabled = True, False
            self._thread = threading.Thread(
                target=self._sweep, args=job, daemon=True, name="cam-explore"
            )
            self._thread.start()

    def _job(self):
        """(base, points, grid, x, y, figures, balance) from the widgets, or None (said
        why); balance: the segment angle that takes up the turn (balance_for), or None."""
        assert self._design is not None  # bound before any click
        design = self._design()
        fields = fields_of(design)  # (of the design read: offer_fields may lag it)
        px, py = fields.get(self.x.value), fields.get(self.y.value)
        names = [FIGURE_LABELS.get(f.value) for f in (self.fig_a, self.fig_b)]
        if self.fig_c.value != NO_FIGURE:
            names.append(FIGURE_LABELS.get(self.fig_c.value))
        if px is None or py is None or px == py:
            self.progress.content = "✖ Choose two different fields (x and y)."
            return None
        if None in names or len(set(names)) < len(names):
            self.progress.content = "✖ Choose two or three different figures (1, 2 and 3)."
            return None
        if self._invalid is not None and self._invalid():
            self.progress.content = (  # (a review: it ran around the last valid design)
                "✖ The input is invalid (see the red panel): fix it, and the sweep runs "
                "around the design you see."
            )
            return None
        kinds = (
            [k.value for k in PAPER_FOLLOWERS]
            if self.all_kinds.value
            else [design.follower.kind.value]
        )
        try:  # a client may send anything: two finite numbers per range, a step count
            (x0, x1), (y0, y1) = (
                _finite_pair(self.x_range.value),
                _finite_pair(self.y_range.value),
            )
        except (TypeError, ValueError):
            self.progress.content = (
                f"✖ Each range needs two finite numbers within ±{MAX_RANGE_ABS:g}."
            )
            return None
        steps = self.steps.value
        if not isinstance(steps, int | float) or steps not in range(2, MAX_STEPS + 1):
            self.progress.content = f"✖ Steps per field: a whole number from 2 to {MAX_STEPS}."
            return None
        # the boxes show what runs (a box left empty sends nothing: a review ran the
        # last range while the box stood blank)
        self.x_range.value, self.y_range.value = (x0, x1), (y0, y1)
        if x0 == x1 or y0 == y1:
            self.progress.content = "✖ Each range needs two different numbers."
            return None
        balance = balance_for(design, [px, py])  # (a segment's angle: a dwell's to give)
        grid = sweep_grid((px, x0, x1), (py, y0, y1), int(steps), kinds)
        base = design.model_dump(mode="json")
        try:
            points = grid_points(grid, base, balance)
        except DesignError as exc:  # (a range too narrow for its steps' distinct values)
            self.progress.content = f"✖ {esc(str(exc))}"
            return None
        return base, points, grid, (px, self.x.value), (py, self.y.value), names, balance

    def _balance(self, design: Design) -> str | None:
        """The segment angle that takes up the turn in the sweep the widgets describe
        (camcore.explore.balance_for), or None."""
        fields = fields_of(design)
        paths = [fields.get(dd.value) for dd in (self.x, self.y)]
        return balance_for(design, [p for p in paths if p is not None])

    def _sweep(self, base, points, grid, x, y, names, balance) -> None:
        """Analyse each distinct design once (points that differ only in a field their
        follower ignores make one design: camcore.sweep.same_designs), in chunks."""
        done: dict[int, dict] = {}  # point index -> its row, for the points analysed
        batched = not PROFILE_FIGURES & set(names)
        try:
            same = self._analyst.same_designs(base, points)
            own = [i for i, j in enumerate(same) if i == j]
            repeats = len(points) - len(own)
            note = f" ({repeats} more points repeat one)" if repeats else ""
            for c in range(0, len(own), CHUNK):
                if self._cancel.is_set():
                    break
                idx = own[c : c + CHUNK]
                rows = self._analyst.sweep_chunk(base, [points[i] for i in idx], batched)
                done.update(zip(idx, rows, strict=True))
                ok = _valid_designs(list(done.values()))
                if self._cancel.is_set():  # ("Cancelling…" stays)
                    continue
                self.progress.content = (
                    f"Running: **{len(done)} / {len(own)}** distinct designs{note}, "
                    f"{ok} valid so far…"
                )
            rows = [
                done[i] if i == j else with_point(done[j], p)
                for i, (j, p) in enumerate(zip(same, points, strict=True))
                if j in done
            ]
            span = [[p[path] for p in points] for path in (x[0], y[0])]  # the asked ranges
            limits = ((min(span[0]), max(span[0])), (min(span[1]), max(span[1])))
            ran = Ran(base, grid, rows, batched, len(points), balance)
            if not self._closed.is_set():  # (no map for a tab that is gone: a review)
                self._show(ran, x, y, names, limits)
        except Exception as exc:  # a worker lost: say so, keep the tab
            self.progress.content = f"✖ The sweep stopped: {esc(exc)}"
        finally:
            self.run_btn.disabled, self.cancel_btn.disabled = False, True

    def _show(self, ran: Ran, x, y, names, limits) -> None:
        base, rows = ran.base, ran.rows
        if not rows:
            self._clear()  # (a review: the last sweep's map stayed, loadable, unmarked)
            self.progress.content = "Cancelled before the first designs."
            return
        with self._lock:  # (a Cancel from now on has nothing left to stop)
            self._drawing, self.cancel_btn.disabled = True, True
            self._map_busy = True  # (a change of the panel's width waits for this map)
            self.progress.content = f"Drawing the map of {len(rows)} points…"
            px = self.shown_px
        try:
            front = pareto(rows, names)
            with self._map_lock:  # (a redraw for a new width may be drawing the last map)
                png = self._analyst.explore_png(rows, x, y, names, front, limits, px)
            values = figure_values(rows, names)
            offers = {}
            for n, i in enumerate(offered(front, values, MAX_FRONT), start=1):
                point, shown = _offer(rows[i])
                figs = ", ".join(
                    f"{FIGURES[m].symbol} {v:.4g} {FIGURES[m].unit}"
                    for m, v in zip(names, values[i], strict=True)
                )
                offers[f"{n}. {shown} → {figs}"] = point
            with self._lock:  # (the check and the publish in one hold: offer_fields)
                stale = fields_of(Design.model_validate(base)) != self._fields
                if not stale:
                    self._publish(ran, offers, png, (rows, x, y, names, front, limits, px))
            if stale:  # (a review: they came back, loadable, after another program's load)
                self._clear()
                self.progress.content = (
                    "The design on screen is another kind of program now: the sweep of "
                    "the earlier one is dropped. Run it again for this one."
                )
        finally:
            self._redraw()  # for a width the panel took meanwhile; frees the map

    def _publish(self, ran: Ran, offers: dict, png: bytes, drawn: tuple) -> None:
        """Show a finished sweep: its offers, map, downloads and summary (under
        self._lock)."""
        rows, x, y, names, front, limits, _ = drawn
        base, total = ran.base, ran.total
        self._base, self._offers, self._armed = base, offers, None
        self._ran, self.files_md.content = ran, ""
        self.csv_btn.disabled = self.spec_btn.disabled = False
        self._drawn = drawn
        self.front_dd.options = tuple(offers) or ("–",)
        self.front_dd.value = self.front_dd.options[0]
        self.load_btn.disabled = not offers
        self._put_image(png)
        self.progress.content = (
            _summary(rows, total, front, names, limits, len(offers))
            + _balanced_text(ran)
            + _outside_text(Design.model_validate(base), (x, y), limits)
        )

    def _put_image(self, png: bytes) -> None:
        """Show ``png`` as the map (under self._lock)."""
        if self.image is None:
            with self._folder:
                self.image = self.gui.add_image(_decode(png), format="png")
        else:
            self.image.image = _decode(png)

    def set_width(self, px: int) -> None:
        """The panel is now ``px`` wide: the map on show is drawn again for it, in the
        background (by whoever draws the map now, if anyone: a sweep's end or an
        earlier change of width)."""
        with self._lock:
            self.shown_px = px
            if self._map_busy or self._drawn is None or self._drawn[-1] == px:
                return
            self._map_busy = True
            threading.Thread(target=self._redraw, daemon=True, name="cam-map").start()

    def _redraw(self) -> None:
        """Draw the map on show for the panel's width until the two agree, then free
        the map (self._map_busy) in the same step as the last look at the width, so
        that no change of it goes unseen."""
        try:
            while True:
                with self._lock:
                    drawn, px = self._drawn, self.shown_px
                    if drawn is None or drawn[-1] == px:
                        self._map_busy = False
                        return
                rows, x, y, names, front, limits, _ = drawn
                with self._map_lock:
                    png = self._analyst.explore_png(rows, x, y, names, front, limits, px)
                with self._lock:
                    if self._drawn is drawn:  # (not cleared or replaced meanwhile)
                        self._drawn = (*drawn[:-1], px)
                        self._put_image(png)
        except Exception:  # (a worker lost: the map drawn for the old width stays)
            with self._lock:
                self._map_busy = False

    def _clear(self) -> None:
        """No results on show: no offers, no map."""
        with self._lock:
            self._offers, self._armed, self._drawn, self._ran = {}, None, None, None
            self.csv_btn.disabled = self.spec_btn.disabled = True
            self.files_md.content = ""
            self.front_dd.options = ("–",)
            self.front_dd.value = "–"
            self.load_btn.disabled = True
            if self.image is not None:
                self.image.remove()
                self.image = None

    def load(self, label: str) -> None:
        """Load a design of the front (the dropdown's value; anything else is ignored).

        The sweep ran around the design on screen when it started; if that design was
        edited since, loading replaces those edits: the first click says which fields
        would change, a second click on the same design loads it."""
        with self._lock:
            point, base = self._offers.get(label) if isinstance(label, str) else None, self._base
            ran, loaded = self._ran, self._loaded
        if self._load is None or self._design is None:
            return
        if point is None:  # not an offer of this sweep (a stale or forged value)
            self.progress.content = "✖ Choose a design of the front first (run a sweep)."
            return
        try:
            design = design_at(base, point)
        except DesignError as exc:
            self.progress.content = f"✖ {esc(exc)}"
            return
        # edits since the sweep's own design on screen: the one loaded from this sweep
        # last, or else the design it ran on (a review: loading a second design of one
        # front warned of "edits", the first's swept values and its follower's name)
        if loaded is not None and loaded[0] is ran:
            edits = edited_since(loaded[1], self._design(), {})
        else:
            edits = edited_since(Design.model_validate(base), self._design(), point)
        if edits and self._armed != label:
            self._armed = label
            self.progress.content = (
                "⚠ This sweep ran on an earlier design. Loading its design replaces your "
                f"later edits ({esc(', '.join(edits))}): click *Load this design* again "
                "to load it, or run the sweep again."
            )
            return
        self._armed = None
        self._load(design)
        with self._lock:
            self._loaded = (ran, design)  # (an edit made after it is an edit: a review)
        number = label.split(" ", 1)[0].rstrip(".")
        self.progress.content = f"Loaded design {esc(number)} of the Pareto front."

    def download(self, what: str) -> None:
        """Send the sweep on show: its rows as CSV (``what`` = "csv", the columns of
        ``camcore sweep``'s Parquet table) or as a SPEC ("spec") that ``camcore sweep``
        runs again, on this machine or a Dask cluster (issue 12: one who outgrows the
        app changes a flag, not the study)."""
        with self._lock:
            ran = self._ran
        if ran is None or self._send is None:
            self.files_md.content = "✖ Run a sweep first: the files hold its results."
            return
        stem = file_stem(Design.model_validate(ran.base))
        n, total = len(ran.rows), ran.total
        cut = f" (the sweep was cancelled after {n} of its {total} points)" if n < total else ""
        if what == "csv":
            name, data = f"{stem}-sweep.csv", csv_text(ran.rows).encode()
            said = f"{n} rows, one per point, the columns of `camcore sweep`'s table{cut}"
        else:
            name, data = (
                f"{stem}-sweep.json",
                spec_document(ran.base, ran.grid, ran.balance).encode(),
            )
            shown = name if _PLAIN_NAME.fullmatch(name) else "SPEC.json"  # (file_stem's
            # slug is plain: inside a code span esc's backslashes would show). The tab
            # ran the batched core, or the full analysis less the geometric check where
            # a figure needs the profile (a review: --fast had no wear column)
            flag, more = ("--fast", "the profile's") if ran.batched else ("--no-verify", "the")
            rows = f"all {total} points{cut}" if cut else "these rows"
            said = (
                f"run it with `camcore sweep {shown} --out results.parquet {flag}` for "
                f"{rows}, without `{flag}` for {more} checks too; `--workers N` or "
                "`--scheduler ADDRESS` runs it on Dask"
            )
        if len(data) > MAX_FILE_BYTES:  # (MAX_DESIGNS rows are ~2 MB: never, by design)
            self.files_md.content = f"✖ {esc(name)} would be {len(data):,} bytes: too large."
            return
        self._send(name, data)
        self.files_md.content = f"Sent **{esc(name)}** ({len(data):,} bytes): {said}."

    def cancel(self) -> None:
        """Stop the sweep after the chunk it is on (said at once: a chunk can take
        seconds on the full-analysis path); nothing once its results are being drawn."""
        with self._lock:
            running = self._thread is not None and self._thread.is_alive()
            if running and not self._drawing and not self._cancel.is_set():
                self._cancel.set()
                self.progress.content = "Cancelling after the current designs…"

    def close(self) -> None:
        """The tab is gone: the sweep stops after its chunk, and draws nothing."""
        self._closed.set()
        self._cancel.set()


def edited_since(base: Design, now: Design, point: dict, most: int = 4) -> list[str]:
    """How the design ``now`` differs from the sweep's ``base`` outside the swept fields
    (``point``'s paths), as the controls show them ("Lift h [mm]: 15 → 25"), up to
    ``most`` of them; a program that is (or was) edited as segments is named as such."""
    classic = base.motion.classic is not None and now.motion.classic is not None
    out = []
    for spec in SPECS:
        if spec.path in point or (spec.path.startswith("motion.") and not classic):
            continue
        a, b = control_value(base, spec), control_value(now, spec)
        if a != b:
            out.append(f"{spec.label}: {a} → {b}")
    if not classic and _segments_at(base, point) != _segments_at(now, point):
        out.append("the program's segments")
    return out[:most] + ([f"{len(out) - most} more"] if len(out) > most else [])


def _segments_at(design: Design, point: dict) -> list | None:
    """``design``'s segments (JSON data) with ``point``'s segment angles (a swept one
    and the dwell that took up the turn are the sweep's, not an edit: a review had
    the second design loaded from one front warn of "edits"); None if it has no
    such segment."""
    data = design.model_dump(mode="json")
    try:
        for path, value in point.items():
            if path.startswith("motion.segments."):
                set_field(data, path, value, "grid.")
    except DesignError:
        return None
    return data["motion"]["segments"]


def _offer(row: dict) -> tuple[dict, str]:
    """A front design's grid point, less the fields its follower ignores (loading it
    keeps the design's own value there: a review saw a concave face's design load with
    the sweep's roller radius), and how the list shows it ("–" for those fields)."""
    ignored = set(ignored_fields(row))
    point, shown = {}, []
    for key, v in row.items():
        if not key.startswith("grid."):
            continue
        path = key[5:]
        if path in ignored:
            shown.append(f"{symbol(path)} –")
            continue
        point[path] = v
        if path == "follower.kind" and isinstance(v, str) and v in FollowerKind.__members__:
            shown.append(FollowerKind(v).label)
        else:
            value = f"{v:.4g}" if isinstance(v, float) else str(v)
            shown.append(f"{symbol(path)} {value}")
    return point, ", ".join(shown)


def _balance_note(design: Design, balance: str) -> str:
    """Which dwell takes up the turn in a sweep of segment angles (the tab says it
    when such a field is chosen: its points change that dwell too)."""
    n = segment_number(balance)
    assert n is not None  # (balance_for gives a segment's angle)
    angle = design.motion.segments[n - 1].angle_deg
    return (
        f"Segment {n} (a dwell of {angle:g}°) takes up the turn: each point sets it "
        "to 360° less the other segments (a point that leaves it no angle is no design)."
    )


def _balanced_text(ran: Ran) -> str:
    """Under a finished sweep of segment angles: which dwell took up the turn (its
    angle is the list's last β; a user's review found it said only before the run)."""
    n = None if ran.balance is None else segment_number(ran.balance)
    return "" if n is None else f"<br>Segment {n}, a dwell, took up the turn (β{n} in the list)."


def _summary(rows: list[dict], total: int, front, names: list[str], limits, listed: int) -> str:
    """The line under a finished sweep: points and distinct designs, valid ones, the
    front; why points are no designs; what a figure cannot tell apart."""
    first = distinct(rows)
    ok = _valid_designs(rows)
    done = "" if len(rows) == total else f", cancelled after {len(rows)} of {total}"
    designs = f"**{len(rows)} points**{done}, {int(first.sum())} distinct designs"
    some = (
        f" ({listed} of them numbered and listed, spread along it)" if len(front) > listed else ""
    )
    points = sum(bool(r.get("valid")) for r in rows)
    valid = f"{ok} valid" + (f" ({points} of the points)" if points != ok else "")
    out = f"{designs}: {valid}, {len(front)} on the Pareto front{some}."
    errors = [str(r["error"]) for r, f in zip(rows, first, strict=True) if f and r.get("error")]
    if errors:  # one reason is one message but for the numbers in it (each point's own)
        reasons = [re.sub(r"-?[0-9][0-9.e+-]*", "#", e) for e in errors]
        common = max(sorted(set(reasons)), key=reasons.count)
        example = errors[reasons.index(common)]
        out += (
            f" {len(errors)} are no design at all; the commonest reason "
            f"({reasons.count(common)}), e.g.: {esc(example[:300])}."
        )
    if not ok:
        out += " No valid design: widen or move the ranges."
    out += _least_text(rows, names[0])
    flat = [axis for axis, (lo, hi) in zip("xy", limits, strict=True) if lo == hi]
    if flat:
        out += f" The {' and '.join(flat)} range{'s are' if len(flat) > 1 else ' is'} one value."
    kinds = {r.get("grid.follower.kind") for r in rows}
    rollers = [k for k in kinds if isinstance(k, str) and k.endswith("_roller")]
    if "wear" in names and rollers:
        out += " Rollers roll: their sliding wear is 0, so they lead on wear."
    return out


def _least_text(rows: list[dict], name: str) -> str:
    """The valid design least in the figure ``name`` for each follower the sweep ran
    (camcore.explore.best_per_kind): "the smallest cam each follower allows", read
    without narrowing the ranges (a designer's review); "" if none is valid."""
    best = best_per_kind(rows, name)
    if not best:
        return ""
    fig = FIGURES[name]
    value = figure_values([rows[i] for i in best.values()], [name])[:, 0]
    each = "; ".join(
        f"{_offer(rows[i])[1]} → {fig.symbol} {v:.4g} {fig.unit}"
        for i, v in zip(best.values(), value, strict=True)
    )
    several = len({r.get("grid.follower.kind") for r in rows}) > 1
    return f"<br>Least {fig.label}{' per follower' if several else ''}: {esc(each)}."


def _outside_text(design: Design, axes, limits) -> str:
    """A warning where ``design`` (the one the sweep ran around) lies outside a field's
    range (``axes``: (path, label) of x and y; ``limits``: their (lo, hi)): ranges kept
    in the browser from an earlier design (a teacher's review) leave it out of the map
    and of the front. "" if it lies inside both."""
    out = []
    for (path, label), (lo, hi) in zip(axes, limits, strict=True):
        v = get_path(design, path)
        if isinstance(v, int | float) and not lo <= v <= hi:
            out.append(f"{esc(label)} = {v:g} is outside its range {lo:g} … {hi:g}")
    if not out:
        return ""
    return (
        "\n\n⚠ The design on screen: " + "; ".join(out) + " (ranges kept from an earlier "
        "design?): *Ranges around the design on screen* centres them on it."
    )


def _valid_designs(rows: list[dict]) -> int:
    """Valid designs among the rows, each distinct design once (camcore.explore)."""
    return sum(bool(r.get("valid")) for r, f in zip(rows, distinct(rows), strict=True) if f)


def _range_label(axis: str, field_label: str) -> str:
    """ "x from, to [mm]": the range's label with the unit of its field's label."""
    unit = field_label[field_label.rfind("[") :] if field_label.endswith("]") else ""
    return f"{axis} from, to {unit}".rstrip()


def _finite_pair(value) -> tuple[float, float]:
    """(from, to) as two floats within +-MAX_RANGE_ABS, else ValueError (a review:
    -1e308 to 1e308 had made NaN points, and 1e308 to 1.7e308 a plot's ticks fail)."""
    lo, hi = (float(v) for v in value)
    if not (abs(lo) <= MAX_RANGE_ABS and abs(hi) <= MAX_RANGE_ABS):  # (NaN: False)
        raise ValueError("not finite")
    return lo, hi


def _kept_pair(value) -> tuple[float, float] | None:
    """A stored range: a list of two finite numbers, else None."""
    if not isinstance(value, list) or len(value) != 2:
        return None
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        return None
    try:
        return _finite_pair(value)
    except (OverflowError, ValueError):  # an integer too large for a float
        return None


def _decode(png: bytes) -> np.ndarray:
    """PNG bytes as an (H, W, 3) array for viser's image widget."""
    import io

    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
