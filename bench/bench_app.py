"""Bench of the design studio, on the server: re-analysis + redraw per slider change,
and the cost and rate of animation frames. ``python bench/bench_app.py`` prints a table;
``run(quick)`` returns rows {name, median_ms, p10_ms, p90_ms, n, note} for bench/run.py."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from rows import row

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the test helper

from fake_tab import FakeTab  # noqa: E402

from app.main import App  # noqa: E402
from camcore.analysis import analyze  # noqa: E402


def _row(name, samples_s, note=""):
    return row(name, np.asarray(samples_s) * 1e3, note)


def _session(app):
    before = set(app.sessions)
    tab = FakeTab(app.port)
    t0 = time.time()
    while not set(app.sessions) - before:
        if time.time() - t0 > 20:
            raise RuntimeError("no session")
        time.sleep(0.02)
    (cid,) = set(app.sessions) - before
    return tab, app.sessions[cid]


def run(quick: bool = False) -> list[dict]:
    n = 10 if quick else 30
    rows = []
    app = App(host="127.0.0.1", port=0)
    try:
        tab, s = _session(app)
        time.sleep(1.5)  # let the background verification of the first design finish
        for kind in ("double_concave", "single_concave", "double_roller", "single_roller"):
            s.ui.controls["follower.kind"].value = kind
            d = s.design
            t = []
            for _ in range(n):
                t.append(time.perf_counter())
                analyze(d, verify=False)
                t[-1] = time.perf_counter() - t[-1]
            rows.append(_row(f"analyze(verify=False) {kind}", t, "camcore alone, 0.1 deg grid"))
            t = []
            for i in range(n):
                t0 = time.perf_counter()
                s.ui.controls["motion.lift_mm"].value = 15.0 + (i % 2) * 0.5  # a slider step
                t.append(time.perf_counter() - t0)
            rows.append(
                _row(
                    f"slider change -> re-analysis + redraw, {kind}",
                    t,
                    "server side: analyze + cam mesh + follower + overlays + "
                    "6 plots + panels, queued to the client",
                )
            )
        s.ui.controls["follower.kind"].value = "double_concave"
        time.sleep(1.0)
        t = []
        for i in range(n):
            t0 = time.perf_counter()
            s.ui.controls["cam.speed_rpm"].value = 1200.0 + (i % 2) * 10  # geometry unchanged
            t.append(time.perf_counter() - t0)
        rows.append(
            _row(
                "speed change -> re-analysis + redraw (geometry kept)",
                t,
                "analyze + plots + panels; cam and follower nodes not re-sent",
            )
        )
        t = []
        for i in range(1, 10 * n):
            t0 = time.perf_counter()
            s.frame(1 / 30, i if i % 3 and i % 15 else i + 1)  # transform-only frames
            t.append(time.perf_counter() - t0)
        rows.append(_row("animation frame (transforms + overlay lines)", t, "one of 30 per second"))
        t = []
        for _ in range(n):
            t0 = time.perf_counter()
            s.frame(1 / 30, 0)  # + slider, label and the 6 plot markers (2 Hz in the loop)
            t.append(time.perf_counter() - t0)
        rows.append(_row("animation frame with plot markers", t, "2 of 30 frames per second"))
        # the real loop: frames delivered per second while playing, GUI still responsive
        s.speed = 90.0
        th0, f0 = s.theta_deg, s.ticker.ticks
        s.toggle_play()
        t0 = time.perf_counter()
        gui = []
        for i in range(10):  # slider changes while the animation runs
            time.sleep(0.25)
            a = time.perf_counter()
            s.ui.controls["motion.lift_mm"].value = 15.0 + (i % 2) * 0.5
            gui.append(time.perf_counter() - a)
        dt = time.perf_counter() - t0
        s.toggle_play()
        fps = (s.ticker.ticks - f0) / dt
        rows.append(
            _row(
                "slider change while animating",
                gui,
                f"loop drew {fps:.1f} frames/s over {dt:.1f} s "
                f"(cam advanced {(s.theta_deg - th0) % 360:.0f} deg at 90 deg/s)",
            )
        )
        tab.close()
    finally:
        app.stop()
    return rows


if __name__ == "__main__":
    for r in run():
        print(
            f"{r['name']:<58} median {r['median_ms']:7.2f} ms  p90 {r['p90_ms']:7.2f} ms  "
            f"n={r['n']:<4} {r['note']}"
        )
