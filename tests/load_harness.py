"""The real app server in a subprocess, its /proc figures, and the load scenarios.

Shared by ``tests/test_load.py`` and ``bench/bench_load.py``. Everything talks to
127.0.0.1 only; every loop is bounded in count and in time.
"""

from __future__ import annotations

import asyncio
import os
import random
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import viser._messages as vm
from viser_client import GuiElement, ViserClient

ROOT = Path(__file__).resolve().parents[1]
LIFT = "Lift h [mm]"
PLOT_S = "Displacement S"
EXPLORE_RUN = "Run the sweep"  # app.explore's button
EXPLORE_DONE = re.compile(r"^\*\*(\d+) points\*\*")  # its message when a sweep ends
READY_RE = re.compile(r"running at http://[^:\s]+:(\d+)")
CLK_TCK = os.sysconf("SC_CLK_TCK")


# --- the server process ------------------------------------------------------------


class ServerProcess:
    """``python -m app.main --port 0`` (or a stand-in command) with its log in a file."""

    def __init__(self, cmd: list[str] | None = None, ready_timeout: float = 60.0):
        self.cmd = cmd or [
            sys.executable,
            "-u",
            "-m",
            "app.main",
            "--host",
            "127.0.0.1",
            "--port",
            "0",
        ]
        self.ready_timeout = ready_timeout
        self.log_file = tempfile.NamedTemporaryFile(  # noqa: SIM115 (closed in stop)
            "w+", prefix="camdesigner-load-", suffix=".log", delete=False
        )
        self.proc: subprocess.Popen | None = None
        self.port: int | None = None

    def start(self) -> ServerProcess:
        env = dict(os.environ, PYTHONUNBUFFERED="1")
        self.proc = subprocess.Popen(
            self.cmd,
            cwd=ROOT,
            stdout=self.log_file,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env=env,
        )
        deadline = time.monotonic() + self.ready_timeout
        while time.monotonic() < deadline:
            m = READY_RE.search(self.log())
            if m:
                self.port = int(m.group(1))
                return self
            if self.proc.poll() is not None:
                raise RuntimeError(f"server exited with {self.proc.returncode}:\n{self.log()}")
            time.sleep(0.05)
        self.stop()
        raise TimeoutError(f"server not ready in {self.ready_timeout} s:\n{self.log()}")

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    @property
    def pid(self) -> int:
        assert self.proc is not None
        return self.proc.pid

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def log(self) -> str:
        try:
            return Path(self.log_file.name).read_text(errors="replace")
        except OSError:
            return ""

    def stop(self) -> None:
        p = self.proc
        if p is not None and p.poll() is None:
            p.send_signal(signal.SIGINT)  # the app's clean Ctrl-C path
            try:
                p.wait(timeout=5)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=5)
        self.log_file.close()

    def cleanup(self) -> None:
        try:
            os.unlink(self.log_file.name)
        except OSError:
            pass

    # /proc figures
    def status(self) -> dict[str, int]:
        out = {}
        for line in Path(f"/proc/{self.pid}/status").read_text().splitlines():
            k, _, v = line.partition(":")
            if k in ("VmRSS", "VmHWM", "Threads"):
                out[k] = int(v.split()[0])
        return out

    def rss_mb(self) -> float:
        return self.status()["VmRSS"] / 1024

    def threads(self) -> int:
        return self.status()["Threads"]

    def cpu_s(self) -> float:
        """utime + stime of the whole process [s]."""
        stat = Path(f"/proc/{self.pid}/stat").read_text()
        fields = stat[stat.rindex(")") + 2 :].split()
        return (int(fields[11]) + int(fields[12])) / CLK_TCK


def idle_cpu_percent(server: ServerProcess, seconds: float = 10.0) -> float:
    """CPU of the server over ``seconds`` of wall time, in % of one core."""
    c0, t0 = server.cpu_s(), time.monotonic()
    time.sleep(seconds)
    return 100.0 * (server.cpu_s() - c0) / (time.monotonic() - t0)


# --- one app tab ---------------------------------------------------------------------


def lift_shown(el: GuiElement) -> float | None:
    """The lift [mm] a Displacement plot shows: the maximum of its S series."""
    data = el.props.get("data")
    if not data or len(data) < 2:
        return None
    s = np.asarray(data[1], float)
    s = s[np.isfinite(s)]
    return round(float(s.max()) * 4) / 4 if s.size > 2 else None  # own values: 0.25 mm apart


