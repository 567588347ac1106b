"""The headless protocol client (tests/viser_client.py) against a tiny viser server."""

from __future__ import annotations

import asyncio

import msgspec.msgpack
import numpy as np
import pytest
import viser
import viser._messages as vm
from viser_client import ProtocolError, ViserClient, build_message, decode_frame


@pytest.fixture(scope="module")
def tiny():
    """A slider, a markdown echoing it, a button, a plot and a per-client scene node."""
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)

    @server.on_client_connect
    def _(client) -> None:
        slider = client.gui.add_slider("Lift", 1.0, 60.0, 0.5, 10.0)
        md = client.gui.add_markdown("lift = 10.0")
        button = client.gui.add_button("Go")
        plot = client.gui.add_uplot(
            (np.arange(4.0), np.zeros(4)), ({"label": "x"}, {"label": "y"}), title="plot"
        )
        client.scene.add_box("/box", dimensions=(1.0, 1.0, 1.0))
        clicks = [0]

        @slider.on_update
        def _(_e) -> None:
            md.content = f"lift = {slider.value}"
            plot.data = (np.arange(4.0), np.full(4, slider.value))
            client.scene.add_icosphere("/ball", radius=slider.value * 1e-3)

        @button.on_click
        def _(_e) -> None:
            clicks[0] += 1
            md.content = f"clicked {clicks[0]}"
            client.scene.remove_by_name("/box")

    yield f"ws://127.0.0.1:{server.get_port()}"
    server.stop()


def run(coro):
    return asyncio.run(asyncio.wait_for(coro, 30))


def test_model_update_and_click(tiny):
    async def go():
        c = await ViserClient(tiny).connect()
        try:
            slider = await c.wait_gui("Lift")
            assert (slider.type, slider.value) == ("Slider", 10.0)
            assert (slider.props["min"], slider.props["max"], slider.props["step"]) == (
                1.0,
                60.0,
                0.5,
            )
            md = await c.wait_for(lambda: c.find_all(type="Markdown"), what="markdown")
            md = md[0]
            assert "lift = 10.0" in md.text
            plot = c.find(type="Uplot")
            assert plot.props["title"] == "plot"
            await c.wait_for(lambda: "/box" in c.scene_names, what="box")
            assert c.replay_done

            await c.set_value("Lift", 12.5)  # what the browser sends
            await c.wait_for(lambda: "lift = 12.5" in md.text, what="echo")
            await c.wait_for(
                lambda: float(np.asarray(plot.props["data"][1])[0]) == 12.5, what="plot data"
            )
            assert isinstance(plot.props["data"][1], np.ndarray)  # binary buffer decoded
            await c.wait_for(lambda: "/ball" in c.scene_names, what="ball")
            assert c.gui[slider.uuid].value == 12.5

            await c.click("Go")
            await c.wait_for(lambda: "clicked 1" in md.text, what="click")
            await c.wait_for(lambda: "/box" not in c.scene_names, what="box removed")
            assert not c.errors
        finally:
            await c.close()

    run(go())


def test_clients_are_independent(tiny):
    async def go():
        a, b = ViserClient(tiny, "a"), ViserClient(tiny, "b")
        await asyncio.gather(a.connect(), b.connect())
        try:
            await asyncio.gather(a.wait_gui("Lift"), b.wait_gui("Lift"))
            await a.set_value("Lift", 30.0)
            md_a = a.find(type="Markdown")
            await a.wait_for(lambda: "lift = 30.0" in md_a.text)
            await b.wait_quiet(0.3, 5)
            assert "lift = 10.0" in b.find(type="Markdown").text
        finally:
            await asyncio.gather(a.close(), b.close())

    run(go())


def test_decoder_is_strict():
    with pytest.raises(ProtocolError, match="unknown message type"):
        build_message({"type": "NoSuchMessage"})
    with pytest.raises(ProtocolError, match="unknown field"):
        build_message({"type": "GuiRemoveMessage", "uuid": "x", "extra": 1})
    with pytest.raises(ProtocolError):
        build_message({"type": "GuiRemoveMessage"})  # missing field
    props = {"order": 0.0, "_markdown": "hi", "visible": True}
    msg = build_message(
        {"type": "GuiMarkdownMessage", "uuid": "u", "container_uuid": "root", "props": props}
    )
    assert isinstance(msg, vm.GuiMarkdownMessage)
    with pytest.raises(ProtocolError, match="GuiMarkdownProps"):
        build_message(
            {
                "type": "GuiMarkdownMessage",
                "uuid": "u",
                "container_uuid": "root",
                "props": {**props, "renamed": 1},
            }
        )
    with pytest.raises(ProtocolError):
        decode_frame(b"\x00" * 8)


def test_frame_round_trip():
    """Encode a frame the way viser's producer does, decode it with the client."""
    import zstandard

    arr = np.linspace(0, 1, 5)
    msg = vm.GuiUpdateMessage("u", {"data": (arr, arr * 2)})
    bufs: list[memoryview] = []
    inner = msgspec.msgpack.encode(
        {
            "messages": (msg.as_serializable_dict(bufs),),
            "timestampSec": 0.0,
            "binaryBufferLengths": tuple(b.nbytes for b in bufs),
        }
    )
    comp = zstandard.ZstdCompressor().compress(inner)
    parts = [len(inner).to_bytes(8, "little"), len(comp).to_bytes(8, "little"), comp]
    off = 16 + len(comp)
    for b in bufs:
        pad = (8 - off % 8) % 8
        parts.append(b"\x00" * pad)
        parts.append(bytes(b))
        off += pad + b.nbytes
    (out,) = decode_frame(b"".join(parts))
    assert isinstance(out, vm.GuiUpdateMessage)
    np.testing.assert_array_equal(out.updates["data"][1], arr * 2)
