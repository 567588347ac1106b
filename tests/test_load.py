"""Many users, long sessions: the real app server under simulated browser tabs.

The server runs in a subprocess (``python -m app.main --port 0``, 127.0.0.1); the tabs
are ``tests/viser_client.py`` clients speaking viser's websocket protocol (viser is
pinned in pyproject.toml because of it). Each tab drags the lift slider through
values only it uses, so the displacement curve it gets back (max S = lift) tells
whose design it shows.

Fast versions run in CI; ``pytest -m slow tests/test_load.py -s`` runs the minute
long load and the connect/disconnect memory loop and prints their figures.
"""

from __future__ import annotations

import asyncio
import json
import math
import time
from pathlib import Path

import msgspec.msgpack
import pytest
import viser._messages as vm
from load_harness import (
    ServerProcess,
    Tab,
    connect_disconnect,
    idle_cpu_percent,
    lift_shown,
    open_tab,
    own_values,
    run_load,
)
from viser_client import ViserClient


@pytest.fixture(scope="module")
def server():
    srv = ServerProcess().start()
    try:
        yield srv
    finally:
        srv.stop()
        alive_log = srv.log()
        srv.cleanup()
        print("\n--- server log (tail) ---\n" + alive_log[-2000:])


def run(coro, timeout: float = 120.0):
    return asyncio.run(asyncio.wait_for(coro, timeout))


def check_load(result, min_redraws: int = 3) -> None:
    s = result.summary()
    print("\nload:", json.dumps(s, default=float))
    assert not result.errors, result.errors
    for t in result.tabs:
        assert not t.foreign, f"{t.name} was shown other designs' lifts {t.foreign[:5]}"
        assert t.sent > 0 and t.shown >= min_redraws, (t.name, t.sent, t.shown)
        assert t.final_shown == t.last_sent, (t.name, t.final_shown, t.last_sent)
        assert t.final_slider == t.last_sent, (t.name, t.final_slider, t.last_sent)
    # GUI trees are per tab: no element uuid is shared between two tabs
    seen: set[str] = set()
    for t in result.tabs:
        assert not (t.gui_uuids & seen), f"{t.name} shares GUI elements with another tab"
        seen |= t.gui_uuids


def test_tabs_see_only_their_own_design(server):
    """5 tabs x 10 lift changes/s for 4 s: every redraw a tab gets is its own design,
    the last value sent is what each ends on, and a new tab opens meanwhile."""
    result = run(run_load(server.url, n_clients=5, duration=4.0, rate_hz=10.0))
    check_load(result)
    assert len(result.probe_s) == 2 and max(result.probe_s) < 20.0, result.probe_s
    assert server.alive()


def test_exploring_tabs_beside_editing_ones(server):
    """Issue 12's split of work: two tabs run Explore sweeps back to back (the
    background worker) while three drag their lifts at 5 changes/s: the editors still
    see only their own designs and end on their last values, and every sweep ends with
    its whole grid (the default setup: 8 x 8 points x the four followers)."""
    result = run(run_load(server.url, n_clients=3, duration=4.0, rate_hz=5.0, explorers=2))
    check_load(result)
    assert len(result.sweeps_per_explorer) == 2, result.summary()
    assert min(result.sweeps_per_explorer) >= 1, result.summary()  # each finished one
    assert set(result.sweep_designs) == {8 * 8 * 4}, result.sweep_designs
    assert server.alive()


async def _assert_serving(url: str, lift: float) -> None:
    """A fresh tab opens, and its lift change comes back redrawn."""
    c = await open_tab(url, "fresh", timeout=30.0)
    try:
        tab = Tab(c, own_values(7))
        await c.set_value(tab.lift, lift)
        await c.wait_for(lambda: lift_shown(tab.plot) == lift, 20.0, what=f"lift {lift}")
    finally:
        await c.close()


