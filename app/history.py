"""Undo and redo of a tab's designs.

Every design the tab shows replaces the one before it; the one before is kept here,
so that a designer can try a change and step back. A slider dragged through twenty
values is one step: a change within SETTLE_S of the previous one joins it (the design
before the burst is the one kept), as the refiner waits for the tab to be still. At
most MOST steps are kept each way; a new change empties the redo side. The browser
keeps the last KEPT each way (app.storage.HISTORY_KEY), so a reload keeps them. Pure
bookkeeping: app.session applies what it returns.
"""

from __future__ import annotations

import math

from camcore.model import Design

MOST = 50  # steps kept back (and forward)
KEPT = 20  # of them, the steps each way the browser keeps across a reload (app.storage)
SETTLE_S = 0.6  # a change within this of the previous one is the same step [s]


class History:
    """The designs before (``past``) and after (``future``) the one on screen."""

    def __init__(self) -> None:
        self.past: list[Design] = []
        self.future: list[Design] = []
        self._last = -math.inf  # when the last change was recorded [s, monotonic]
        self.version = 0  # counts changes of the steps (not of a burst joining one)

    def record(self, before: Design, now: float) -> None:
        """The design on screen changed at ``now`` [s]; ``before`` is the one it replaced."""
        new_step = now - self._last >= SETTLE_S or not self.past
        if new_step or self.future:  # (a burst joining a step changes no step)
            self.version += 1
        if new_step:
            self.past.append(before)
            del self.past[:-MOST]
        self._last = now
        self.future.clear()

    def undo(self, current: Design) -> Design | None:
        """The design to show instead of ``current`` (which becomes redoable), None if
        there is nothing to undo."""
        return self._step(self.past, self.future, current)

    def redo(self, current: Design) -> Design | None:
        """The design undone last, None if there is none."""
        return self._step(self.future, self.past, current)

    def drop_same(self, current: Design) -> None:
        """Drop the last steps back that are ``current`` itself (a change undone by hand
        in one burst): none of them would change the design."""
        self._drop_same(self.past, current)

    def _drop_same(self, source: list[Design], current: Design) -> None:
        if source and source[-1] == current:
            self.version += 1
        while source and source[-1] == current:
            source.pop()

    def _step(self, source: list[Design], dest: list[Design], current: Design) -> Design | None:
        self._drop_same(source, current)
        if not source:
            return None
        dest.append(current)
        del dest[:-MOST]
        self._last = -math.inf  # the next change is a step of its own
        self.version += 1
        return source.pop()

    def clear(self) -> None:
        self.restore([], [])

    def restore(self, past: list[Design], future: list[Design]) -> None:
        """Take ``past`` and ``future`` as the steps (a reload's, app.storage)."""
        self.past, self.future = past[-MOST:], future[-MOST:]
        self._last = -math.inf
        self.version += 1

    def text(self) -> str:
        """How many steps each way, for the line under the buttons ("" if none)."""
        if not self.past and not self.future:
            return ""
        n = len(self.past)
        return f"{n} {'step' if n == 1 else 'steps'} to undo, {len(self.future)} to redo"
