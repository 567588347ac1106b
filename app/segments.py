"""The motion program as a table of segments (issue 10): one row per segment (kind,
angle, lift, law, and ↑ ↓ ✕), an add button and the two sums a program must meet.

The table holds only its widgets. It reports every user edit to ``on_change``: the
whole list of segments (dicts as in a design file), or None for "read the table
(``current``) when the edit's turn comes"; the session decides whether
that makes a valid design. Values the session writes in (``show``) fire no edit.
"""

from __future__ import annotations

import contextlib
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from camcore.model import MAX_SEGMENTS

from .controls import LABEL_OF_LAW, LAW_LABELS, LAW_OF_LABEL, LAWS, fine
from .panels import segment_sums_markdown

KINDS = ("rise", "fall", "dwell")
ANGLE_RANGE = (0.0, 360.0)  # what a row's angle box takes [deg]
LIFT_RANGE = (0.001, 1000.0)  # what a row's lift box takes [mm]


@dataclass(frozen=True)
class Row:
    """One segment as the table shows it, from a MotionSegment or a table dict."""

    kind: str
    angle_deg: float
    lift_mm: float | None
    law: str | None

    @classmethod
    def of(cls, g) -> Row:
        if isinstance(g, dict):
            kind, law = str(g.get("kind")), g.get("law")
            return cls(
                kind if kind in KINDS else "dwell",
                float(g.get("angle_deg", 0.0)),
                g.get("lift_mm"),
                law if law in LAWS else None,
            )
        return cls(g.kind.value, float(g.angle_deg), g.lift_mm, g.law.value if g.law else None)

    def as_dict(self) -> dict:
        g: dict = {"kind": self.kind, "angle_deg": self.angle_deg}
        if self.kind != "dwell":
            g.update(lift_mm=self.lift_mm, law=self.law)
        return g


def moved(segs: list[dict], i: int, action: str) -> list[dict] | None:
    """The list after a row action: ↑ / ↓ move segment i, ✕ removes it, + appends a
    0° dwell. None where the action does nothing (or is not one of these: a client
    may send anything)."""
    segs = list(segs)
    if action == "+" and len(segs) < MAX_SEGMENTS:
        segs.append({"kind": "dwell", "angle_deg": 0.0})
    elif action == "✕" and len(segs) > 1 and 0 <= i < len(segs):
        segs.pop(i)
    elif action == "↑" and 0 < i < len(segs):
        segs[i - 1], segs[i] = segs[i], segs[i - 1]
    elif action == "↓" and 0 <= i < len(segs) - 1:
        segs[i], segs[i + 1] = segs[i + 1], segs[i]
    else:
        return None
    return segs


