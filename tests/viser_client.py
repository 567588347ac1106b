"""A small headless client for viser's websocket protocol (viser 1.1.1, pinned).

It speaks the wire format of the installed viser well enough to stand in for a
browser tab in load tests:

* connects with the subprotocol ``viser-v<version>`` and announces a camera (the
  server only runs ``on_client_connect`` after the first ``ViewerCameraMessage``);
* decodes the server's frames (zstd-compressed msgpack + raw aligned binary
  buffers, see ``viser.infra._infra._message_producer``) into viser's own message
  classes, strictly: an unknown message type or a field that is added, removed or
  renamed raises :class:`ProtocolError`, so a change of viser's protocol fails
  loudly instead of silently passing tests;
* keeps a model of the GUI (uuid -> type, label, value, props) and of the scene
  (node name -> type, props, pose), following update and remove messages;
* sends what the browser sends: ``GuiUpdateMessage(uuid, {"value": v})`` for an
  input (``ControlPanel/Generated.tsx``) and ``{"value": True}`` for a button
  press (``components/Button.tsx``), msgpack-encoded as a plain dict with a
  ``type`` key (``WebsocketClientWorker.ts``).

Everything is asyncio (``websockets.asyncio.client``), so one thread drives many
clients.
"""

from __future__ import annotations

import asyncio
import dataclasses
import functools
import time
from collections import Counter
from collections.abc import Callable
from typing import Any, get_args, get_origin

import msgspec.msgpack
import numpy as np
import viser
import viser._messages as vm
import websockets
import zstandard
from typing_extensions import get_type_hints
from websockets.asyncio.client import ClientConnection, connect

SUBPROTOCOL = f"viser-v{viser.__version__}"
_ZSTD = zstandard.ZstdDecompressor()


class ProtocolError(RuntimeError):
    """The server sent something this client does not understand."""


# --- decoding -------------------------------------------------------------------------


def _replace_placeholders(obj: Any, buffers: list[np.ndarray]) -> Any:
    if isinstance(obj, dict):
        if "__binary_index" in obj and "dtype" in obj:
            raw = buffers[obj["__binary_index"]]
            return raw.view(np.dtype(obj["dtype"]))
        return {k: _replace_placeholders(v, buffers) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_replace_placeholders(v, buffers) for v in obj]
    return obj


def split_frame(data: bytes) -> tuple[dict, list[np.ndarray]]:
    """One server frame -> (decoded msgpack dict, raw binary buffers as uint8 arrays).

    Layout: [u64 inner size][u64 compressed size][zstd msgpack][pad to 8][buffers...]
    """
    if len(data) < 16:
        raise ProtocolError(f"frame of {len(data)} bytes is shorter than its header")
    inner_len = int.from_bytes(data[0:8], "little")
    comp_len = int.from_bytes(data[8:16], "little")
    if 16 + comp_len > len(data):
        raise ProtocolError("frame shorter than its compressed payload")
    inner = _ZSTD.decompress(data[16 : 16 + comp_len], max_output_size=inner_len)
    if len(inner) != inner_len:
        raise ProtocolError(f"decompressed {len(inner)} bytes, header says {inner_len}")
    payload = msgspec.msgpack.decode(inner)
    if not isinstance(payload, dict) or "messages" not in payload:
        raise ProtocolError(f"unexpected frame payload keys: {list(payload)[:5]}")
    buffers: list[np.ndarray] = []
    offset = 16 + comp_len
    whole = np.frombuffer(data, np.uint8)
    for n in payload.get("binaryBufferLengths", ()):
        offset += (8 - offset % 8) % 8
        if offset + n > len(data):
            raise ProtocolError("binary buffer runs past the end of the frame")
        buffers.append(whole[offset : offset + n])
        offset += n
    return payload, buffers


_CLASSES: dict[str, type] = vm.Message._subclass_from_type_string()


