"""No lost work: each tab's design kept in its own browser (localStorage).

The working design is written on every change and read back when the tab opens, so a
reload or a server restart returns the user to what they had. Named designs the user
saves live in the same place (a short, bounded list). Nothing of one browser is
visible to another: viser's ``client.local_storage`` is the browser's own storage for
this origin, and the server keeps no copy beyond the open tab.

What comes back from a browser is untrusted: every design is parsed with the same
strict, size-capped parser as an uploaded file, and the saved list is bounded.
"""

from __future__ import annotations

import itertools
import json
import math
import textwrap
import threading

from camcore.model import (
    MAX_DESIGN_BYTES,
    MAX_SEGMENTS,
    Design,
    DesignError,
    design_from_json,
    design_to_json,
)

from .scene import CAMERA_VIEWS, OVERLAYS
from .segments import ANGLE_RANGE, LIFT_RANGE

WORKING_KEY = "camdesigner.working"
SAVED_KEY = "camdesigner.saved"
EXPLORE_KEY = "camdesigner.explore"  # the Explore tab's setup (not its results)
# a working design this version could not open (a later version's, a damaged one),
# set aside as it was rather than overwritten by the default design
UNREADABLE_KEY = "camdesigner.unreadable"
# the segment table's program while it does not make a valid design (the working design
# is the last valid one): a reload brings the unfinished program back; "" once valid
PROGRAM_KEY = "camdesigner.program"
# how the tab was looking at the design: cam angle, play speed, pause at stations, wide
# panel, overlays, camera preset (a teacher's review: a reload kept the design only)
VIEW_KEY = "camdesigner.view"
# the designs Undo and Redo go to (app.history: the last KEPT each way), so that a
# reload keeps a designer's steps back as well as the design
HISTORY_KEY = "camdesigner.history"
# the tab (a random id) that wrote the working design last, written with it: a reload
# takes the Undo steps only if the same tab wrote them (the browser's tabs share both
# keys, and a tab that rewrote the design without a step of its own had left another
# tab's steps beside it: Undo after a reload led into that tab's designs, a review)
PAIR_KEY = "camdesigner.pair"
KEYS = (  # all read at once
    WORKING_KEY,
    SAVED_KEY,
    EXPLORE_KEY,
    PROGRAM_KEY,
    VIEW_KEY,
    UNREADABLE_KEY,
    HISTORY_KEY,
    PAIR_KEY,
)
MAX_HISTORY_CHARS = 2_000_000  # of its stored text: 40 designs of 50 kB (one is ~3 kB)
MAX_SETUP_BYTES = 4096  # characters of the stored text
MAX_SAVED = 20  # named designs per browser
MAX_NAME = 60  # characters of a saved design's name
MAX_UNREAD_NAME = 1000  # ... of a name this version cannot show, kept as it is
# the saved list's stored text: a browser's storage holds about 5 million characters a
# site, so a longer text is not one a browser wrote
MAX_SAVED_CHARS = 5_000_000
# how long a read waits for a browser that is connected but does not answer: a browser
# busy with its first frames (software WebGL on a classroom PC) had answered after 5 s
# in 2 of 11 starts, and the reload kept nothing (a teacher's review)
READ_TIMEOUT_S = 20.0


def parse_working(text: str | None) -> Design | None:
    """The stored working design, or None if there is none or it is not a valid design."""
    opened = open_untrusted(text) if text else None
    return opened if isinstance(opened, Design) else None


def open_untrusted(text: str | bytes) -> Design | str:
    """The design in text a browser sent or kept, or why it is not one. Any failure is
    a why, not a crash: the restore must never die on what a browser holds (a
    400-digit number had raised OverflowError there, and from then on nothing was
    kept in that browser, with no message)."""
    try:
        return design_from_json(text)
    except DesignError as exc:
        return str(exc)
    except Exception as exc:  # an untrusted text found a parser defect: say so, go on
        return f"not a design this version can read ({type(exc).__name__})"


def read_saved(text: str | None) -> tuple[dict[str, str], dict]:
    """(parse_saved, unread_entries) of a stored saved list, its text parsed once (a
    security review: 500,000 tiny entries in 5 MB cost 0.7 s a parse, twice a click)."""
    raw = _saved_object(text)
    saved = _saved_of(raw)
    return saved, _unread_of(raw, saved)


def unread_entries(text: str | None, saved: dict[str, str]) -> dict:
    """The entries of a stored saved list that parse_saved left out (a later version's,
    a name too long): kept as they are when the list is written back, so saving a
    design never drops what this version cannot show. At most MAX_SAVED of them, each
    a JSON value of at most MAX_DESIGN_BYTES written under a name of at most
    MAX_UNREAD_NAME characters (a review: 1.75 million tiny entries had held 158 MB in
    the tab and cost 12 s at every save). {} unless ``text`` is a JSON object."""
    return _unread_of(_saved_object(text), saved)


def parse_saved(text: str | None) -> dict[str, str]:
    """{name: design JSON} from storage, keeping only well-formed entries, at most
    MAX_SAVED of them (a tampered value never grows the server's memory)."""
    return _saved_of(_saved_object(text))


