"""Design-space exploration over sweep rows (camcore.sweep): the figures a designer
trades against each other, the Pareto front of chosen figures among the valid
designs, and the map that shows which limit fails where.

Rows are ``camcore.sweep.row`` dicts (the flattened ``report --json`` summary plus
``grid.<path>`` values), so whatever the sweep ran on (this process, a Dask cluster,
the app's background worker) the exploration reads the same table.
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass, field

import numpy as np

from .checks import CODES
from .model import PAPER_FOLLOWERS, Design, FollowerKind, SegmentKind
from .sweep import Spec, axis_values, first_violation, front_order, pareto_mask


@dataclass(frozen=True)
class Figure:
    """A figure of merit of a design, read from a sweep row (smaller is better): the
    largest of the row's ``columns`` (None / NaN if any is missing)."""

    label: str
    unit: str
    columns: tuple[str, ...]
    symbol: str = ""  # how a list of designs names it ("R 70.75 mm")

    def get(self, row: dict) -> float | None:
        vals = [row.get(c) for c in self.columns]
        return None if any(v is None for v in vals) else max(vals)  # type: ignore[type-var]

    def of_table(self, table: dict[str, np.ndarray]) -> np.ndarray:
        """The figure of every row of a column table (name -> float array, NaN for null)."""
        return np.maximum.reduce([np.asarray(table[c], dtype=float) for c in self.columns])


FIGURES: dict[str, Figure] = {
    "cam_size": Figure("cam size R (high-dwell radius)", "mm", ("dwell_radius_mm",), "R"),
    "stress": Figure("max contact stress σ_H", "MPa", ("contact_stress_max_MPa.cycle",), "σ_H"),
    "pressure_angle": Figure(
        "max pressure angle",
        "°",
        ("pressure_angle_max_deg.rise", "pressure_angle_max_deg.fall"),
        "φ",
    ),
    "force": Figure("max contact force F_N", "N", ("contact_force_max_N.cycle",), "F_N"),
    "torque": Figure("peak driving torque", "N m", ("cam_torque_max_Nm.drive",), "T"),
    "wear": Figure("max wear depth", "µm/10⁶ cycles", ("wear_depth_max_um_per_Mcycle",), "wear"),
    "outer_diameter": Figure("cam outer diameter", "mm", ("profile.outer_diameter_mm",), "Ø"),
}


# figures the batched core (sweep --fast) does not compute
PROFILE_FIGURES = {"wear", "outer_diameter"}


def sweep_grid(
    x: tuple[str, float, float], y: tuple[str, float, float], steps: int, kinds: list[str]
) -> dict:
    """The grid of a SPEC (camcore.sweep.parse_spec) for the follower ``kinds`` times
    ``steps`` values of each field, (path, from, to) from ``x`` and ``y``: the kinds
    vary slowest, y fastest."""
    return {
        "follower.kind": list(kinds),
        x[0]: {"from": x[1], "to": x[2], "num": steps},
        y[0]: {"from": y[1], "to": y[2], "num": steps},
    }


def grid_points(grid: dict, base: dict | None = None, balance: str | None = None) -> list[dict]:
    """The points of a SPEC's ``grid``, {path: value} each, in the order and with the
    very values ``camcore sweep`` gives them (the same axes, the last fastest); with
    ``balance`` (the SPEC's), each point also sets that segment angle of ``base`` (a
    Design's JSON data) to the rest of the turn, as the sweep does."""
    axes = tuple((path, axis_values(path, raw)) for path, raw in grid.items())
    return list(Spec(base or {}, axes, grid, balance=balance).points())


def spec_document(base: dict, grid: dict, balance: str | None = None) -> str:
    """A SPEC document of the sweep of ``grid`` around the design ``base`` (a Design's
    JSON data), with its ``balance`` if any: ``camcore sweep SPEC --out T.parquet
    --fast`` runs the same designs, and without ``--fast`` adds the profile's figures
    and checks."""
    extra = {} if balance is None else {"balance": balance}
    return json.dumps({"base": base, "grid": grid, **extra}, indent=1) + "\n"