async def open_tab(url: str, name: str = "tab", timeout: float = 30.0) -> ViserClient:
    """Connect and wait until the tab is fully drawn (lift control, S plot with data)."""
    c = await ViserClient(url, name).connect(timeout=timeout)
    try:
        await c.wait_for(
            lambda: (
                _plot(c) is not None and lift_shown(_plot(c)) is not None and c.find_all(label=LIFT)
            ),
            timeout,
            what="the design view",
        )
    except BaseException:
        await c.close()
        raise
    return c


def _plot(c: ViserClient) -> GuiElement | None:
    for el in c.gui.values():
        if el.type == "Uplot" and el.props.get("title") == PLOT_S:
            return el
    return None


REFINE_WAIT_S = 1.5  # a still tab is refined after app.session.SETTLE_S (0.6 s) + ~0.5 s


@dataclass
class TabStats:
    name: str
    own: set[float]
    sent: int = 0
    shown: int = 0  # displacement redraws with a new design seen
    plot_updates: int = 0  # displacement plot data messages received
    latencies: list[float] = field(default_factory=list)  # send -> redraw seen [s]
    foreign: list[float] = field(default_factory=list)  # lifts shown that are not ours
    last_sent: float | None = None
    final_shown: float | None = None
    final_slider: float | None = None
    gui_uuids: set[str] = field(default_factory=set)
    bytes_in: int = 0  # received from the first edit until the last was drawn


class Tab:
    """A simulated user dragging the lift slider through values only it uses."""

    def __init__(self, client: ViserClient, own: list[float]):
        self.c = client
        self.own = own
        self.stats = TabStats(client.name, set(own))
        self.plot = _plot(client)
        self.lift = client.find(label=LIFT)
        self.initial = lift_shown(self.plot)
        self.pending: dict[float, float] = {}  # lift -> send time (latest)
        self.seen_own = False
        self.last_shown = self.initial
        self.stats.gui_uuids = set(client.gui)
        client.add_listener(self._on_message)

    def _on_message(self, msg: vm.Message, t: float) -> None:
        if not isinstance(msg, vm.GuiUpdateMessage):
            return
        if msg.uuid == self.lift.uuid and "value" in msg.updates:
            v = float(msg.updates["value"])
            if v not in self.stats.own:  # the server set our slider to someone else's value
                self.stats.foreign.append(v)
        if msg.uuid != self.plot.uuid or "data" not in msg.updates:
            return
        self.stats.plot_updates += 1
        v = lift_shown(self.plot)
        if v is None:
            return
        if v in self.stats.own:
            self.seen_own = True
        elif not (v == self.initial and not self.seen_own):
            self.stats.foreign.append(v)
            return
        if v != self.last_shown:
            self.stats.shown += 1
        self.last_shown = v
        sent_t = self.pending.pop(v, None)
        if sent_t is not None:
            self.stats.latencies.append(t - sent_t)
            # anything sent before it was superseded (coalesced by the app)
            for k in [k for k, ts in self.pending.items() if ts < sent_t]:
                del self.pending[k]

    async def drag(
        self, duration: float, rate_hz: float, rng: random.Random, phase: float = 0.0
    ) -> None:
        """Send a new lift every 1 / rate_hz s for ``duration`` s, the first after
        ``phase`` periods (0: at once)."""
        period = 1.0 / rate_hz
        t_end = time.monotonic() + duration
        nxt = time.monotonic() + phase * period
        await asyncio.sleep(phase * period)
        prev = None
        n_max = int(duration * rate_hz) + 1
        for _ in range(n_max):
            if time.monotonic() >= t_end:
                break
            v = rng.choice([x for x in self.own if x != prev])
            prev = v
            self.pending[v] = time.perf_counter()
            await self.c.set_value(self.lift, v)
            self.stats.sent += 1
            self.stats.last_sent = v
            nxt += period
            await asyncio.sleep(max(0.0, nxt - time.monotonic()))

    async def settle(self, timeout: float = 20.0) -> None:
        """Wait until our last value is on screen (or time out), then record."""
        want = self.stats.last_sent
        if want is not None:
            try:
                await self.c.wait_for(
                    lambda: lift_shown(self.plot) == want, timeout, what=f"lift {want} on screen"
                )
            except TimeoutError:
                pass
        self.stats.final_shown = lift_shown(self.plot)
        self.stats.final_slider = self.c.gui[self.lift.uuid].value