BAD_FRAMES = {
    "garbage bytes": b"\x00\xff\xfe not msgpack \xc1\xc1",
    "text frame": "hello",
    "unknown type": msgspec.msgpack.encode({"type": "NoSuchMessage", "x": 1}),
    "not a dict": msgspec.msgpack.encode([1, 2, 3]),
    "missing fields": msgspec.msgpack.encode({"type": "GuiUpdateMessage"}),
    "truncated msgpack": msgspec.msgpack.encode(
        {"type": "GuiUpdateMessage", "uuid": "x", "updates": {"value": 1.0}}
    )[:-3],
    "2 MB of zeros": b"\x00" * (2 << 20),
}


def test_bad_websocket_messages(server):
    """Undecodable frames close only the sender's connection (code 1011, logged);
    bad updates inside a session are logged and ignored; other tabs never notice."""

    async def go():
        good = await open_tab(server.url, "bystander")
        gtab = Tab(good, own_values(0))
        lifts = iter(own_values(0)[1:])

        async def bystander_ok() -> None:
            v = next(lifts)
            await good.set_value(gtab.lift, v)
            await good.wait_for(lambda: lift_shown(gtab.plot) == v, 20.0, what=f"lift {v}")

        for name, frame in BAD_FRAMES.items():
            n0 = len(server.log())
            c = await ViserClient(server.url, name).connect()
            await c.wait_for(lambda c=c: c.gui, 20.0, what="first GUI element")
            await c.send_raw(frame)
            with pytest.raises(ConnectionError, match="1011"):
                await c.wait_for(lambda: False, 10.0, what="the server to drop us")
            await c.close()
            await bystander_ok()
            deadline = time.monotonic() + 5
            while (
                "connection handler failed" not in server.log()[n0:] and time.monotonic() < deadline
            ):
                await asyncio.sleep(0.1)
            assert "connection handler failed" in server.log()[n0:], f"{name}: not logged"

        # well-formed messages with bad content, inside a live session
        c = await open_tab(server.url, "hostile")
        tab = Tab(c, own_values(1))
        uuid = tab.lift.uuid
        bad_updates = [
            ("unknown uuid", vm.GuiUpdateMessage("no-such-uuid", {"value": 3.0})),
            ("string value", vm.GuiUpdateMessage(uuid, {"value": "abc"})),
            ("list value", vm.GuiUpdateMessage(uuid, {"value": [1, 2]})),
            ("null value", vm.GuiUpdateMessage(uuid, {"value": None})),
            ("dict value", vm.GuiUpdateMessage(uuid, {"value": {"a": 1}})),
            ("NaN", vm.GuiUpdateMessage(uuid, {"value": math.nan})),
            ("inf", vm.GuiUpdateMessage(uuid, {"value": math.inf})),
            ("negative", vm.GuiUpdateMessage(uuid, {"value": -5.0})),
            ("huge", vm.GuiUpdateMessage(uuid, {"value": 1e300})),
            ("unknown prop", vm.GuiUpdateMessage(uuid, {"no_such_prop": 1})),
            (
                "station 99",
                vm.GuiUpdateMessage(c.find(label="Go to station").uuid, {"value": "99"}),
            ),
            (
                "unknown kind",
                vm.GuiUpdateMessage(c.find(label="Kind").uuid, {"value": "no_such_kind"}),
            ),
            ("button without value", vm.GuiUpdateMessage(c.find(label="▶ Play").uuid, {})),
            ("scene update, unknown node", vm.SceneNodeUpdateMessage("/nope", {"x": 1})),
        ]
        for i, (name, msg) in enumerate(bad_updates):
            await c.send(msg)
            if name == "unknown kind":  # invalid until fixed, as it should be: fix it
                await asyncio.sleep(0.2)
                await c.set_value("Kind", "double_concave")
            v = tab.own[i % len(tab.own)]
            if v == lift_shown(tab.plot):
                v = tab.own[(i + 1) % len(tab.own)]
            await c.set_value(tab.lift, v)  # the same tab still works afterwards
            await c.wait_for(
                lambda v=v: lift_shown(tab.plot) == v, 20.0, what=f"lift {v} after {name}"
            )
            assert lift_shown(gtab.plot) != v
        assert not c.errors and not good.errors
        await c.close()
        await bystander_ok()
        await good.close()
        await _assert_serving(server.url, own_values(7)[3])

    run(go())
    assert server.alive()


