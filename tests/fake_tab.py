"""A headless stand-in for a browser tab (tests and bench): a websocket client that
viser counts as a connected client once it has sent its camera."""

from __future__ import annotations

import threading

import msgspec
import viser
import websockets.sync.client as wsc


class FakeTab:
    def __init__(self, port: int, host: str = "127.0.0.1"):
        self.ws = wsc.connect(
            f"ws://{host}:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None
        )
        self.ws.send(
            msgspec.msgpack.encode(
                {
                    "type": "ViewerCameraMessage",
                    "wxyz": [1.0, 0.0, 0.0, 0.0],
                    "position": [0.0, 0.0, 1.0],
                    "fov": 1.0,
                    "near": 0.01,
                    "far": 100.0,
                    "image_height": 700,
                    "image_width": 1000,
                    "look_at": [0.0, 0.0, 0.0],
                    "up_direction": [0.0, 1.0, 0.0],
                }
            )
        )
        self.bytes = 0
        threading.Thread(target=self._drain, daemon=True).start()

    def _drain(self) -> None:
        try:
            for m in self.ws:
                self.bytes += len(m)
        except Exception:
            pass

    def camera(self, position, look_at, width: int, height: int) -> None:
        """Send a camera message, as a browser does on an orbit or a resize."""
        self.ws.send(
            msgspec.msgpack.encode(
                {
                    "type": "ViewerCameraMessage",
                    "wxyz": [1.0, 0.0, 0.0, 0.0],
                    "position": [float(v) for v in position],
                    "fov": 0.14,
                    "near": 0.01,
                    "far": 100.0,
                    "image_height": height,
                    "image_width": width,
                    "look_at": [float(v) for v in look_at],
                    "up_direction": [0.0, 1.0, 0.0],
                }
            )
        )

    def close(self) -> None:
        self.ws.close()
