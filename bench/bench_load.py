"""Load figures of the real app server (subprocess on 127.0.0.1, simulated tabs).

Rows: GUI round trip of one tab (lift change -> redrawn displacement curve back),
the same under k tabs dragging at once, redraws/s sustained, time for a new tab to be
drawn while others work, RSS growth per 100 sessions opened and closed, idle CPU.
The clients are tests/viser_client.py (viser's websocket protocol).
"""

from __future__ import annotations

import asyncio
import sys
import time
from pathlib import Path

from rows import row as _row

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from load_harness import (  # noqa: E402
    ServerProcess,
    connect_disconnect,
    idle_cpu_percent,
    round_trips,
    run_load,
)


def _value(name: str, value: float, n: int, note: str) -> dict:
    """A single figure (not a time): in the median column, the unit in the note."""
    return {"name": name, "median_ms": value, "p10_ms": None, "p90_ms": None, "n": n, "note": note}


def run(quick: bool = True, slow: bool = False) -> list[dict]:
    n_rt = 15 if quick else 40
    clients = 4 if quick else 6
    duration = 4.0 if quick else (60.0 if slow else 15.0)
    rate = 10.0
    sessions = 40 if quick else (300 if slow else 100)
    idle_s = 3.0 if quick else 10.0
    srv = ServerProcess().start()
    rows: list[dict] = []
    try:
        rt = asyncio.run(round_trips(srv.url, n_rt))
        rows.append(
            _row(
                "GUI round trip, 1 tab",
                (x * 1e3 for x in rt),
                "lift change -> redrawn S curve received",
            )
        )

        load = asyncio.run(run_load(srv.url, clients, duration, rate))
        s = load.summary()
        bad = f"; {s['foreign']} FOREIGN REDRAWS" if s["foreign"] else ""
        rows.append(
            _row(
                f"GUI round trip, {clients} tabs x {rate:g}/s",
                load.latencies_ms,
                f"{duration:g} s; {s['sent_per_s']:.0f} changes/s sent, "
                f"{s['redraws_per_s']:.0f} redraws/s seen{bad}",
            )
        )
        rows.append(
            _value(
                f"redraws/s sustained, {clients} tabs",
                s["redraws_per_s"],
                s["redraws_seen"],
                "per second (not ms); newest value wins, the app drops superseded changes",
            )
        )
        rows.append(
            _row(
                "new tab drawn while others drag",
                (p * 1e3 for p in load.probe_s),
                "connect -> lift control and S curve on screen",
            )
        )

        asyncio.run(connect_disconnect(srv.url, 20))  # warm-up
        time.sleep(2.0)
        rss0 = srv.rss_mb()
        res = asyncio.run(connect_disconnect(srv.url, sessions))
        time.sleep(3.0)
        rss1 = srv.rss_mb()
        per100 = (rss1 - rss0) * 100.0 / max(1, res["sessions"])
        rows.append(
            _value(
                "RSS growth per 100 sessions",
                per100,
                res["sessions"],
                f"MB (not ms); RSS {rss0:.0f} -> {rss1:.0f} MB over "
                f"{res['sessions']} open/close ({res['aborted']} aborted)",
            )
        )
        rows.append(
            _row(
                "tab open (connect -> drawn), idle server",
                [res["open_median_s"] * 1e3],
                "median of the polite sessions",
            )
        )
        time.sleep(1.0)
        cpu = idle_cpu_percent(srv, idle_s)
        rows.append(
            _value("idle CPU, no clients", cpu, 1, f"% of one core (not ms) over {idle_s:g} s")
        )
    finally:
        srv.stop()
        srv.cleanup()
    return rows


if __name__ == "__main__":
    for r in run(quick="--full" not in sys.argv, slow="--slow" in sys.argv):
        print(r)