def test_oversized_values_and_messages_are_refused(server):
    """A security review: viser took messages of up to 50 MB and kept any value sent for
    a widget (twenty 40 MB strings and two vectors of 5 million numbers took the server
    from 163 MB to 1.4 GB). A frame over app.inbound.MAX_MESSAGE_BYTES closes the
    sender's connection (1009); a string longer than a widget's, or a vector longer
    than its own, is dropped before viser keeps it; other tabs never notice."""
    from app.inbound import MAX_MESSAGE_BYTES, MAX_VALUE_CHARS

    async def go():
        good = await open_tab(server.url, "bystander")
        gtab = Tab(good, own_values(2))
        c = await open_tab(server.url, "hostile")
        texts = [e for e in c.gui.values() if e.type in ("TextInput", "Dropdown")]
        vectors = [e for e in c.gui.values() if e.type == "Vector2"]
        assert texts and vectors
        rss = server.rss_mb()
        for i, el in enumerate(texts * 2):
            await c.send(vm.GuiUpdateMessage(el.uuid, {"value": chr(65 + i % 26) * (4 << 20)}))
        for el in vectors:
            await c.send(vm.GuiUpdateMessage(el.uuid, {"value": [1.0] * 500_000}))
        tab = Tab(c, own_values(3))
        await c.set_value(tab.lift, tab.own[1])  # the hostile tab itself still works
        await c.wait_for(lambda: lift_shown(tab.plot) == tab.own[1], 30.0, what="lift")
        assert server.rss_mb() - rss < 60, (rss, server.rss_mb())  # (4 MB each: none kept)
        await c.send_raw(b"\x00" * (MAX_MESSAGE_BYTES + 1))
        with pytest.raises(ConnectionError, match="1009"):
            await c.wait_for(lambda: False, 10.0, what="the server to drop us")
        c.abort()  # (a close handshake on the dropped socket can fail in asyncio)
        await good.set_value(gtab.lift, gtab.own[1])
        await good.wait_for(lambda: lift_shown(gtab.plot) == gtab.own[1], 20.0, what="lift")
        await good.close()

    assert MAX_VALUE_CHARS < 4 << 20
    run(go())
    assert server.alive()


def test_vanishing_clients(server):
    """Tabs that drop their TCP connection mid-update or mid-build: the server frees
    their sessions (no leaked threads) and keeps serving."""

    async def vanish_round(k: int) -> None:
        for i in range(4):  # killed while the server builds the tab
            c = await ViserClient(server.url, f"kill{k}.{i}").connect()
            await asyncio.sleep(0.02 * i)
            c.abort()
            await c.close()
        for i in range(3):  # killed with updates in flight
            c = await open_tab(server.url, f"burst{k}.{i}")
            lift = c.find(label="Lift h [mm]")
            for v in own_values(2) * 3:
                await c.set_value(lift, v)
            c.abort()
            await c.close()

    async def fill_pool() -> None:
        """Grow viser's thread pool first: 8 tabs' bursts at once, two lanes each
        (app.inbound.TabLanes), more than a round of vanishing tabs uses. (A round alone
        no longer fills it, and the pool's later growth had read as leaked sessions.)"""
        tabs = await asyncio.gather(*[open_tab(server.url, f"fill{i}") for i in range(8)])

        async def burst(c) -> None:
            lift = c.find(label="Lift h [mm]")
            for v in own_values(3) * 4:
                await c.set_value(lift, v)

        await asyncio.gather(*[burst(c) for c in tabs])
        await asyncio.sleep(2.0)
        for c in tabs:
            await c.close()

    async def go():
        await fill_pool()
        await vanish_round(0)
        await _assert_serving(server.url, own_values(7)[1])
        return server.threads()

    def settled_threads(limit: int, wait: float = 15.0) -> int:
        deadline = time.monotonic() + wait
        n = server.threads()
        while n > limit and time.monotonic() < deadline:
            time.sleep(0.25)
            n = server.threads()
        return n

    run(go())
    before = settled_threads(0, wait=3.0)  # (fill_pool and round 0: the pool is full)
    run(vanish_round(1))
    run(_assert_serving(server.url, own_values(7)[2]))
    after = settled_threads(before + 1)
    print(f"\nserver threads after vanishing tabs: {before} -> {after}")
    # a leaked session keeps 2 threads (animation, settle) forever
    assert after <= before + 1, f"threads {before} -> {after}: sessions leaked"
    assert server.alive()


