"""A size cap on file uploads, enforced as the bytes arrive.

viser 1.1.1 buffers every part of an upload in memory and only hands the whole file
to the app when the last part has arrived, so an application-level size check comes
too late: a 45 MB upload raised the server by ~100 MB, and unfinished uploads stayed
buffered until the tab closed. viser has no hook for this, so we wrap the two handlers
of its GUI API that receive an upload (its start message, which declares the size,
and each part) at the narrowest point: a transfer that declares more than the cap is
never buffered, and one whose received bytes pass the cap (or its own declared size)
is dropped at once. ``install`` must run before the server is created, because viser
registers the handlers as bound methods in ``GuiApi.__init__``.

The refusal is reported through ``on_refused(client_id, filename, size_bytes)`` so the
tab can say why its upload went nowhere.
"""

from __future__ import annotations

from collections.abc import Callable

from viser._gui_api import GuiApi

MAX_UPLOAD_BYTES = 1_000_000  # a design file is a few kB (camcore.model.MAX_DESIGN_BYTES)

_state: dict = {"max_bytes": MAX_UPLOAD_BYTES, "on_refused": None, "installed": False}


def install(
    max_bytes: int = MAX_UPLOAD_BYTES, on_refused: Callable[[int, str, int], None] | None = None
) -> None:
    """Cap every upload of every viser server created from now on at ``max_bytes``."""
    _state["max_bytes"], _state["on_refused"] = max_bytes, on_refused
    if _state["installed"]:
        return
    start, part = GuiApi._handle_file_transfer_start, GuiApi._handle_file_transfer_part

    def guarded_start(self, client_id, message):
        if message.size_bytes > _state["max_bytes"] or message.size_bytes < 0:
            _refuse(client_id, message.filename, message.size_bytes)
            return  # never buffered: its parts find no transfer and are ignored
        start(self, client_id, message)

    def guarded_part(self, client_id, message):
        state = self._current_file_upload_states.get(message.transfer_uuid)
        if state is not None:
            limit = min(_state["max_bytes"], state["total_bytes"])
            if state["transferred_bytes"] + len(message.content) > limit:
                self._current_file_upload_states.pop(message.transfer_uuid, None)
                _refuse(
                    client_id, state["filename"], state["transferred_bytes"] + len(message.content)
                )
                return
        part(self, client_id, message)

    GuiApi._handle_file_transfer_start = guarded_start  # type: ignore[method-assign]
    GuiApi._handle_file_transfer_part = guarded_part  # type: ignore[method-assign]
    _state["installed"] = True


def _refuse(client_id: int, filename: str, size: int) -> None:
    callback = _state["on_refused"]
    if callback is not None:
        callback(client_id, filename, size)
