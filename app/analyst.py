"""The physics of every tab, computed off the server's interpreter.

The server is one Python process; its GUI work (scene, curves, websocket) holds the
GIL. The analyses run in worker processes so that a 2-core machine uses both cores:

- the *foreground* worker answers a tab's edit: the fast analysis, its summary and
  its curves (~10 ms, shipped back pickled, ~1 MB);
- the *background* worker, on CPU time nobody else wants, refines a tab that has
  gone still: the verified analysis and the four-follower comparison (~0.5 s).

``Analyst(processes=False)`` computes in the calling thread (tests of the pure
session logic, the bench's floor). A worker that dies is replaced on the next call.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from concurrent.futures import CancelledError, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

import numpy as np

from camcore import explore, sweep, toolpath
from camcore.analysis import Analysis, analyze, compare
from camcore.model import PAPER_FOLLOWERS, Design
from camcore.report import summary
from camcore.units import to_mpa

from .plots import CurveData, curve_data, stride_index

WORKERS = {"fg": 1, "bg": 1, "doc": 1}  # processes per pool (a second foreground one did not help
# the class benchmark on 2 cores, and each worker holds ~130 MB)


@dataclass(frozen=True)
class Result:
    """An analysis, its report summary (camcore.report.summary) and what the Curves tab
    shows of it (app.plots.curve_data), all computed in the worker."""

    analysis: Analysis
    summary: dict
    curves: CurveData


@dataclass(frozen=True)
class Refined(Result):
    """The verified analysis, plus the four followers compared on the same design:
    {kind: {"summary": dict, "theta_deg", "FN_N", "stress_MPa": arrays} | error str},
    and why the design's cutter cannot cut it (camcore.toolpath.GougeError), or None."""

    compare: dict[Any, Any]
    cutter: str | None = None


def fast(design: Design) -> Result:
    """What a tab needs after an edit (runs in a worker)."""
    a = analyze(design, verify=False)
    return Result(a, summary(a), curve_data(a))


def refined(design: Design) -> Refined:
    """What a still tab gets next (runs in the background worker)."""
    a = analyze(design, verify=True)
    out: dict[Any, Any] = {}
    for kind, r in compare(design, kinds=PAPER_FOLLOWERS, errors=True).items():
        if isinstance(r, str):
            out[kind] = r
            continue
        idx = stride_index(r.theta.size)  # as the other curves
        out[kind] = {
            "summary": summary(r),
            "theta_deg": np.degrees(r.theta[idx]),
            "FN_N": r.guide.FN[idx],
            "stress_MPa": to_mpa(r.stress.max(axis=0))[idx],
        }
    return Refined(a, summary(a), curve_data(a), out, _cutter_gouges(a))


def _cutter_gouges(a: Analysis) -> str | None:
    """The G-code download's refusal of the design's cutter, pass depth or file size, said before
    the download (~10-20 ms: the geometric gouge test of camcore.toolpath); None if
    they fit or the profile has no part at all (the panel's 'No solid' says that)."""
    try:
        toolpath.check_passes(a.design.cam)  # a rule of the export: said before it too
    except toolpath.ExportError as exc:
        return str(exc)
    try:
        path, _ = toolpath.cutter_path(a)
    except toolpath.GougeError as exc:
        return str(exc)
    except Exception:  # noqa: BLE001  (not a part: said elsewhere, not by the cutter)
        return None
    try:
        toolpath.check_size(a.design.cam, path.shape[0] + 2)  # the file's moves, as gcode
    except toolpath.ExportError as exc:
        return str(exc)
    return None


def _export(kind: str, a: Analysis) -> bytes:
    from camcore.export import EXPORTS

    return EXPORTS[kind].write(a)


