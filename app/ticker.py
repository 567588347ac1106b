"""Two small background loops that know nothing of cams or sessions.

``Ticker`` calls ``step(dt, n)`` at a fixed rate while it runs (the animation);
``Debouncer`` calls ``work()`` once its owner has been still for a while (the
verified analysis and the comparison, which cost ~0.1 s each), and at most one
debounced job runs at a time across everything that shares its ``gate``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable


class Ticker:
    """Calls ``step(dt, n)`` ``fps`` times a second while running; asleep otherwise.

    dt is the real time since the last step (capped at ``max_dt`` s so a stalled
    machine does not jump the animation), n counts steps since start. ``ticks`` is
    the number of steps taken (read by the bench)."""

    def __init__(
        self,
        step: Callable[[float, int], None],
        fps: float = 30.0,
        max_dt: float = 0.2,
        name: str = "ticker",
    ):
        self.step, self.period, self.max_dt = step, 1.0 / fps, max_dt
        self.running = False
        self.ticks = 0
        self.failures = 0  # steps that raised (logged; the animation goes on)
        self._wake = threading.Event()
        self._closed = threading.Event()
        self.thread = threading.Thread(target=self._loop, daemon=True, name=name)

    def start(self) -> Ticker:
        self.thread.start()
        return self

    def run(self, on: bool) -> None:
        self.running = on
        if on:
            self._wake.set()

    def close(self) -> None:
        self._closed.set()
        self._wake.set()

    def _loop(self) -> None:
        n, last = 0, time.perf_counter()
        while not self._closed.is_set():
            if not self.running:
                self._wake.wait(0.5)
                self._wake.clear()
                last = time.perf_counter()
                continue
            now = time.perf_counter()
            try:
                self.step(min(now - last, self.max_dt), n)
            except Exception:  # the owner went away mid-step, or a defect of a step
                if self._closed.is_set():
                    return
                # logged, and the animation goes on: one bad step (a review found one
                # from a client's NaN camera) must not stop a tab's animation for good
                self.failures += 1
                if self.failures == 1 or self.failures % 1000 == 0:
                    logging.getLogger(__name__).exception("animation step failed")
            self.ticks += 1
            last, n = now, n + 1
            time.sleep(max(0.0, self.period - (time.perf_counter() - now)))


class Debouncer:
    """Runs ``work()`` after ``poke()`` once no other poke came for ``quiet_s``.

    ``gate`` (a semaphore shared by all debouncers of a server) lets one job run at a
    time, so the cheap foreground work of every tab always comes first. ``pending``
    tells a running job that a newer poke makes its result stale."""

    def __init__(
        self,
        work: Callable[[], None],
        quiet_s: float,
        gate: threading.Semaphore,
        name: str = "debouncer",
    ):
        self.work, self.quiet_s, self.gate = work, quiet_s, gate
        self._poked = threading.Event()
        self._closed = threading.Event()
        self.thread = threading.Thread(target=self._loop, daemon=True, name=name)

    def start(self) -> Debouncer:
        self.thread.start()
        return self

    def poke(self) -> None:
        self._poked.set()

    @property
    def pending(self) -> bool:
        return self._poked.is_set()

    def close(self) -> None:
        self._closed.set()
        self._poked.set()

    def _loop(self) -> None:
        while not self._closed.is_set():
            if not self._poked.wait(0.5):
                continue
            self._poked.clear()
            time.sleep(self.quiet_s)
            if self._poked.is_set():
                continue  # poked again meanwhile: wait for quiet again
            with self.gate:
                if not self._poked.is_set() and not self._closed.is_set():
                    self._run()

    def _run(self) -> None:
        """One job; a defect of it is logged and the loop goes on (it had ended the
        thread, and the tab's checks stayed "running" for good: a review)."""
        try:
            self.work()
        except Exception:
            if not self._closed.is_set():
                logging.getLogger(__name__).exception("background job failed")