def _check_dataclass_fields(value: Any, annotation: Any, where: str) -> None:
    """A dict sent for a dataclass-typed field must carry exactly its fields."""
    if get_origin(annotation) is not None:  # Optional[Props] etc.
        for arg in get_args(annotation):
            if dataclasses.is_dataclass(arg) and isinstance(value, dict):
                _check_dataclass_fields(value, arg, where)
        return
    if not (dataclasses.is_dataclass(annotation) and isinstance(value, dict)):
        return
    expected = {f.name for f in dataclasses.fields(annotation)}
    got = set(value)
    if got != expected:
        raise ProtocolError(
            f"{where}: fields {sorted(got ^ expected)} differ from viser's "
            f"{annotation.__name__} (extra {sorted(got - expected)}, "
            f"missing {sorted(expected - got)})"
        )


@functools.cache
def _hints(cls: type) -> dict[str, Any]:
    """The field annotations of a message class, resolved once per class: resolving them
    per message made the simulated tabs of the class bench spend ~80 % of their CPU
    in typing.get_type_hints, competing with the server they measure."""
    return get_type_hints(cls)


def build_message(mapping: dict) -> vm.Message:
    """A decoded message dict -> an instance of viser's own message class (strict)."""
    mapping = dict(mapping)
    type_name = mapping.pop("type", None)
    cls = _CLASSES.get(type_name) if isinstance(type_name, str) else None
    if cls is None:
        raise ProtocolError(f"unknown message type {type_name!r}")
    hints = _hints(cls)
    for k, v in mapping.items():
        if k not in hints:
            raise ProtocolError(f"{type_name}: unknown field {k!r}")
        _check_dataclass_fields(v, hints[k], f"{type_name}.{k}")
    init_names = {f.name for f in dataclasses.fields(cls) if f.init}
    kwargs = {k: v for k, v in mapping.items() if k in init_names}
    late = {k: v for k, v in mapping.items() if k not in init_names}
    try:
        msg = cls(**kwargs)
    except TypeError as exc:
        raise ProtocolError(f"{type_name}: {exc}") from exc
    for k, v in late.items():
        setattr(msg, k, v)
    return msg


def decode_frame(data: bytes) -> list[vm.Message]:
    payload, buffers = split_frame(data)
    return [build_message(_replace_placeholders(m, buffers)) for m in payload["messages"]]


def encode_message(msg: vm.Message) -> bytes:
    """Client -> server encoding: msgpack of the message's fields plus ``type``."""
    return msgspec.msgpack.encode(msg.as_serializable_dict())


# --- model ------------------------------------------------------------------------------


@dataclasses.dataclass
class GuiElement:
    uuid: str
    type: str  # message class name without "Gui"/"Message", e.g. "Slider", "Markdown"
    container: str | None
    props: dict[str, Any]
    value: Any = None
    has_value: bool = False

    @property
    def label(self) -> str | None:
        return self.props.get("label")

    @property
    def text(self) -> str:
        """Markdown/HTML content (rendered markdown for markdown elements)."""
        for key in ("_markdown", "content"):
            if key in self.props and isinstance(self.props[key], str):
                return self.props[key]
        return ""


@dataclasses.dataclass
class SceneNode:
    name: str
    type: str
    owner: str
    props: dict[str, Any]
    position: tuple | None = None
    wxyz: tuple | None = None
    visible: bool = True


def _short_type(cls_name: str) -> str:
    s = cls_name
    if s.startswith("Gui"):
        s = s[3:]
    if s.endswith("Message"):
        s = s[: -len("Message")]
    return s


def _as_dict(props: Any) -> dict:
    if isinstance(props, dict):
        return dict(props)
    if dataclasses.is_dataclass(props):
        return dict(vars(props))
    return {}