def _saved_object(text: str | None) -> dict:
    """The stored saved list's JSON object, {} if it is none or too long to be one."""
    if not text or len(text) > MAX_SAVED_CHARS:
        return {}
    try:
        raw = json.loads(text)
    except (ValueError, RecursionError):  # (a review's deep nesting had killed the restore)
        return {}
    return raw if isinstance(raw, dict) else {}


def _saved_of(raw: dict) -> dict[str, str]:
    out = {}
    for name, value in itertools.islice(raw.items(), MAX_SAVED):
        if (
            isinstance(name, str)
            and 0 < len(name) <= MAX_NAME
            and isinstance(value, str)
            and len(value) <= MAX_DESIGN_BYTES
        ):
            out[name] = value
    return out


def _unread_of(raw: dict, saved: dict[str, str]) -> dict:
    out: dict[str, object] = {}
    for k, v in raw.items():
        if len(out) == MAX_SAVED:
            break
        if k not in saved and len(k) <= MAX_UNREAD_NAME:
            if len(json.dumps(v)) <= MAX_DESIGN_BYTES:  # (the text is at most 5 M)
                out[k] = v
    return out


def working_error(text: str | None) -> str | None:
    """Why a stored working design cannot be opened (DesignError's words), None if it
    can or there is none."""
    opened = open_untrusted(text) if text else None
    return opened if isinstance(opened, str) else None


def parse_setup(text: str | None) -> dict | None:
    """The stored Explore setup as a dict (its entries are checked by the panel), or
    None if absent, too long or not a JSON object."""
    if not text or len(text) > MAX_SETUP_BYTES:
        return None
    try:
        raw = json.loads(text)
    except (ValueError, RecursionError):  # (deep nesting fits in 4,096 characters)
        return None
    return raw if isinstance(raw, dict) else None


# entry -> what a stored view may hold there (anything else is left out, entry by entry)
_VIEW_CHECKS = {
    "theta_deg": lambda v: _number(v) and 0.0 <= v < 360.0,
    "speed_deg_s": lambda v: _number(v) and 5.0 <= v <= 360.0,  # the slider's range
    "pause_at_stations": lambda v: isinstance(v, bool),
    "wide_panel": lambda v: isinstance(v, bool),
    "camera_view": lambda v: v in CAMERA_VIEWS,
    "overlays": lambda v: (
        isinstance(v, dict) and all(k in OVERLAYS and isinstance(on, bool) for k, on in v.items())
    ),
}


def _number(v) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def parse_view(text: str | None) -> dict:
    """The stored view (VIEW_KEY) as a dict of its well-formed entries only (a browser's
    storage is untrusted: a wrong entry is dropped, the others still count); {} if
    absent, too long or not a JSON object."""
    raw = parse_setup(text)  # (the same bounds: at most MAX_SETUP_BYTES, an object)
    if raw is None:
        return {}
    out = {}
    for key, ok in _VIEW_CHECKS.items():
        try:
            if key in raw and ok(raw[key]):
                out[key] = raw[key]
        except TypeError:  # (an unhashable value tested for membership)
            pass
    return out


_SEGMENT_FIELDS = {"kind": (str,), "angle_deg": (int, float), "lift_mm": (int, float, type(None))}
_FIELDS = {*_SEGMENT_FIELDS, "law"}  # law: a string (or None)
# what the table's boxes take (a kept lift of 2000 mm had broken the table's rebuild)
_RANGES = {"angle_deg": ANGLE_RANGE, "lift_mm": LIFT_RANGE}
# a full table's JSON: ~110 characters a segment with full-precision floats (the Explore
# setup's 4,096 had cut a 48-segment program: it was not kept)
MAX_PROGRAM_CHARS = 200 * MAX_SEGMENTS


def parse_program(text: str | None) -> list[dict] | None:
    """The stored unfinished program as the table's segment dicts, or None if absent
    or not one: a JSON list of 1 to MAX_SEGMENTS objects of at most the table's fields
    (kind, angle_deg, lift_mm, law) with numbers as numbers (the model then says what
    is wrong with it, as with the user's own edit)."""
    if not text or len(text) > MAX_PROGRAM_CHARS:
        return None
    try:  # (NaN and Infinity are not numbers the table could have sent; 1e400 is
        # read as infinity, a 400-digit integer as one: the table's ranges refuse both)
        raw = json.loads(text, parse_constant=_refuse)
    except (ValueError, RecursionError):
        return None
    if not isinstance(raw, list) or not 0 < len(raw) <= MAX_SEGMENTS:
        return None
    for g in raw:
        if not isinstance(g, dict) or not {"kind", "angle_deg"} <= set(g) <= _FIELDS:
            return None
        if any(
            isinstance(v, bool)
            or not isinstance(v, _SEGMENT_FIELDS.get(k, (str, type(None))))
            or (isinstance(v, int | float) and not _RANGES[k][0] <= v <= _RANGES[k][1])
            for k, v in g.items()
        ):
            return None
    return raw


