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

The bytes one tab may have in unfinished transfers are capped too (MAX_IN_FLIGHT_BYTES,
declared sizes): a review started 150 uploads of just under the cap and left them
unfinished, and the server grew by 145 MB.

The refusal is reported through ``on_refused(client_id, filename, size_bytes, why)`` so
the tab can say why its upload went nowhere.
"""

from __future__ import annotations

from collections.abc import Callable

from viser._gui_api import GuiApi

MAX_UPLOAD_BYTES = 1_000_000  # a design file is a few kB (camcore.model.MAX_DESIGN_BYTES)
MAX_IN_FLIGHT_BYTES = 2 * MAX_UPLOAD_BYTES  # declared bytes of one tab's unfinished uploads
MAX_IN_FLIGHT = 4  # unfinished uploads of one tab, whatever they declare (a second
# review's transfers declaring 0 bytes were never counted, and never finished)
MAX_NAME_CHARS = 1000  # of an upload's file name and type (kept while it is unfinished)
# the smallest part a transfer may announce on average: viser's browser sends 512 KiB
# parts, so a 1 MB file comes in 2; a review announced 2^62 parts and sent 300,000
# empty ones, each kept (22 MB for nothing, until the tab closed)
MIN_PART_BYTES = 16 * 1024

_state: dict = {"max_bytes": MAX_UPLOAD_BYTES, "on_refused": None, "installed": False}


def install(
    max_bytes: int = MAX_UPLOAD_BYTES,
    on_refused: Callable[[int, str, int, str], None] | None = None,
) -> None:
    """Cap every upload of every viser server created from now on at ``max_bytes``."""
    _state["max_bytes"], _state["on_refused"] = max_bytes, on_refused
    if _state["installed"]:
        return
    start, part = GuiApi._handle_file_transfer_start, GuiApi._handle_file_transfer_part

    def guarded_start(self, client_id, message):
        cap, size = _state["max_bytes"], message.size_bytes
        if size > cap or size < 0:
            _refuse(client_id, message.filename, size, f"more than the {cap:,}-byte limit")
            return  # never buffered: its parts find no transfer and are ignored
        name, mime = message.filename, message.mime_type
        if not (isinstance(name, str) and isinstance(mime, str)):
            return  # not what a browser sends: dropped
        if len(name) > MAX_NAME_CHARS or len(mime) > MAX_NAME_CHARS:
            _refuse(client_id, name, size, "its name is too long")
            return
        if not 0 <= message.part_count <= max(1, -(-size // MIN_PART_BYTES)):
            _refuse(client_id, name, size, f"it announced {message.part_count:,} parts")
            return
        mine = [
            s["total_bytes"]
            for s in list(self._current_file_upload_states.values())
            if s.get("client_id") == client_id
        ]
        if len(mine) >= MAX_IN_FLIGHT or sum(mine) + size > MAX_IN_FLIGHT_BYTES:
            why = f"{len(mine)} earlier uploads from this tab ({sum(mine):,} bytes) are unfinished"
            _refuse(client_id, message.filename, size, why)
            return
        start(self, client_id, message)

    def guarded_part(self, client_id, message):
        state = self._current_file_upload_states.get(message.transfer_uuid)
        if state is not None:
            if not message.content:  # (an empty part carries nothing: never kept)
                return
            cap, declared = _state["max_bytes"], state["total_bytes"]
            got = state["transferred_bytes"] + len(message.content)
            if got > min(cap, declared):
                self._current_file_upload_states.pop(message.transfer_uuid, None)
                why = (
                    f"more than the {cap:,}-byte limit"
                    if got > cap
                    else f"more than the {declared:,} bytes it announced"
                )
                _refuse(client_id, state["filename"], got, why)
                return
        part(self, client_id, message)

    GuiApi._handle_file_transfer_start = guarded_start  # type: ignore[method-assign]
    GuiApi._handle_file_transfer_part = guarded_part  # type: ignore[method-assign]
    _state["installed"] = True


def _refuse(client_id: int, filename: str, size: int, why: str) -> None:
    callback = _state["on_refused"]
    if callback is not None:
        callback(client_id, filename, size, why)