def _warm(role: str) -> int:
    """Worker start: the background worker ("bg") only gets CPU time no one else wants
    (SCHED_IDLE where Linux has it, else the lowest nice), so a class's refinements
    never slow down its edits; the documents' worker ("doc") runs at nice DOC_NICE,
    behind the edits but never starved (at SCHED_IDLE a review's PDF had not come in
    30 s while two other processes kept the cores busy). Then warm the imports."""
    if role == "bg":
        try:
            os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
        except (AttributeError, OSError):
            os.nice(19)
    elif role == "doc":
        try:
            os.nice(DOC_NICE)
        except (AttributeError, OSError):  # (no nice: run at the normal priority)
            pass
    fast(Design())
    return os.getpid()


DOC_NICE = 10  # ~1/10 of a core's share beside a normal process that wants it all


class Analyst:
    """Single-process pools: foreground and background (started with the server) and
    the documents' (started at the first report or diagram asked for), or none
    (``processes=False``)."""

    def __init__(self, processes: bool = True):
        self.processes = processes
        self.closed = False  # after close(): compute in the caller (a tab shutting down)
        self._lock = threading.Lock()
        self._pools: dict[str, ProcessPoolExecutor | None] = dict.fromkeys(WORKERS)
        if processes:
            for name in ("fg", "bg"):
                self._pool(name)  # start now: the first tab should not wait for it

    def _pool(self, name: str) -> ProcessPoolExecutor | None:
        """The pool, started if need be; None once the analyst is closed."""
        with self._lock:
            pool = self._pools[name]
            if pool is None and not self.closed:
                ctx = multiprocessing.get_context("spawn")  # never fork a threaded server
                pool = ProcessPoolExecutor(WORKERS[name], mp_context=ctx)
                pool.submit(_warm, name)
                self._pools[name] = pool
            return pool

    def _run(self, name: str, fn, *args):
        if not self.processes or self.closed:  # closed: never start a worker again
            return fn(*args)
        for _ in range(2):
            pool = self._pool(name)
            if pool is None:
                break
            try:
                return pool.submit(fn, *args).result()
            except BrokenProcessPool:  # the worker died (killed, out of memory): a new one
                with self._lock:
                    if self._pools[name] is pool:
                        self._pools[name] = None
            except (RuntimeError, CancelledError):  # shut down meanwhile (the server stops)
                break
        return fn(*args)  # twice broken, or closed: compute here rather than fail the tab

    def fast(self, design: Design) -> Result:
        return self._run("fg", fast, design)

    def refined(self, design: Design) -> Refined:
        return self._run("bg", refined, design)

    def sweep_chunk(self, base: dict, points: list[dict], batched: bool = False) -> list[dict]:
        """Sweep rows of a batch of grid points: one fast analysis each
        (camcore.sweep.row), or ``batched`` the batched core (camcore.batch)."""
        return self._run("bg", sweep.run_chunk, base, points, False, batched)

    def same_designs(self, base: dict, points: list[dict]) -> list[int]:
        """camcore.sweep.same_designs (validates every point), in the background worker."""
        return self._run("bg", sweep.same_designs, base, points)

    def document(self, kind: str, a: Analysis) -> bytes:
        """camcore.export's ``kind`` file of ``a`` (the reports: ~1 s of matplotlib),
        made in the documents' worker, not in the server's interpreter."""
        return self._run("doc", _export, kind, a)

    def stations_image(self, a: Analysis) -> np.ndarray:
        """camcore.document.stations_image of ``a``, drawn in the documents' worker."""
        from camcore.document import stations_image

        return self._run("doc", stations_image, a)

    def explore_png(
        self, rows, x, y, names, front, limits=None, shown_px: int = explore.PANEL_PX
    ) -> bytes:
        """camcore.explore.explore_png for a panel ``shown_px`` wide, drawn in the
        background worker."""
        return self._run("bg", explore.explore_png, rows, x, y, names, front, shown_px, limits)

    def close(self) -> None:
        with self._lock:
            self.closed = True
            pools, self._pools = list(self._pools.values()), dict.fromkeys(WORKERS)
        for pool in pools:
            if pool is not None:
                pool.shutdown(wait=True, cancel_futures=True)