class ViserClient:
    """One simulated browser tab."""

    def __init__(self, url: str, name: str = "client"):
        if url.startswith("http"):
            url = "ws" + url[4:]
        self.url = url
        self.name = name
        self.ws: ClientConnection | None = None
        self.gui: dict[str, GuiElement] = {}
        self.scene: dict[tuple[str, str], SceneNode] = {}
        self.counts: Counter[str] = Counter()
        self.frames = 0
        self.bytes_in = 0
        self.replay_done = False
        self.errors: list[BaseException] = []
        self.closed_reason: str | None = None
        self.last_frame_t = 0.0
        self._changed = asyncio.Event()
        self._reader: asyncio.Task | None = None
        self._listeners: list[Callable[[vm.Message, float], None]] = []

    # -- connection ----------------------------------------------------------------

    async def connect(self, timeout: float = 10.0, camera: bool = True) -> ViserClient:
        self.ws = await asyncio.wait_for(
            connect(
                self.url,
                subprotocols=[SUBPROTOCOL],
                max_size=None,
                compression=None,
                open_timeout=timeout,
                ping_interval=None,
            ),
            timeout,
        )
        self._reader = asyncio.get_running_loop().create_task(self._read_loop())
        if camera:
            await self.send_camera()
        return self

    async def send_camera(self, width: int = 800, height: int = 600) -> None:
        await self.send(
            vm.ViewerCameraMessage(
                wxyz=(1.0, 0.0, 0.0, 0.0),
                position=(0.0, 0.0, 1.0),
                fov=1.0,
                near=0.01,
                far=100.0,
                image_height=height,
                image_width=width,
                look_at=(0.0, 0.0, 0.0),
                up_direction=(0.0, 0.0, 1.0),
            )
        )

    async def send(self, msg: vm.Message) -> None:
        assert self.ws is not None, "not connected"
        await self.ws.send(encode_message(msg))

    async def send_raw(self, data: bytes | str) -> None:
        assert self.ws is not None, "not connected"
        await self.ws.send(data)

    async def close(self) -> None:
        if self.ws is not None:
            try:
                await asyncio.wait_for(self.ws.close(), 5.0)
            except (TimeoutError, OSError, websockets.ConnectionClosed):
                self.abort()
        await self._stop_reader()

    def abort(self) -> None:
        """Vanish: drop the TCP connection without a websocket close handshake."""
        transport = self.ws.transport if self.ws is not None else None
        if transport is not None and not transport.is_closing():  # (closed: nothing to drop)
            transport.abort()

    async def _stop_reader(self) -> None:
        if self._reader is not None:
            self._reader.cancel()
            try:
                await self._reader
            except (asyncio.CancelledError, Exception):
                pass
            self._reader = None

    @property
    def connected(self) -> bool:
        return self.ws is not None and self.closed_reason is None

    async def _read_loop(self) -> None:
        assert self.ws is not None
        try:
            async for data in self.ws:
                t = time.perf_counter()
                if not isinstance(data, bytes):
                    raise ProtocolError(f"text frame from server: {data[:80]!r}")
                self.frames += 1
                self.bytes_in += len(data)
                self.last_frame_t = t
                for msg in decode_frame(data):
                    self.apply(msg)
                    for cb in self._listeners:
                        cb(msg, t)
                self._changed.set()
            self.closed_reason = f"closed {self.ws.close_code} {self.ws.close_reason}"
        except websockets.ConnectionClosed as exc:
            self.closed_reason = f"closed {exc}"
        except Exception as exc:  # a decode error: keep it for the test to see
            self.errors.append(exc)
            self.closed_reason = f"error {exc!r}"
        finally:
            self._changed.set()

    # -- model -----------------------------------------------------------------------

    def apply(self, msg: vm.Message) -> None:
        name = type(msg).__name__
        self.counts[name] += 1
        if isinstance(msg, vm._CreateGuiComponentMessage):
            el = GuiElement(
                uuid=msg.uuid,
                type=_short_type(name),
                container=getattr(msg, "container_uuid", None),
                props=_as_dict(getattr(msg, "props", {})),
            )
            if hasattr(msg, "value"):
                el.value, el.has_value = msg.value, True
            self.gui[msg.uuid] = el
        elif isinstance(msg, vm.GuiUpdateMessage):
            el = self.gui.get(msg.uuid)
            if el is None:
                return  # the browser ignores it too
            for k, v in msg.updates.items():
                if k == "value":
                    el.value, el.has_value = v, True
                else:
                    el.props[k] = v
        elif isinstance(msg, vm.GuiRemoveMessage):
            self.gui.pop(msg.uuid, None)
        elif isinstance(msg, vm.ResetGuiMessage):
            self.gui.clear()
        elif isinstance(msg, vm._CreateSceneNodeMessage):
            key = (msg.owner, msg.name)
            self.scene[key] = SceneNode(
                name=msg.name,
                type=name.removesuffix("Message"),
                owner=msg.owner,
                props=_as_dict(getattr(msg, "props", {})),
            )
        elif isinstance(msg, vm.RemoveSceneNodeMessage):
            self.scene.pop((msg.owner, msg.name), None)
        elif isinstance(msg, vm.SceneNodeUpdateMessage):
            node = self.scene.get((msg.owner, msg.name))
            if node is not None:
                node.props.update(msg.updates)
        elif isinstance(msg, vm.SetPositionMessage):
            node = self.scene.get((msg.owner, msg.name))
            if node is not None:
                node.position = tuple(msg.position)
        elif isinstance(msg, vm.SetOrientationMessage):
            node = self.scene.get((msg.owner, msg.name))
            if node is not None:
                node.wxyz = tuple(msg.wxyz)
        elif isinstance(msg, vm.SetSceneNodeVisibilityMessage):
            node = self.scene.get((msg.owner, msg.name))
            if node is not None:
                node.visible = bool(msg.visible)
        elif isinstance(msg, vm.ReplayDoneMessage):
            self.replay_done = True

    def add_listener(self, cb: Callable[[vm.Message, float], None]) -> None:
        """``cb(message, receive_time)`` for every decoded message, after the model."""
        self._listeners.append(cb)

    def remove_listener(self, cb: Callable[[vm.Message, float], None]) -> None:
        self._listeners.remove(cb)

    @property
    def scene_names(self) -> set[str]:
        return {n.name for n in self.scene.values()}

    def find_all(
        self, label: str | None = None, type: str | None = None, contains: str | None = None
    ) -> list[GuiElement]:
        out = []
        for el in self.gui.values():
            if label is not None and el.label != label:
                continue
            if type is not None and el.type != type:
                continue
            if contains is not None and contains not in el.text:
                continue
            out.append(el)
        return out

    def find(
        self, label: str | None = None, type: str | None = None, contains: str | None = None
    ) -> GuiElement:
        """The one element matching; KeyError if none or several."""
        found = self.find_all(label, type, contains)
        if len(found) != 1:
            have = sorted({str(e.label) for e in self.gui.values() if e.label})
            raise KeyError(
                f"{len(found)} GUI elements match label={label!r} type={type!r} "
                f"contains={contains!r}; labels: {have}"
            )
        return found[0]

    def _resolve(self, target: str | GuiElement) -> GuiElement:
        if isinstance(target, GuiElement):
            return target
        if target in self.gui:
            return self.gui[target]
        return self.find(label=target)

    # -- actions ---------------------------------------------------------------------

    async def set_value(self, target: str | GuiElement, value: Any) -> GuiElement:
        """Change an input as the browser does: local state first, then the update."""
        el = self._resolve(target)
        el.value, el.has_value = value, True
        await self.send(vm.GuiUpdateMessage(el.uuid, {"value": value}))
        return el

    async def click(self, target: str | GuiElement) -> GuiElement:
        el = self._resolve(target)
        await self.send(vm.GuiUpdateMessage(el.uuid, {"value": True}))
        return el

    async def wait_for(
        self, predicate: Callable[[], Any], timeout: float = 10.0, what: str = "condition"
    ) -> Any:
        """Wait until ``predicate()`` is truthy (checked after every frame)."""
        deadline = time.monotonic() + timeout
        while True:
            self._changed.clear()
            result = predicate()
            if result:
                return result
            if self.errors:
                raise self.errors[0]
            if self.closed_reason is not None:
                raise ConnectionError(f"{self.name}: {self.closed_reason} while waiting for {what}")
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"{self.name}: timed out after {timeout:g} s waiting for {what}")
            try:
                await asyncio.wait_for(self._changed.wait(), left)
            except TimeoutError:
                pass

    async def wait_quiet(self, quiet: float = 0.3, timeout: float = 10.0) -> None:
        """Wait until no frame has arrived for ``quiet`` seconds (bounded)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if time.perf_counter() - self.last_frame_t >= quiet:
                return
            await asyncio.sleep(quiet / 3)

    async def wait_gui(self, label: str, timeout: float = 10.0) -> GuiElement:
        await self.wait_for(
            lambda: self.find_all(label=label), timeout, what=f"GUI element {label!r}"
        )
        return self.find(label=label)