class Explorer:
    """A student exploring: runs the Explore tab's sweep (its default setup: two fields
    x 8 steps x the four followers) again and again, each after the last has ended."""

    def __init__(self, client: ViserClient):
        self.c = client
        self.sweeps_s: list[float] = []  # click -> the sweep's closing message [s]
        self.designs: list[int] = []  # designs each sweep analysed
        self._ended: list[int] = []  # design counts of the closing messages seen
        client.add_listener(self._on_message)

    def _on_message(self, msg: vm.Message, t: float) -> None:
        if isinstance(msg, vm.GuiUpdateMessage) and msg.uuid in self.c.gui:
            done = EXPLORE_DONE.match(self.c.gui[msg.uuid].text)
            if done and ("content" in msg.updates or "_markdown" in msg.updates):
                self._ended.append(int(done.group(1)))

    async def explore(self, duration: float, timeout: float = 120.0) -> None:
        """Run sweeps for ``duration`` s (the last one started is waited for)."""
        t_end = time.monotonic() + duration
        run = await self.c.wait_gui(EXPLORE_RUN, timeout)  # (a tab is built in stages)
        while time.monotonic() < t_end:
            seen = len(self._ended)
            # the button is enabled again just after the closing message
            await self.c.wait_for(lambda: not run.props.get("disabled"), timeout, what="Run")
            t = time.perf_counter()
            await self.c.click(run)
            await self.c.wait_for(lambda n=seen: len(self._ended) > n, timeout, what="a sweep")
            self.sweeps_s.append(time.perf_counter() - t)
            self.designs.append(self._ended[-1])


def own_values(i: int, n: int = 12) -> list[float]:
    """Lifts [mm] only tab ``i`` uses: 20 + 3 i ... + 2.75, never the default 15. Up to
    30 tabs every value is a valid design of the paper example (its lift must stay
    below 169.7 mm, Eq. 3), so every change costs a whole analysis and redraw."""
    return [20.0 + 3.0 * i + 0.25 * k for k in range(n)]


@dataclass
class LoadResult:
    n_clients: int
    duration: float
    rate_hz: float
    tabs: list[TabStats]
    probe_s: list[float]  # time for a new tab to be fully drawn, during and after the load
    wall_s: float
    errors: list[str]
    sweeps_s: list[float] = field(default_factory=list)  # explorers' sweeps, click -> end
    sweep_designs: list[int] = field(default_factory=list)  # designs of each of them
    sweeps_per_explorer: list[int] = field(default_factory=list)

    @property
    def latencies_ms(self) -> list[float]:
        return [x * 1e3 for t in self.tabs for x in t.latencies]

    @property
    def sent(self) -> int:
        return sum(t.sent for t in self.tabs)

    @property
    def shown(self) -> int:
        return sum(t.shown for t in self.tabs)

    def summary(self) -> dict:
        lat = self.latencies_ms
        q = _quantiles(lat)
        return {
            "clients": self.n_clients,
            "duration_s": self.duration,
            "rate_hz": self.rate_hz,
            "sent": self.sent,
            "sent_per_s": self.sent / self.duration,
            "redraws_seen": self.shown,
            "redraws_per_s": self.shown / self.duration,
            "plot_updates_per_s": sum(t.plot_updates for t in self.tabs) / self.duration,
            "latency_ms": q,
            "n_latency": len(lat),
            # what a tab receives per edit it makes (the redraw, and the refinement and
            # comparison that follow once it is still), compressed as sent [kB]
            "kb_per_edit": sum(t.bytes_in for t in self.tabs) / max(1, self.sent) / 1e3,
            "probe_s": [round(p, 3) for p in self.probe_s],
            "foreign": sum(len(t.foreign) for t in self.tabs),
            "sweeps_s": [round(x, 2) for x in self.sweeps_s],
            "sweep_designs": self.sweep_designs,
            "errors": self.errors,
        }


def _quantiles(xs: list[float]) -> dict:
    if not xs:
        return {
            "median": float("nan"),
            "p10": float("nan"),
            "p90": float("nan"),
            "max": float("nan"),
        }
    a = np.asarray(xs)
    return {
        "median": float(np.median(a)),
        "p10": float(np.percentile(a, 10)),
        "p90": float(np.percentile(a, 90)),
        "max": float(a.max()),
    }