def segment_angle_paths(design: Design) -> dict[str, tuple[int, SegmentKind]]:
    """The angle of each rise and fall of a program made of segments (a classic
    program has its own fields, motion.rise_deg ...), by its path
    ("motion.segments.0.angle_deg"): the fields a sweep may vary with a ``balance``;
    none if no dwell can take up the turn (balance_for)."""
    segs = design.motion.segments
    if design.motion.classic is not None or all(s.kind is not SegmentKind.dwell for s in segs):
        return {}
    return {
        f"motion.segments.{i}.angle_deg": (i, s.kind)
        for i, s in enumerate(segs)
        if s.kind is not SegmentKind.dwell
    }


def balance_for(design: Design, paths: list[str]) -> str | None:
    """The segment angle that takes up the turn when ``paths`` sweep segment angles of
    ``design`` (segment_angle_paths): the longest dwell's, the nearest of equals to
    the first swept segment, the one after it before the one before (an indexer's
    rise against the dwell that follows it, a fall against its own cycle's dwell: a
    review's fall had moved a dwell of the second cycle). None if no path is a
    segment angle (segment_angle_paths: then there is a dwell)."""
    angles = segment_angle_paths(design)
    swept = [angles[p][0] for p in paths if p in angles]
    if not swept:
        return None
    segs, s = design.motion.segments, swept[0]
    n = len(segs)

    def rank(i: int) -> tuple[float, int, bool]:
        after, before = (i - s) % n, (s - i) % n
        return (segs[i].angle_deg, -min(after, before), after <= before)

    dwells = [i for i in range(n) if segs[i].kind is SegmentKind.dwell]
    return f"motion.segments.{max(dwells, key=rank)}.angle_deg"


def figure_values(rows: list[dict], names: list[str]) -> np.ndarray:
    """(rows x figures) of FIGURES[names]; NaN where a row has none (not a design)."""
    out = np.full((len(rows), len(names)), np.nan)
    for i, r in enumerate(rows):
        for j, n in enumerate(names):
            v = FIGURES[n].get(r) if r.get("error") is None else None
            out[i, j] = np.nan if v is None else float(v)
    return out


def ignored_fields(row: dict) -> list[str]:
    """The grid paths of ``row`` its follower does not use (FollowerKind.uses): a single
    follower swept over the double follower's offset e is one design, many times."""
    kind = _try_kind(_kind(row))
    if kind is None:
        return []
    return [
        k[5:]
        for k in row
        if k.startswith("grid.follower.") and not kind.uses(k[len("grid.follower.") :])
    ]


def distinct(rows: list[dict]) -> np.ndarray:
    """True for one row of each distinct design (the first that is a design at all):
    rows that differ only in grid fields their follower does not use are the same
    design."""
    kept: dict[tuple, int] = {}  # design key -> the row that stands for it
    for i, r in enumerate(rows):
        drop = {f"grid.{p}" for p in ignored_fields(r)}
        key = tuple(
            sorted(
                (k, repr(v + 0.0 if isinstance(v, float) else v))  # -0.0 is 0.0
                for k, v in r.items()
                if k.startswith("grid.") and k not in drop
            )
        )
        j = kept.get(key)
        # an ignored field is still checked against its own limits (a roller radius of 0
        # for a concave face): a row refused for it must not hide a valid copy
        if j is None or (rows[j].get("error") is not None and r.get("error") is None):
            kept[key] = i
    out = np.zeros(len(rows), dtype=bool)
    out[list(kept.values())] = True
    return out


def best_per_kind(rows: list[dict], name: str) -> dict[str, int]:
    """Per follower kind of the rows (in their order), the valid row least in the
    figure FIGURES[name] (the first of equal ones): "the smallest cam each follower
    allows", "the least stress each reaches" (a designer's review had narrowed the
    ranges again and again to read it off the map). Kinds with no valid row with a
    value are left out."""
    v = figure_values(rows, [name])[:, 0]
    out: dict[str, int] = {}
    for i, r in enumerate(rows):
        if not r.get("valid") or not np.isfinite(v[i]):
            continue
        k = _kind(r)
        if k not in out or v[i] < v[out[k]]:
            out[k] = i
    return out


OFFERED = 30  # designs of a front numbered on the map and listed for loading