def proposed_name(name: str) -> str:
    """A name to keep ``name``'d design under that fits MAX_NAME: the name itself, or
    without its closing parenthesis, or cut at a word with " …" (a review: the paper's
    example was kept as "… (double concave faces", cut mid-parenthesis); "my cam" for
    none."""
    name = " ".join(str(name).split())
    if len(name) > MAX_NAME and " (" in name:
        name = name.split(" (")[0]
    short = textwrap.shorten(name, MAX_NAME, placeholder=" …")
    if name and short == "…":  # (one word longer than a name: cut inside it, a review)
        short = name[: MAX_NAME - 2] + " …"
    return short or "my cam"


def _refuse(name: str):
    raise ValueError(name)


def history_text(past: list[Design], future: list[Design], tab: str = "") -> str:
    """The steps of an app.history.History to keep: the last KEPT each way, and the
    ``tab`` that wrote them (PAIR_KEY)."""
    from .history import KEPT

    def texts(designs: list[Design]) -> list[str]:
        return [design_to_json(d) for d in designs[-KEPT:]]

    return json.dumps({"past": texts(past), "future": texts(future), "tab": tab})


def parse_history(text: str | None, pair: str | None = None) -> tuple[list[Design], list[Design]]:
    """(past, future) from history_text's text, as untrusted as any stored design:
    at most KEPT each way, each parsed like an uploaded file; a step that is not a
    valid design is left out (the others still count); ([], []) if the text is not
    history_text's, or if its steps are another tab's than the one that wrote the
    working design (``pair``: PAIR_KEY's value; steps or a design kept without a tab,
    an earlier version's, are taken as they are)."""
    from .history import KEPT

    if not text or len(text) > MAX_HISTORY_CHARS:
        return [], []
    try:
        raw = json.loads(text)
    except (ValueError, RecursionError):
        return [], []
    if not isinstance(raw, dict):
        return [], []
    tab = raw.get("tab")
    if isinstance(tab, str) and tab and isinstance(pair, str) and pair and tab != pair:
        return [], []

    def designs(key: str) -> list[Design]:
        entries = raw.get(key)
        if not isinstance(entries, list):
            return []
        parsed = (parse_working(e) if isinstance(e, str) else None for e in entries[-KEPT:])
        return [d for d in parsed if d is not None]

    return designs("past"), designs("future")


def with_saved(saved: dict[str, str], name: str, design: Design) -> dict[str, str]:
    """The list with ``design`` saved under ``name`` (replacing one of the same name).

    Raises ValueError for an empty or too long name, or a full list."""
    name = name.strip()
    if not name or len(name) > MAX_NAME:
        raise ValueError(f"a name of 1 to {MAX_NAME} characters, please")
    if name not in saved and len(saved) >= MAX_SAVED:
        raise ValueError(f"this browser already keeps {MAX_SAVED} designs; delete one first")
    return {**saved, name: design_to_json(design)}


class BrowserStore:
    """The browser-side storage of one tab (``client.local_storage``)."""

    def __init__(self, client):
        self._storage = client.local_storage
        self.silent = False  # a read got no answer: what is stored is unknown

    def read(self, key: str) -> str | None:
        """The stored string, or None if absent, unreadable or the browser is silent
        (then ``silent`` is set: a tab that writes after such a read could replace what
        the browser holds without having seen it). Once silent, later reads return None
        at once: the tab keeps nothing anyway, and each would wait READ_TIMEOUT_S."""
        if self.silent:
            return None
        try:
            value = self._storage.get_item(key, timeout=READ_TIMEOUT_S)
        except (RuntimeError, TimeoutError):
            self.silent = True
            return None
        return value if isinstance(value, str) else None

    def fresh(self, key: str) -> tuple[bool, str | None]:
        """(answered, value): ``read`` now, for a write that must not replace what
        another tab of this browser wrote meanwhile; a browser that does not answer this
        time leaves ``silent`` as it was. Waits up to READ_TIMEOUT_S: never call it with
        the tab's lock held."""
        was, self.silent = self.silent, False
        value = self.read(key)
        answered, self.silent = not self.silent, was
        return answered, value

    def read_all(self, keys: tuple[str, ...]) -> dict[str, str | None]:
        """``read`` of every key, all asked at once: a busy browser answers them
        together. (Read one after another, the third of six had waited past its 5 s
        while the browser drew its first frames with software WebGL, and the tab kept
        nothing from then on.) A silent browser costs READ_TIMEOUT_S once."""
        values: dict[str, str | None] = {}
        threads = [  # (daemon threads: a read left waiting never holds up the exit)
            threading.Thread(
                target=lambda k=k: values.__setitem__(k, self.read(k)),
                name="storage-read",
                daemon=True,
            )
            for k in keys
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        if self.silent or len(values) < len(keys):  # (a read failed: the rest is not
            self.silent = True  # the whole story)
            return dict.fromkeys(keys)
        return {k: values[k] for k in keys}

    def write(self, key: str, value: str) -> None:
        try:  # (viser's warning about a closed tab is filtered in app.main)
            self._storage.set_item(key, value)
        except Exception:  # the tab is gone: nothing to keep
            pass