class SegmentTable:
    """The rows live in ``folder`` (a viser GUI folder of ``gui``)."""

    def __init__(self, gui, folder, on_change: Callable[[list[dict] | None], None]):
        self.gui, self.folder, self.on_change = gui, folder, on_change
        self.rows: list[dict] = []  # widget handles by key, one dict per segment
        self._extra: list = []
        self.sums: Any = None  # the sums' markdown handle, built with the rows
        # the thread writing the session's values in (show): viser runs a widget's
        # callbacks in the thread that sets its value, so that thread's callbacks are
        # the session's own writes; a user's edit arrives on another thread and counts
        # (a plain flag had dropped an edit made while the table was being redrawn)
        self._writer: int | None = None
        # held while show() writes the rows: an edit reads them whole, never half old
        # and half new (a review: a torn read had made a 351 deg program)
        self._rows_lock = threading.Lock()
        self.lock: Any = contextlib.nullcontext()  # the session's (bound with on_change)

    def kinds(self) -> list[str]:
        return [r["kind"].value for r in self.rows]

    def as_dicts(self) -> list[dict]:
        """The table's segments as the user sees them."""
        return [
            Row(
                r["kind"].value,
                float(r["angle"].value),
                float(r["lift"].value),
                LAW_OF_LABEL.get(r["law"].value, r["law"].value),
            ).as_dict()
            for r in self.rows
        ]

    def show(self, segs) -> None:
        """Show segments (MotionSegments or dicts): values in place when the rows match
        in kind, rows rebuilt when segments were added, removed or changed kind."""
        rows = [Row.of(g) for g in segs]
        typed = [str(g["kind"]) if isinstance(g, dict) else g.kind.value for g in segs]
        with self._rows_lock:
            self._write(rows, typed)
        self.sums.content = segment_sums_markdown([g.as_dict() for g in rows])

    def _write(self, rows: list[Row], typed: list[str]) -> None:
        if self.kinds() != typed:  # (as typed: a refused kind stays on screen as it is)
            self._build(rows)
        self._writer = threading.get_ident()
        try:
            for r, g, kind in zip(self.rows, rows, typed, strict=True):
                # a row whose kind the user changed in place keeps its widgets: their
                # lift and law follow the kind (a dwell made a rise had kept them greyed),
                # shown for a rise or fall only (a dwell's greyed "5 mm, cycloidal" read
                # as values of the dwell)
                dwell = kind == "dwell"
                for key in ("lift", "law"):
                    if r[key].disabled != dwell:
                        r[key].disabled, r[key].visible = dwell, not dwell
                r["angle"].value = g.angle_deg
                if g.lift_mm is not None:
                    r["lift"].value = float(g.lift_mm)
                if g.law is not None:
                    r["law"].value = LABEL_OF_LAW[g.law]
        finally:
            self._writer = None

    def _edited(self, widget, value) -> None:
        """A widget's new ``value``: on_change(None), and the session reads the whole
        table (``current``) when this edit's turn comes, not before it has taken its
        turn (a review: an edit that read the table first but took its turn second
        undid the edit after it); an edit a redraw wrote over meanwhile is dropped
        (the table shows what holds)."""
        if self._writer == threading.get_ident():
            return  # the session's own write
        with self._rows_lock:
            if not (widget.value is value or widget.value == value):  # (NaN is itself)
                return
        self.on_change(None)

    def current(self) -> list[dict]:
        """The table's segments, read when no redraw is half done."""
        with self._rows_lock:
            return self.as_dicts()

    def act(self, i: int, action: str) -> None:
        """A row's button (or the add button, i = len(rows), action "+"). The rows are
        read and changed under the session's lock: two quick clicks on "add" had read
        the same rows and added one segment."""
        with self.lock:
            segs = moved(self.as_dicts(), i, action)
            if segs is not None:
                self.on_change(segs)

    def _build(self, rows: list[Row]) -> None:
        for h in [h for r in self.rows for h in r.values()] + self._extra:
            h.remove()
        gui, self.rows = self.gui, []
        with self.folder:
            for i, g in enumerate(rows):
                self.rows.append(self._row(gui, i, g))
            add = gui.add_button("Add a segment (a 0° dwell at the end)")
            add.on_click(lambda _e: self.act(len(self.rows), "+"))
            self.sums = gui.add_markdown("")
            self._extra = [add, self.sums]

    def _row(self, gui, i: int, g: Row) -> dict:
        dwell, n = g.kind == "dwell", f"{i + 1}."
        row = {
            "kind": gui.add_dropdown(f"{n} kind", KINDS, initial_value=g.kind),
            "angle": fine(
                gui.add_number(
                    f"{n} angle [°]",
                    _in_range(g.angle_deg, ANGLE_RANGE, 0.0),
                    min=ANGLE_RANGE[0],
                    max=ANGLE_RANGE[1],
                    step=0.5,
                )
            ),
            "lift": fine(
                gui.add_number(
                    f"{n} lift [mm]",
                    _in_range(g.lift_mm or 5.0, LIFT_RANGE, 5.0),
                    min=LIFT_RANGE[0],
                    max=LIFT_RANGE[1],
                    step=0.5,
                    disabled=dwell,
                    visible=not dwell,
                )
            ),
            "law": gui.add_dropdown(
                f"{n} law",
                LAW_LABELS,
                disabled=dwell,
                visible=not dwell,
                initial_value=LABEL_OF_LAW[g.law or LAWS[0]],
            ),
            "move": gui.add_button_group(n, ("↑", "↓", "✕")),
        }
        for key in ("kind", "angle", "lift", "law"):
            row[key].on_update(lambda e: self._edited(e.target, e.target.value))
        row["move"].on_click(lambda e, j=i: self.act(j, e.target.value))
        return row


def _in_range(value: float, bounds: tuple[float, float], default: float) -> float:
    """A row's value as its new number box may start: within the box's bounds (viser
    refuses others), ``default`` if not finite. Only a value a hostile client sent past
    the box's bounds is changed (a review: a lift of 5000 mm left the table half built
    at the next redraw); the design had refused it already, and the status said why."""
    if not math.isfinite(value):
        return default
    return min(max(value, bounds[0]), bounds[1])