def offered(front: np.ndarray, values: np.ndarray, most: int = OFFERED) -> np.ndarray:
    """At most ``most`` designs of ``front`` (ordered by the first figure), spread
    evenly along it in the plane of the figures (``values``: rows x figures; each
    figure scaled to its extent on the front), both ends included: the first ``most``
    had offered only the smallest cams of a 107-design front, and every n-th design
    had offered groups of designs 0.01 mm apart where the front crowds (a review)."""
    if len(front) <= most:
        return front
    v = values[front]
    span = np.ptp(v, axis=0)
    steps = np.hypot.reduce(np.diff(v / np.where(span > 0, span, 1.0), axis=0), axis=1)
    along = np.concatenate([[0.0], np.cumsum(steps)])  # distance along the front
    if along[-1] == 0.0:  # (all at one point: by position)
        along = np.arange(len(front), dtype=float)
    targets = np.linspace(0.0, along[-1], most)
    nearest = np.clip(np.searchsorted(along, targets), 1, len(front) - 1)
    nearest -= targets - along[nearest - 1] < along[nearest] - targets  # the closer one
    return front[np.unique(nearest)]


def pareto(rows: list[dict], names: list[str]) -> np.ndarray:
    """Indices of the valid rows on the Pareto front of FIGURES[names] (all minimized),
    ordered by the first figure; a design swept several times (``distinct``) once."""
    v = figure_values(rows, names)
    valid = np.array([bool(r.get("valid")) for r in rows], dtype=bool)
    v[~(valid & distinct(rows))] = np.nan
    return front_order(v, np.flatnonzero(pareto_mask(v)))


# --- the front of a sweep's table (camcore pareto) ---------------------------------


@dataclass(frozen=True)
class TableFront:
    """What a sweep's Parquet table says about "which cam is best?"."""

    rows: int
    valid: int
    refused: int  # not designs at all (the row's error)
    first_limits: dict[str, int]  # first broken limit -> rows, the commonest first
    profile_checked: bool  # False if any valid row comes from the batched core
    front: list[dict]  # per distinct front design: {"row", "grid": {...}, "figures": {...}}
    repeats: int  # front rows that repeat a listed design (a field its follower ignores)
    lacking: int  # valid rows without a value for a figure (not compared)
    lacking_by: dict[str, int] = field(default_factory=dict)  # figure -> rows without it
    lacking_why: list[str] = field(default_factory=list)  # why they lack it, as known
    # per follower kind, the valid row least in the first figure (best_per_kind):
    # {"row", "grid", "value"}
    least: dict[str, dict] = field(default_factory=dict)


