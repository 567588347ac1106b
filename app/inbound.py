"""Bounds on what a tab sends over the websocket, besides its uploads (app.uploads),
and on the server's callback threads it may hold (TabLanes, at the end).

viser 1.1.1 accepts websocket messages of up to 50 MB and keeps whatever value a client
sends for a GUI element: any string for a text box or a dropdown, a tuple of any length
for a vector. A security review sent twenty 40 MB strings and two vectors of 5,000,000
numbers from one tab, and the server grew from 163 MB to 1.4 GB. A browser sends none
of this: its largest message is the answer to a read of the browser's storage (the
saved designs, at most a few MB: app.storage), and a widget's value is a short name or
two numbers. So:

- a message larger than MAX_MESSAGE_BYTES closes that tab's connection (the websockets
  library's own limit, lowered from viser's 50 MB);
- a GUI update whose value is a string longer than MAX_VALUE_CHARS, or a vector longer
  than the element's own, is dropped before viser keeps it, as are the updates viser's
  casts would crash on (a list for a number).

``install`` must run before the server is created: viser registers its handlers as
bound methods when the server starts. ``lane_tabs`` runs once it is created, before any
tab connects.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor

import websockets.asyncio.server
from viser._gui_api import GuiApi

MAX_MESSAGE_BYTES = 16 * 1024 * 1024  # (the saved list's 5 million characters, UTF-8)
MAX_VALUE_CHARS = 1000  # of a text box's or dropdown's value (a name: 60 characters)

_state = {"installed": False}


class _CappedServe(websockets.asyncio.server.serve):
    """websockets' ``serve`` with its message size capped at MAX_MESSAGE_BYTES."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs["max_size"] = min(kwargs.get("max_size") or MAX_MESSAGE_BYTES, MAX_MESSAGE_BYTES)
        super().__init__(*args, **kwargs)


def acceptable(current: object, value: object) -> bool:
    """Whether a client's ``value`` for a property of an element that holds ``current``
    is within what a browser sends: a string of at most MAX_VALUE_CHARS, a list only of
    the element's own vector's length, nothing nested otherwise. (Its type is viser's to
    cast; a wrong one is logged there and the server goes on.)"""
    if isinstance(current, tuple):
        return isinstance(value, (list, tuple)) and len(value) == len(current)
    if isinstance(value, str):
        return len(value) <= MAX_VALUE_CHARS
    return not isinstance(value, (list, tuple, dict, bytes))


def install() -> None:
    """Cap the websocket messages and the GUI values of every viser server created from
    now on (module docstring)."""
    if _state["installed"]:
        return
    handle_updates = GuiApi._handle_gui_updates

    async def guarded_updates(self, client_id, message) -> None:
        handle = self._gui_input_handle_from_uuid.get(message.uuid, None)
        if handle is not None and isinstance(message.updates, dict):
            state = handle._impl
            for prop, value in message.updates.items():
                if not acceptable(getattr(state, prop, None), value):
                    return  # dropped: not what a browser sends
        await handle_updates(self, client_id, message)

    GuiApi._handle_gui_updates = guarded_updates  # type: ignore[method-assign]
    websockets.asyncio.server.serve = _CappedServe  # type: ignore[misc]
    _state["installed"] = True


LANES_PER_TAB = 2  # of a tab's callbacks running at once (an edit beside a download)
MAX_QUEUED = 256  # of a tab's callbacks waiting their turn; more are dropped


class TabLanes:
    """viser's callback executor with each tab's callbacks in lanes of their own.

    viser runs every tab's plain-def callbacks on one 32-thread pool. A tab's callbacks
    take its lock in turn, so while one runs the others each parked a pool thread: one
    tab's burst of events (a slider, overlay toggles, Save clicks) took all 32 and froze
    every tab (a security review: 17-19 s). Here at most LANES_PER_TAB of a tab's
    callbacks hold pool threads; the rest wait in the tab's own queue, in order, and a
    tab with MAX_QUEUED waiting has its next ones dropped. A callback whose arguments
    name no tab (the server's own) goes to the pool as before.
    """

    def __init__(self, pool: ThreadPoolExecutor) -> None:
        self._pool = pool
        self._lock = threading.Lock()
        self._running: dict[int, int] = {}  # tab (client id) -> its callbacks running
        self._queued: dict[int, deque] = {}  # tab -> (fn, args, kwargs, future) waiting

    def submit(self, fn: Callable, /, *args, **kwargs) -> Future:
        tab = _tab_of(args)
        if tab is None:
            return self._pool.submit(fn, *args, **kwargs)
        future: Future = Future()
        with self._lock:
            queue = self._queued.setdefault(tab, deque())
            if self._running.get(tab, 0) < LANES_PER_TAB:
                self._running[tab] = self._running.get(tab, 0) + 1
                start = True
            elif len(queue) < MAX_QUEUED:
                queue.append((fn, args, kwargs, future))
                start = False
            else:  # dropped: this tab already has MAX_QUEUED callbacks waiting
                future.set_result(None)
                return future
        if start:
            self._pool.submit(self._lane, tab, (fn, args, kwargs, future))
        return future

    def _lane(self, tab: int, job: tuple) -> None:
        """Run ``job``, then the tab's waiting callbacks one after another."""
        while True:
            fn, args, kwargs, future = job
            if future.set_running_or_notify_cancel():
                try:
                    future.set_result(fn(*args, **kwargs))
                except BaseException as exc:  # (reported by viser's done callback)
                    future.set_exception(exc)
            with self._lock:
                queue = self._queued.get(tab)
                if queue:
                    job = queue.popleft()
                    continue
                self._running[tab] -= 1
                if not self._running[tab]:
                    del self._running[tab]
                    self._queued.pop(tab, None)
                return

    def shutdown(self, wait: bool = True, **kwargs) -> None:
        self._pool.shutdown(wait=wait, **kwargs)


def _tab_of(args: tuple) -> int | None:
    """The client id a callback's arguments belong to: a GUI event's, a client
    handle's (connect, disconnect) or a camera's; None for none."""
    for a in args:
        tab = getattr(a, "client_id", None)
        if tab is None and type(a).__name__ == "CameraHandle":
            tab = getattr(a.client, "client_id", None)
        if isinstance(tab, int):
            return tab
    return None


def lane_tabs(server) -> None:
    """Give ``server`` (a viser.ViserServer, before any tab connects) a TabLanes
    executor: the tabs' GUI and camera handlers take it as they are made."""
    server._thread_executor = TabLanes(server._thread_executor)
