"""Entry point: ``camdesigner [--host 127.0.0.1] [--port 8080]``.

Starts a viser server; every browser tab gets its own Session (design, analysis,
animation), created on connect and freed on disconnect.
"""

from __future__ import annotations

import argparse
import ctypes
import ctypes.util
import gc
import os
import signal
import sys
import threading
import time
import warnings

import viser

from camcore import batch

from . import inbound, uploads, viser_speedups
from .analyst import Analyst
from .session import Session

# A tab that closes while its redraw is in flight makes viser warn once per queued
# message; that is expected (the session is being torn down), not worth a log line.
warnings.filterwarnings("ignore", message=r"Queued a \w+ on a closed connection")
IDLE_TRIM_S = 2.0  # after the last tab leaves
# tabs served at once: a class of thirty twice over (each tab holds ~3.5 MB and a few
# threads; beyond this a tab is told the server is full)
MAX_TABS = 60


def _load_malloc_trim():
    try:
        return ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim
    except (OSError, AttributeError):  # not glibc
        return None


_MALLOC_TRIM = _load_malloc_trim()

M_MMAP_THRESHOLD, M_ARENA_MAX = -3, -8  # glibc mallopt parameters (malloc.h)


def _tune_malloc() -> None:
    """Keep numpy's large temporaries out of the heap. glibc raises its mmap threshold
    each time a large block is freed (up to 32 MB), after which the analysis' arrays
    (tens to hundreds of kB each) land in the per-thread heaps and fragment them: 30
    busy tabs left the server at 3-6x its idle RSS after they closed. A fixed 128 kB
    threshold maps every larger array on its own (returned to the OS when freed), and
    4 arenas instead of 8 per core bound the per-thread heaps. No effect off glibc."""
    try:
        mallopt = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").mallopt
    except (OSError, AttributeError):
        return
    mallopt(M_MMAP_THRESHOLD, 128 * 1024)
    mallopt(M_ARENA_MAX, 4)


def _trim_heap() -> None:
    """Give the memory a closed tab freed back to the OS. glibc keeps freed blocks in
    per-thread arenas (viser's callbacks run on a 32-thread pool), so without this the
    server's RSS crept up by ~0.3 MB per tab opened and closed, forever. The collect
    first frees the tab's reference cycles (GUI callbacks that close over the Session)."""
    if _MALLOC_TRIM is not None:
        gc.collect()
        _MALLOC_TRIM(0)