def table_front(path, names: list[str]) -> TableFront:
    """The Pareto front of FIGURES[names] over the valid rows of the sweep table at
    ``path`` (camcore.sweep's Parquet), read column-wise so a million-row table takes
    seconds; the front is ordered by the first figure, each distinct design once.
    FileError if the file is not a sweep table or its valid rows lack a figure's
    column."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .files import FileError, regular_file

    try:
        have = set(pq.read_schema(regular_file(path)).names)
    except (OSError, pa.ArrowException) as exc:
        raise FileError(f"{path}: not a readable Parquet table ({exc})") from None
    if not {"valid", "error"} <= have or not any(c.startswith("grid.") for c in have):
        raise FileError(f"{path}: not a camcore sweep table (no valid, error and grid columns)")
    try:
        return _table_front(path, names, have)
    except FileError:
        raise
    except (OSError, pa.ArrowException, ValueError, TypeError, AttributeError) as exc:
        # columns of the right names holding something else (a hand-made table)
        why = f"{type(exc).__name__}: {str(exc)[:200]}"
        raise FileError(f"{path}: not a camcore sweep table ({why})") from None


def _table_front(path, names: list[str], have: set[str]) -> TableFront:
    import pyarrow as pa
    import pyarrow.parquet as pq

    from .files import FileError

    wanted = list(dict.fromkeys(c for n in names for c in FIGURES[n].columns))
    present = [c for c in wanted if c in have]
    grid = sorted(c for c in have if c.startswith("grid."))
    extra = [c for c in ("profile_checked", "follower", "violations") if c in have]
    t = pq.read_table(path, columns=[*grid, "valid", "error", *extra, *present])
    refused = t.column("error").is_valid().to_numpy(zero_copy_only=False)
    valid = _bools(t.column("valid"), False) & ~refused
    gone = [(n, c) for n in names for c in FIGURES[n].columns if c not in have]
    if gone and valid.any():  # (a table of no design at all has no figure columns)
        n, c = gone[0]
        why = " (a --fast sweep leaves it out)" if n in PROFILE_FIGURES else ""
        raise FileError(f"{path} has no column {c} for the figure {n}{why}")
    nan = np.full(t.num_rows, np.nan)
    cols = {
        c: t.column(c).cast(pa.float64()).to_numpy(zero_copy_only=False) if c in have else nan
        for c in wanted
    }
    values = np.column_stack([FIGURES[n].of_table(cols) for n in names])
    values[~valid] = np.nan
    reasons = _lacking_why(t, values, valid, names, grid)
    values[np.isinf(values)] = np.nan  # (a hand-made table's: -inf had been a "least")
    idx = np.flatnonzero(pareto_mask(values))
    idx = front_order(values, idx)  # by the first figure, then the next, then row
    # the follower kind tells which grid fields a row's design ignores (distinct)
    rows = t.select([*grid, *present, *extra]).take(idx).to_pylist()
    keep = distinct(rows)
    front = [
        {
            "row": int(i),  # in the table, from 0 (camcore.sweep.design_of_row)
            "grid": {  # None: a field the follower does not use (any value)
                k[5:]: None if k[5:] in ignored_fields(r) else v
                for k, v in r.items()
                if k.startswith("grid.")
            },
            "figures": {n: float(values[i, j]) for j, n in enumerate(names)},
        }
        for r, i, k in zip(rows, idx, keep, strict=True)
        if k
    ]
    broken = ~valid & ~refused
    least = _least_per_kind(t, values[:, 0], grid)
    checked = "profile_checked" not in have or bool(
        _bools(t.column("profile_checked"), True)[valid].all()
    )
    return TableFront(
        rows=t.num_rows,
        valid=int(valid.sum()),
        refused=int(refused.sum()),
        first_limits=(
            _first_limits(t.column("violations"), broken)
            if "violations" in have
            else ({"invalid": int(broken.sum())} if broken.any() else {})
        ),
        profile_checked=checked,
        front=front,
        repeats=len(rows) - len(front),
        lacking=int((valid & ~np.isfinite(values).all(axis=1)).sum()),
        lacking_by={
            n: int((valid & ~np.isfinite(values[:, j])).sum())
            for j, n in enumerate(names)
            if (valid & ~np.isfinite(values[:, j])).any()
        },
        least=least,
        lacking_why=reasons,
    )


def _lacking_why(
    t, values: np.ndarray, valid: np.ndarray, names: list[str], grid: list[str]
) -> list[str]:
    """Why ``valid`` rows of a table lack a figure (NaN or +-inf in ``values``, per row
    and figure), as far as the table tells: a fast sweep leaves the profile's figures
    out, a knife edge has no contact stress, and an infinite value is no figure (a
    review: rollers' -inf had been blamed on knife edges)."""
    out = []
    missing = np.isnan(values) & valid[:, None]
    for j, n in enumerate(names):
        if n in PROFILE_FIGURES and missing[:, j].any():
            out.append(f"rows of the batched core have no {n}")
    if "stress" in names:
        kinds = _kinds(t, grid)
        if (
            kinds is not None
            and (missing[:, names.index("stress")] & (kinds == "knife_edge")).any()
        ):
            out.append("a knife edge has no contact stress")
    for j, n in enumerate(names):
        if (k := int(np.isinf(values[:, j]).sum())) > 0:
            out.append(f"{k} {'row holds' if k == 1 else 'rows hold'} an infinite {n}")
    return out


def _kinds(t, grid: list[str]) -> np.ndarray | None:
    """The follower kind of each row of table ``t``, or None if it does not say."""
    col = "grid.follower.kind" if "grid.follower.kind" in grid else "follower"
    if col not in t.column_names:
        return None
    return np.array([str(k) for k in t.column(col).to_pylist()], dtype=object)


def _least_per_kind(t, first: np.ndarray, grid: list[str]) -> dict[str, dict]:
    """best_per_kind over a table (``first``: the first figure per row, NaN where the
    row is not valid), column-wise: per follower kind in the table's order, the row
    least in it (the first of equal ones)."""
    col = "grid.follower.kind" if "grid.follower.kind" in grid else "follower"
    kinds = _kinds(t, grid)
    if kinds is None:
        return {}
    out: dict[str, dict] = {}
    for kind in dict.fromkeys(kinds):
        v = np.where(kinds == kind, first, np.nan)
        if not np.isfinite(v).any():
            continue
        i = int(np.nanargmin(v))
        r = t.select(grid).slice(i, 1).to_pylist()[0]
        out[kind] = {
            "row": i,
            "grid": {
                k[5:]: None if k[5:] in ignored_fields({**r, col: kind}) else x
                for k, x in r.items()
            },
            "value": float(first[i]),
        }
    return out


def _bools(column, null: bool) -> np.ndarray:
    """A boolean column as a numpy array, ``null`` where it holds none."""
    import pyarrow as pa

    return np.asarray(
        column.cast(pa.bool_()).fill_null(null).to_numpy(zero_copy_only=False), dtype=bool
    )


def _first_limits(violations, broken: np.ndarray) -> dict[str, int]:
    """First broken limit -> count over the rows ``broken`` (JSON text per row); each
    distinct text is parsed once."""
    import json

    import pyarrow as pa

    text = violations.cast(pa.string()).filter(pa.array(broken)).fill_null("[]")
    counts = text.value_counts()
    out: dict[str, int] = {}
    for text, n in zip(
        counts.field("values").to_pylist(), counts.field("counts").to_pylist(), strict=True
    ):
        codes = [v.get("code") or "invalid" for v in json.loads(text)] or ["invalid"]
        out[str(codes[0])] = out.get(str(codes[0]), 0) + int(n)
    return dict(sorted(out.items(), key=lambda kv: (-kv[1], kv[0])))


# --- the map ------------------------------------------------------------------------

_OK = "valid"
_MARKERS: dict[FollowerKind | None, str] = dict(zip(PAPER_FOLLOWERS, "os^D", strict=True))


def _kind(r: dict) -> str:
    return str(r.get("grid.follower.kind") or r.get("follower") or "")


# The map is drawn for the width it is shown at: one point of text is PT_PX pixels
# there (9 pt: 12 px, legible in the app's 384 px panel as in its 1000 px wide one),
# and the PNG has twice the pixels (sharp on a high-DPI screen; the image's full-size
# view doubles the text). A review found the earlier 760 px drawing's text at ~5 px
# once the narrow panel had scaled it down.
PT_PX = 1.35  # shown pixels per point of text
DPI = 2 * 72 * PT_PX  # the PNG's pixels per inch: twice the shown ones
FONT, SMALL = 9, 8  # [pt] titles and axis labels; ticks, legends and the front's numbers
PANEL_PX = 384  # the app's narrow panel (app.layout.NARROW_PANEL_PX)
MAP_IN = 2.4  # [in] the least width of one follower's map (more fit side by side)
WIDE_IN = 6.0  # [in] from this figure width: one-line titles, four-column legends


def explore_png(
    rows: list[dict],
    x: tuple[str, str],
    y: tuple[str, str],
    names: list[str],
    front: np.ndarray,
    shown_px: int = PANEL_PX,
    limits: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> bytes:
    """The exploration as one PNG (explore_figure), 2 x ``shown_px`` pixels wide (drawn
    for 240 px at least)."""
    fig = explore_figure(rows, x, y, names, front, shown_px, limits)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI)
    return buf.getvalue()


def _extent(values) -> tuple[float, float]:
    """(least, largest) of the finite ``values``; (0, 1) if there are none."""
    values = np.asarray(values, dtype=float)
    v = values[np.isfinite(values)]
    return (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)


def _limits(values) -> tuple[float, float]:
    """An axis' limits around the finite ``values``, with a margin for the markers."""
    lo, hi = _extent(values)
    pad = 0.05 * (hi - lo) if hi > lo else 0.5 * abs(lo) or 1.0
    return lo - pad, hi + pad


def explore_figure(
    rows: list[dict],
    x: tuple[str, str],
    y: tuple[str, str],
    names: list[str],
    front: np.ndarray,
    shown_px: int = PANEL_PX,
    limits: tuple[tuple[float, float], tuple[float, float]] | None = None,
):
    """The exploration as a matplotlib Figure, laid out to be shown ``shown_px`` wide
    (PT_PX pixels per point of text): per follower kind, the (x, y) grid coloured by
    the first limit each design breaks (green: valid), side by side as many as fit
    (MAP_IN), all on the same axes: ``limits`` ((x0, x1), (y0, y1)), the sweep's
    ranges, else those of the rows (a sweep cancelled midway leaves a kind part of the
    range, which must not look like the whole); below (beside one follower's map in a
    panel WIDE_IN wide), the valid designs in the plane of the first two figures with
    the Pareto front of ``names`` (two or three figures; a third colours the points)
    numbered as in the app's list. ``x`` and ``y`` are (grid path, axis label)."""
    from matplotlib.figure import Figure as MplFigure

    kinds = list(dict.fromkeys(_kind(r) for r in rows))
    causes = [first_violation(r) or _OK for r in rows]
    legend = sorted({_OK, *causes}, key=_outcome_rank)
    cmap = {c: _colour(c) for c in legend}
    n = max(1, len(kinds))
    width = max(shown_px, 240) / (72 * PT_PX)  # [in]
    # one follower in a wide panel: its map beside the front, not one map the panel's
    # width and as tall, with the front below the fold (a review at 1920 px)
    beside = n == 1 and width >= WIDE_IN
    cols = 2 if beside else min(n, max(2, int(width // MAP_IN)))
    maps = math.ceil(n / cols)
    map_h = 0.72 * width / cols + 0.5  # [in] a map and its title and ticks
    front_h = 0.0 if beside else min(0.75 * width, 4.2) + 0.6
    legend_h = 0.3 + 0.2 * math.ceil(len(legend) / (2 if width < WIDE_IN else 4))
    fig = MplFigure(
        figsize=(width, legend_h + maps * map_h + front_h), dpi=DPI, layout="constrained"
    )
    if beside:
        grid = fig.add_gridspec(1, 2)
    else:
        grid = fig.add_gridspec(maps + 1, cols, height_ratios=[map_h] * maps + [front_h])
    xs = np.array([float(r.get(f"grid.{x[0]}", np.nan)) for r in rows])
    ys = np.array([float(r.get(f"grid.{y[0]}", np.nan)) for r in rows])
    xlim = _limits(xs if limits is None else limits[0])
    ylim = _limits(ys if limits is None else limits[1])
    cells = max(len(set(xs[np.isfinite(xs)])), len(set(ys[np.isfinite(ys)])), 2)
    side = 0.8 * (72 * width / cols - 40) / cells  # [pt] a marker fills most of its cell
    first = None
    for i, kind in enumerate(kinds):
        ax = fig.add_subplot(grid[i // cols, i % cols], sharex=first, sharey=first)
        first = first or ax
        m = np.array([_kind(r) == kind for r in rows])
        ax.scatter(
            xs[m],
            ys[m],
            c=[cmap[c] for c, k in zip(causes, m, strict=True) if k],
            marker="s",
            s=float(np.clip(side, 3.0, 11.0)) ** 2,
            edgecolors="none",
        )
        unused = {p for r in rows if _kind(r) == kind for p in ignored_fields(r)}
        note = [axis for axis, (path, _) in zip("xy", (x, y), strict=True) if path in unused]
        title = _label(kind) + (f"\n(does not use {' or '.join(note)})" if note else "")
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_title(title, fontsize=FONT)
        bottom, left = i + cols >= n, i % cols == 0  # (no map below it; the first column)
        room = (72 * width - 45) / cols - 8  # [pt] a map's width (less the y label, ticks)
        ax.set_xlabel(_wrapped(x[1], room) if bottom else "", fontsize=FONT)
        ax.set_ylabel(y[1] if left else "", fontsize=FONT)
        ax.tick_params(labelsize=SMALL, labelbottom=bottom, labelleft=left)
    handles = [_patch(cmap[c], c.replace("_", " ")) for c in legend]  # (words, not codes)
    fig.legend(
        handles=handles,
        loc="outside upper center",
        ncols=min(2 if width < WIDE_IN else 4, len(handles)),
        fontsize=SMALL,
        title="first limit broken",
        title_fontsize=SMALL,
    )
    if beside:
        _pareto_panel(fig.add_subplot(grid[0, 1]), rows, names, front, width / 2)
    else:
        _pareto_panel(fig.add_subplot(grid[maps, :]), rows, names, front, width)
    return fig


def _wrapped(label: str, room_pt: float) -> str:
    """``label`` on as many lines as it needs to fit ``room_pt`` wide (a review: two
    maps' "Base radius r_b [mm]" ran into one another in the narrow panel)."""
    import textwrap

    chars = max(8, int((room_pt - 12) / (0.6 * FONT)))  # (a character ~0.6 em wide)
    return "\n".join(textwrap.wrap(label, chars, break_long_words=False)) or label


def _pareto_panel(ax, rows: list[dict], names: list[str], front: np.ndarray, width: float) -> None:
    """The valid designs in the plane of the first two figures, the front numbered; a
    third figure colours the points, and its front (which in this plane is no curve)
    is ringed instead of joined. ``width``: the figure's [in]."""
    from matplotlib.colors import Normalize
    from matplotlib.lines import Line2D

    fa, fb = FIGURES[names[0]], FIGURES[names[1]]
    v = figure_values(rows, names)
    valid = np.array([bool(r.get("valid")) for r in rows])
    third = len(names) > 2 and valid.any()
    colour: dict = {}
    if third:
        colour = {"cmap": "viridis", "norm": Normalize(*_span(v[valid, 2]))}
    kinds = list(dict.fromkeys(_kind(r) for r in rows))
    for kind in kinds:
        m = valid & np.array([_kind(r) == kind for r in rows])
        marker = _MARKERS.get(_try_kind(kind), "o")
        extra = {"c": v[m, 2], **colour} if third else {}
        ax.scatter(v[m, 0], v[m, 1], s=14, alpha=0.55, label=_label(kind), marker=marker, **extra)
    if front.size:
        if third:
            ax.scatter(v[front, 0], v[front, 1], s=70, facecolors="none", edgecolors="k", lw=0.9)
        else:
            ax.plot(v[front, 0], v[front, 1], "k-", lw=0.8, alpha=0.6)
    ax.set_xlabel(f"{fa.label} [{fa.unit}]", fontsize=FONT)
    ax.set_ylabel(f"{fb.label} [{fb.unit}]", fontsize=FONT)
    if third:
        from matplotlib.cm import ScalarMappable

        fc = FIGURES[names[2]]
        bar = ax.figure.colorbar(ScalarMappable(**colour), ax=ax)
        bar.set_label(f"{fc.label} [{fc.unit}]", fontsize=FONT)
        bar.ax.tick_params(labelsize=SMALL)
        title = "valid designs; ringed and numbered:\nthe Pareto front of all three figures"
    else:
        title = "valid designs; the numbered line is\nthe Pareto front (smaller is better)"
    ax.set_title(title if width < WIDE_IN else title.replace("\n", " "), fontsize=FONT)
    ax.tick_params(labelsize=SMALL)
    if not valid.any():  # (a review: empty axes of -0.04 .. 0.04 "MPa" said nothing)
        ax.text(
            0.5,
            0.5,
            "no valid design in this sweep",
            transform=ax.transAxes,
            ha="center",
            va="center",
            fontsize=FONT + 2,
        )
        ax.set_xticks([])
        ax.set_yticks([])
    if valid.any():
        handles = [  # grey markers: with a third figure the colour is its value
            Line2D(
                [], [], ls="", marker=_MARKERS.get(_try_kind(k), "o"), color="0.45", label=_label(k)
            )
            for k in kinds
        ]
        ax.legend(  # below the axes, never over the designs (a review)
            handles=handles if third else None,
            fontsize=SMALL,
            loc="upper center",
            bbox_to_anchor=(0.5, -0.16 if width < WIDE_IN else -0.12),
            ncols=2 if width < WIDE_IN else 4,
            frameon=False,
        )
    if front.size:  # last: the numbers are placed on the axes as laid out
        _number_front(ax, v, front)


def _number_front(ax, v: np.ndarray, front: np.ndarray) -> None:
    """The front's numbers (the app's list). Designs at (nearly) one spot, within a
    line of text, share a label ("3,4", "16-18"); any other gets its own, put above or
    below, right or left of its design, where it overprints no label placed before it
    and, if it can, stays within the axes (a review could not find 17 under another
    label; a later one found designs 13-14 unnumbered, their numbers joined to a label
    7 mm of R away; another saw "4-6" cut at the image's edge). Measured in the
    axes' own fraction, from their size once the figure is laid out (a colour bar
    narrows them); the labels take no part in the layout, so it stays as measured."""
    ax.figure.draw_without_rendering()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    box = ax.get_position()
    w_in, h_in = box.width * ax.figure.get_figwidth(), box.height * ax.figure.get_figheight()
    line = 1.25 * SMALL / 72 / h_in  # a line of text's height, in the axes' fraction
    char = 0.62 * SMALL / 72 / w_in  # a character's width (digits, commas)
    pad = (3 / 72 / w_in, 3 / 72 / h_in)  # the label's offset from its design
    groups: list[tuple[np.ndarray, int, list[int]]] = []  # (where, design, its numbers)
    for n, i in enumerate(offered(front, v), start=1):
        at = np.array([(v[i, 0] - x0) / (x1 - x0), (v[i, 1] - y0) / (y1 - y0)])
        same = [g for g in groups if abs(at[0] - g[0][0]) < char and abs(at[1] - g[0][1]) < line]
        if same:
            same[0][2].append(n)
        else:
            groups.append((at, i, [n]))
    placed: list[tuple[float, float, float, float]] = []  # label boxes (x0, x1, y0, y1)
    sides = [(right, up) for up in (True, False) for right in (True, False)]
    for at, i, numbers in groups:
        text = numbers_text(numbers)
        w, h = char * len(text) + pad[0], line + pad[1]
        boxes = [
            (at[0] if right else at[0] - w, at[0] + w if right else at[0],
             at[1] if up else at[1] - h, at[1] + h if up else at[1])
            for right, up in sides
        ]  # fmt: skip
        free = [k for k, b in enumerate(boxes) if not any(_overlap(b, p) for p in placed)]
        inside = [k for k in free if _within_axes(boxes[k])]  # (a review: "4-6" cut off
        k = inside[0] if inside else free[0] if free else 0  # at the image's right edge)
        placed.append(boxes[k])
        right, up = sides[k]
        ax.annotate(
            text,
            (v[i, 0], v[i, 1]),
            fontsize=SMALL,
            xytext=(3 if right else -3, 3 if up else -3),
            textcoords="offset points",
            ha="left" if right else "right",
            va="bottom" if up else "top",
        ).set_in_layout(False)


def _within_axes(b: tuple[float, ...]) -> bool:
    """Whether box (x0, x1, y0, y1), in the axes' fraction, lies within the axes."""
    return 0.0 <= b[0] and b[1] <= 1.0 and 0.0 <= b[2] and b[3] <= 1.0


def _overlap(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """Whether boxes (x0, x1, y0, y1) overlap."""
    return a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3]


def numbers_text(numbers: list[int]) -> str:
    """Increasing numbers as runs: [3, 4, 5, 9] -> "3-5,9", [3, 4] -> "3,4"."""
    runs: list[list[int]] = []
    for n in numbers:
        if runs and n == runs[-1][-1] + 1:
            runs[-1].append(n)
        else:
            runs.append([n])
    return ",".join(f"{r[0]}-{r[-1]}" if len(r) > 2 else ",".join(map(str, r)) for r in runs)


def _span(values: np.ndarray) -> tuple[float, float]:
    """_extent of ``values``, a width of one where they are all equal (a colour scale)."""
    lo, hi = _extent(values)
    return (lo, hi) if hi > lo else (lo - 0.5, hi + 0.5)


def _try_kind(value: str) -> FollowerKind | None:
    try:
        return FollowerKind(value)
    except ValueError:
        return None


def _label(kind: str) -> str:
    k = _try_kind(kind)
    return k.label if k is not None else kind or "design"


# the map's outcomes in a fixed order: each has its own colour in every sweep (a review:
# red had meant another limit from one run to the next)
OUTCOMES = (_OK, "not a design", *CODES, "invalid")


def _outcome_rank(cause: str) -> int:
    return OUTCOMES.index(cause) if cause in OUTCOMES else len(OUTCOMES)


def _colour(cause: str) -> tuple[float, ...]:
    """A cause's colour: green for valid, grey for no design at all, the limits from
    matplotlib's tab20 (its strong colours first, greens and greys left out) and
    tab20b, black for anything else."""
    from matplotlib import colormaps

    if cause == _OK:
        return (0.17, 0.63, 0.17)
    if cause == "not a design":
        return (0.62, 0.62, 0.62)
    tab20, tab20b = colormaps["tab20"], colormaps["tab20b"]  # (20 colours each)
    strong = [tab20(i)[:3] for i in range(0, 20, 2) if i not in (4, 14)]  # the first
    light = [tab20(i)[:3] for i in range(1, 20, 2) if i not in (5, 15)]  # limits: strong
    palette = strong + light + [tab20b(i)[:3] for i in (0, 8, 12, 16, 2)]  # (4: olive)
    i = _outcome_rank(cause) - 2
    return tuple(palette[i]) if 0 <= i < len(palette) else (0.0, 0.0, 0.0)


def _patch(colour, label: str):
    from matplotlib.patches import Patch

    return Patch(color=colour, label=label)
