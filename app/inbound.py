"""Bounds on what a tab sends over the websocket, besides its uploads (app.uploads).

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
bound methods when the server starts.
"""

from __future__ import annotations

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