class App:
    """The server and the live sessions, by client id. ``processes`` runs the physics in
    spawned worker processes (app.analyst): a script that creates an App must do so
    under ``if __name__ == "__main__":``, the multiprocessing rule."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 8080,
        verbose: bool = False,
        animate: bool = True,
        processes: bool = True,
        max_tabs: int = MAX_TABS,
    ):
        _tune_malloc()  # before the server's threads create their arenas
        batch.KEEP_FREED = False  # (a sweep run here, without a worker, must not undo it)
        viser_speedups.install()
        uploads.install(uploads.MAX_UPLOAD_BYTES, self._upload_refused)  # before the server
        inbound.install()  # (and the messages' and values' sizes)
        self.server = viser.ViserServer(
            host=host, port=port, label="Disk-cam designer", verbose=verbose
        )
        inbound.lane_tabs(self.server)  # (each tab's callbacks in lanes of their own)
        self.server.gui.configure_theme(
            control_width="large", show_share_button=False, brand_color=(40, 90, 160)
        )
        self.server.scene.set_up_direction("+y")  # the follower moves along +Y
        self.sessions: dict[int, Session] = {}
        self._gone: set[int] = set()  # left while their Session was still being built
        self._refused: set[int] = set()  # open tabs turned away: the server was full
        self._building = 0  # Sessions being built
        self.max_tabs = max_tabs
        self._lock = threading.Lock()
        self.animate = animate
        self.analyst = Analyst(processes)  # the physics, in worker processes (app.analyst)
        self.server.on_client_connect(self._connect)
        self.server.on_client_disconnect(self._disconnect)

    @property
    def port(self) -> int:
        return self.server.get_port()

    def _connect(self, client) -> None:
        # viser runs connect and disconnect callbacks on its thread pool: a tab closed
        # while its Session is built gets its disconnect first; close that Session.
        with self._lock:
            full = len(self.sessions) + self._building >= self.max_tabs
            if not full:
                self._building += 1
            elif client.client_id in self._gone:  # (it left already)
                self._gone.discard(client.client_id)
            else:
                self._refused.add(client.client_id)
        if full:
            return _turn_away(client, self.max_tabs)
        try:
            s = Session(client, animate=self.animate, analyst=self.analyst)
        except BaseException:
            with self._lock:
                self._gone.discard(client.client_id)
                self._building -= 1
            raise
        with self._lock:
            self._building -= 1
            gone = client.client_id in self._gone
            self._gone.discard(client.client_id)
            if not gone:
                self.sessions[client.client_id] = s
        if gone:
            s.close()
            del s
            _trim_heap()

    def _upload_refused(self, client_id: int, filename: str, size: int, why: str) -> None:
        with self._lock:
            s = self.sessions.get(client_id)
        if s is not None:
            s.upload_refused(filename, size, why)

    def _disconnect(self, client) -> None:
        with self._lock:
            if client.client_id in self._refused:
                self._refused.discard(client.client_id)
                return
            s = self.sessions.pop(client.client_id, None)
            if s is None:
                self._gone.add(client.client_id)
        if s is not None:
            s.close()
            del s
            _trim_heap()
            with self._lock:
                last = not self.sessions
            if last:  # the class has left: trim again once their in-flight work is gone
                t = threading.Timer(IDLE_TRIM_S, _trim_heap)
                t.daemon = True
                t.start()

    def stop(self) -> None:
        with self._lock:
            sessions, self.sessions = list(self.sessions.values()), {}
        for s in sessions:
            s.close()
        self.server.stop()
        self.analyst.close()


def _turn_away(client, max_tabs: int) -> None:
    """Say to a tab opened beyond the server's ``max_tabs`` that it is full (no Session
    is built: each costs ~3.5 MB and threads, and a security review's one client had
    opened 60, taking the server from 51 to 711 threads)."""
    try:
        client.gui.add_markdown(
            f"**This server is full:** it serves {max_tabs} tab{'s' * (max_tabs != 1)} "
            "at once (`camdesigner --max-tabs`). Close a tab you no longer use, or reload "
            "this page in a minute."
        )
    except Exception:  # (the tab left meanwhile)
        pass


def _port_free(host: str, port: int) -> bool:
    """Whether ``port`` can be bound on ``host`` now (viser would silently move on).
    With SO_REUSEADDR, as the server binds it: a closed connection of a server just
    stopped (TIME_WAIT, ~60 s) does not make the port busy; a listener does."""
    import socket

    try:
        with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET) as sock:
            if os.name != "nt":  # (on Windows it would let a bind share a live port)
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, port))
        return True
    except OSError:
        return False


NO_TCACHE = "glibc.malloc.tcache_count=0"  # a GLIBC_TUNABLES entry
REEXECED = "CAMDESIGNER_NO_TCACHE"  # set across the restart: the tunable is ours


def _reexec_without_tcache() -> None:
    """Restart this command once (same process, os.execv) with glibc's per-thread
    cache off: a tunable read only at process start. viser's 32 callback threads live
    on after a class leaves, each caching freed chunks that pin heap pages malloc_trim
    cannot return: ~13 MB of a 30-tab class (1.44x idle after it, 1.34x without;
    per-edit CPU unchanged). The workers spawned later get the default back. A user's
    own tcache setting is kept; and the restarted process never restarts again (glibc
    drops tunables for a privileged binary: a review's loop)."""
    if _MALLOC_TRIM is None or sys.platform != "linux":
        return
    given = os.environ.get("GLIBC_TUNABLES", "")
    tunables = [t for t in given.split(":") if t]
    if os.environ.pop(REEXECED, None) == "set":  # restarted: the tunable is not the workers'
        rest = [t for t in tunables if t != NO_TCACHE]
        if rest:
            os.environ["GLIBC_TUNABLES"] = ":".join(rest)
        else:
            os.environ.pop("GLIBC_TUNABLES", None)
        return
    if any(t.startswith("glibc.malloc.tcache_count=") for t in tunables):
        return  # (the user's own)
    os.environ["GLIBC_TUNABLES"] = ":".join([*tunables, NO_TCACHE])
    os.environ[REEXECED] = "set"
    sys.stdout.flush()
    try:
        os.execv(sys.executable, sys.orig_argv)
    except OSError:  # (no restart: the server runs as before, with the cache)
        os.environ.pop(REEXECED)
        if given:
            os.environ["GLIBC_TUNABLES"] = given
        else:
            os.environ.pop("GLIBC_TUNABLES")


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(prog="camdesigner", description=__doc__.splitlines()[0])
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to bind (default 127.0.0.1, this machine only); "
        "0.0.0.0 serves every network interface: see the README",
    )
    p.add_argument(
        "--port", type=int, default=8080, help="port (default 8080); a busy port is an error"
    )
    p.add_argument(
        "--max-tabs",
        type=int,
        default=MAX_TABS,
        help=f"tabs served at once (default {MAX_TABS}); a tab beyond it is told the "
        "server is full",
    )
    args = p.parse_args(argv)
    if not 1 <= args.max_tabs <= 1000:
        p.error("--max-tabs: 1 to 1000")
    if argv is None:  # (the command line's server, not a test's call)
        _reexec_without_tcache()
    if not _port_free(args.host, args.port):
        p.exit(
            2,
            f"camdesigner: error: port {args.port} on {args.host} is busy (another "
            "program, or camdesigner already running?); choose one with --port N\n",
        )
    # Ctrl-C and SIGTERM stop cleanly, even when started with SIGINT ignored (a
    # background job of a non-interactive shell inherits that).
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, _interrupt)
    app = App(args.host, args.port, max_tabs=args.max_tabs)
    if not args.host.startswith("127.") and args.host not in ("localhost", "::1"):
        print(
            f"warning: serving on {args.host}: anyone who can reach this address can use "
            "the app (no login, no TLS); every visitor gets their own session",
            flush=True,
        )
    host = "localhost" if args.host in ("127.0.0.1", "0.0.0.0") else args.host
    print(f"Disk-cam designer running at http://{host}:{app.port}  (Ctrl-C to stop)", flush=True)
    try:
        while True:
            time.sleep(1.0)
    except KeyboardInterrupt:
        print("\nstopping…", flush=True)
    finally:
        app.stop()


if __name__ == "__main__":
    main()