async def run_load(
    url: str,
    n_clients: int,
    duration: float,
    rate_hz: float,
    seed: int = 0,
    probe: bool = True,
    lockstep: bool = False,
    explorers: int = 0,
) -> LoadResult:
    """``n_clients`` tabs drag their own lift values at ``rate_hz`` for ``duration`` s.

    Each tab starts at its own random phase of the period, as a class's students do
    (``lockstep``: all at the same instant, so every second brings a burst of
    ``n_clients`` edits at once: the worst case). ``explorers`` more tabs run Explore
    sweeps meanwhile (Explorer); their sweep times are in the result."""
    t0 = time.perf_counter()
    rng = random.Random(seed)
    clients = await asyncio.gather(*(open_tab(url, f"tab{i}") for i in range(n_clients)))
    tabs = [Tab(c, own_values(i)) for i, c in enumerate(clients)]
    sweepers = [
        Explorer(c)
        for c in await asyncio.gather(*(open_tab(url, f"explorer{i}") for i in range(explorers)))
    ]
    errors: list[str] = []
    probes: list[float] = []

    async def probe_once() -> None:
        t = time.perf_counter()
        c = await open_tab(url, "probe", timeout=30.0)
        probes.append(time.perf_counter() - t)
        await c.close()

    async def probe_mid() -> None:
        await asyncio.sleep(duration / 2)
        await probe_once()

    start_bytes = [c.bytes_in for c in clients]
    try:
        jobs = [
            t.drag(
                duration, rate_hz, random.Random(rng.random()), 0.0 if lockstep else rng.random()
            )
            for t in tabs
        ]
        if probe:
            jobs.append(probe_mid())
        jobs += [e.explore(duration) for e in sweepers]
        await asyncio.gather(*jobs)
        await asyncio.gather(*(t.settle() for t in tabs))
        await asyncio.sleep(REFINE_WAIT_S)  # the last edit's refinement is sent too
        for t, c, b0 in zip(tabs, clients, start_bytes, strict=True):
            t.stats.bytes_in = c.bytes_in - b0
        if probe:
            await probe_once()
        for c in [*clients, *(e.c for e in sweepers)]:
            errors += [f"{c.name}: {e!r}" for e in c.errors]
            if c.closed_reason:
                errors.append(f"{c.name}: {c.closed_reason}")
    finally:
        await asyncio.gather(
            *(c.close() for c in [*clients, *(e.c for e in sweepers)]), return_exceptions=True
        )
    return LoadResult(
        n_clients,
        duration,
        rate_hz,
        [t.stats for t in tabs],
        probes,
        time.perf_counter() - t0,
        errors,
        [s for e in sweepers for s in e.sweeps_s],
        [n for e in sweepers for n in e.designs],
        [len(e.sweeps_s) for e in sweepers],
    )


async def round_trips(url: str, n: int = 30, seed: int = 1) -> list[float]:
    """One tab, one update at a time: send a lift, wait for the redrawn S plot [s]."""
    c = await open_tab(url, "rt")
    try:
        tab = Tab(c, own_values(0))
        rng = random.Random(seed)
        out = []
        prev = tab.initial
        for _ in range(n):
            v = rng.choice([x for x in tab.own if x != prev])
            prev = v
            t = time.perf_counter()
            await c.set_value(tab.lift, v)
            await c.wait_for(lambda v=v: lift_shown(tab.plot) == v, 20.0, what=f"lift {v}")
            out.append(time.perf_counter() - t)
        return out
    finally:
        await c.close()


async def connect_disconnect(
    url: str, sessions: int, polite_every: int = 2, time_limit: float = 300.0
) -> dict:
    """Open and close ``sessions`` tabs one after the other (bounded by ``time_limit``).

    Every ``polite_every``-th tab waits for the full view before closing; the others
    close as soon as the first GUI element arrives, and every fourth of those just
    drops the TCP connection (a tab killed mid-build)."""
    t_end = time.monotonic() + time_limit
    done, aborted, t_open = 0, 0, []
    for i in range(sessions):
        if time.monotonic() > t_end:
            break
        if i % polite_every == 0:
            t = time.perf_counter()
            c = await open_tab(url, f"s{i}")
            t_open.append(time.perf_counter() - t)
            await c.close()
        else:
            c = await ViserClient(url, f"s{i}").connect()
            try:
                await c.wait_for(lambda c=c: c.gui, 30.0, what="first GUI element")
            finally:
                if i % 4 == 1:
                    c.abort()
                    aborted += 1
                await c.close()
        done += 1
    return {
        "sessions": done,
        "aborted": aborted,
        "open_median_s": statistics.median(t_open) if t_open else float("nan"),
    }