# --- slow: by hand, ``pytest -m slow tests/test_load.py -s`` ---------------------------


@pytest.mark.slow
def test_slow_minute_of_load(server):
    result = run(run_load(server.url, n_clients=8, duration=60.0, rate_hz=8.0), 300)
    check_load(result, min_redraws=20)
    assert max(result.probe_s) < 30.0, result.probe_s


@pytest.mark.slow
def test_slow_memory_and_idle_cpu(server):
    """A few hundred sessions opened and closed: RSS after ~ RSS before; idle CPU ~ 0."""
    run(connect_disconnect(server.url, 40), 300)  # warm-up: caches, thread pool, arenas
    time.sleep(2.0)
    rss0, thr0 = server.rss_mb(), server.threads()
    t0 = time.perf_counter()
    res = run(connect_disconnect(server.url, 300, time_limit=400.0), 600)
    loop_s = time.perf_counter() - t0
    time.sleep(3.0)
    rss1, thr1 = server.rss_mb(), server.threads()
    time.sleep(2.0)
    cpu = idle_cpu_percent(server, 10.0)
    figures = {
        "sessions": res["sessions"],
        "aborted": res["aborted"],
        "loop_s": round(loop_s, 1),
        "open_median_s": round(res["open_median_s"], 3),
        "rss_before_mb": round(rss0, 1),
        "rss_after_mb": round(rss1, 1),
        "rss_growth_mb": round(rss1 - rss0, 1),
        "threads": (thr0, thr1),
        "idle_cpu_percent": round(cpu, 2),
    }
    print("\nmemory/idle:", json.dumps(figures))
    assert res["sessions"] >= 200
    assert rss1 - rss0 < 30.0, figures
    assert thr1 <= thr0 + 2, figures
    assert cpu < 2.0, figures


@pytest.mark.slow
def test_slow_class_of_thirty_tabs(server):
    """Issue 12, a class on one server: 30 tabs each change the lift once a second for
    30 s. Every tab sees only its own design and ends on its last value; a new tab is
    drawn meanwhile. The latency, new-tab and memory figures are printed (their goals
    are measured by bench/bench_class.py and reported in the README, not asserted)."""
    rss0 = server.rss_mb()
    result = run(run_load(server.url, n_clients=30, duration=30.0, rate_hz=1.0), 300)
    check_load(result, min_redraws=10)
    time.sleep(5.0)
    s = result.summary()
    print(
        "\nclass:",
        json.dumps(
            {
                "latency_ms": s["latency_ms"],
                "new_tab_s": s["probe_s"],
                "rss_mb": [round(rss0, 1), round(server.rss_mb(), 1)],
            }
        ),
    )
    assert max(result.probe_s) < 30.0, result.probe_s


def test_the_server_runs_without_glibcs_thread_cache_and_its_workers_with_it(server):
    """app.main restarts itself once with GLIBC_TUNABLES' tcache off (viser's idle
    callback threads had pinned ~13 MB after a class left); the analysis workers it
    spawns keep glibc's default."""
    from app.main import NO_TCACHE

    def environ(pid: int) -> list[str]:
        return Path(f"/proc/{pid}/environ").read_bytes().decode().split("\0")

    tunables = [e for e in environ(server.pid) if e.startswith("GLIBC_TUNABLES=")]
    assert tunables and NO_TCACHE in tunables[0].split("=", 1)[1].split(":")
    run(connect_disconnect(server.url, 1), 60)  # (a tab: the workers have analysed)
    children = Path(f"/proc/{server.pid}/task/{server.pid}/children").read_text().split()
    assert children
    for pid in map(int, children):
        assert not any(NO_TCACHE in e for e in environ(pid)), pid
