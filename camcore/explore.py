"""Design-space exploration over sweep rows (camcore.sweep): the figures a designer
trades against each other, the Pareto front of chosen figures among the valid
designs, and the map that shows which limit fails where.

Rows are ``camcore.sweep.row`` dicts (the flattened ``report --json`` summary plus
``grid.<path>`` values), so whatever the sweep ran on (this process, a Dask cluster,
the app's background worker) the exploration reads the same table.
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .model import PAPER_FOLLOWERS, FollowerKind
from .sweep import first_violation, pareto_mask


@dataclass(frozen=True)
class Figure:
    """A figure of merit of a design, read from a sweep row (smaller is better)."""

    label: str
    unit: str
    get: Callable[[dict], float | None]


def _key(name: str) -> Callable[[dict], float | None]:
    return lambda r: r.get(name)


def _max_of(*names: str) -> Callable[[dict], float | None]:
    def get(r: dict) -> float | None:
        vals = [r.get(n) for n in names]
        return None if any(v is None for v in vals) else max(vals)  # type: ignore[type-var]

    return get


FIGURES: dict[str, Figure] = {
    "cam_size": Figure("cam size R (high-dwell radius)", "mm", _key("dwell_radius_mm")),
    "stress": Figure("max contact stress σ_H", "MPa", _key("contact_stress_max_MPa.cycle")),
    "pressure_angle": Figure(
        "max pressure angle",
        "°",
        _max_of("pressure_angle_max_deg.rise", "pressure_angle_max_deg.fall"),
    ),
    "force": Figure("max contact force F_N", "N", _key("contact_force_max_N.cycle")),
    "torque": Figure("peak driving torque", "N m", _key("cam_torque_max_Nm.drive")),
    "wear": Figure("max wear depth", "µm/10⁶ cycles", _key("wear_depth_max_um_per_Mcycle")),
}


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
            sorted((k, repr(v)) for k, v in r.items() if k.startswith("grid.") and k not in drop)
        )
        j = kept.get(key)
        # an ignored field is still checked against its own limits (a roller radius of 0
        # for a concave face): a row refused for it must not hide a valid copy
        if j is None or (rows[j].get("error") is not None and r.get("error") is None):
            kept[key] = i
    out = np.zeros(len(rows), dtype=bool)
    out[list(kept.values())] = True
    return out


def pareto(rows: list[dict], names: list[str]) -> np.ndarray:
    """Indices of the valid rows on the Pareto front of FIGURES[names] (all minimized),
    ordered by the first figure; a design swept several times (``distinct``) once."""
    v = figure_values(rows, names)
    valid = np.array([bool(r.get("valid")) for r in rows], dtype=bool)
    v[~(valid & distinct(rows))] = np.nan
    idx = np.flatnonzero(pareto_mask(v))
    return idx[np.argsort(v[idx, 0], kind="stable")]


# --- the map ------------------------------------------------------------------------

_OK = "valid"
_MARKERS: dict[FollowerKind | None, str] = dict(zip(PAPER_FOLLOWERS, "os^D", strict=True))


def _kind(r: dict) -> str:
    return str(r.get("grid.follower.kind") or r.get("follower") or "")


def explore_png(
    rows: list[dict],
    x: tuple[str, str],
    y: tuple[str, str],
    names: list[str],
    front: np.ndarray,
    width_px: int = 760,
    limits: tuple[tuple[float, float], tuple[float, float]] | None = None,
) -> bytes:
    """The exploration as one PNG (explore_figure)."""
    fig = explore_figure(rows, x, y, names, front, width_px, limits)
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def _limits(values) -> tuple[float, float]:
    """An axis' limits around the finite ``values``, with a margin for the markers."""
    values = np.asarray(values, dtype=float)
    v = values[np.isfinite(values)]
    lo, hi = (float(v.min()), float(v.max())) if v.size else (0.0, 1.0)
    pad = 0.05 * (hi - lo) if hi > lo else 0.5 * abs(lo) or 1.0
    return lo - pad, hi + pad


def explore_figure(
    rows: list[dict],
    x: tuple[str, str],
    y: tuple[str, str],
    names: list[str],
    front: np.ndarray,
    width_px: int = 760,
    limits: tuple[tuple[float, float], tuple[float, float]] | None = None,
):
    """The exploration as a matplotlib Figure: per follower kind, the (x, y) grid
    coloured by the first limit each design breaks (green: valid), all on the same axes:
    ``limits`` ((x0, x1), (y0, y1)), the sweep's ranges, else those of the rows (a
    sweep cancelled midway leaves a kind part of the range, which must not look like
    the whole); below, the valid designs in the plane of the first two figures with the
    Pareto front numbered (the numbers of the app's list). ``x`` and ``y`` are (grid
    path, axis label)."""
    from matplotlib.figure import Figure as MplFigure

    kinds = list(dict.fromkeys(_kind(r) for r in rows))
    causes = [first_violation(r) or _OK for r in rows]
    legend = [_OK] + sorted({c for c in causes if c != _OK})
    cmap = {c: _colour(i) for i, c in enumerate(legend)}
    n = max(1, len(kinds))
    cols = min(n, 2)
    maps = math.ceil(n / cols)
    fig = MplFigure(figsize=(width_px / 100, 3.0 * maps + 4.2), dpi=100, layout="constrained")
    grid = fig.add_gridspec(maps + 1, cols, height_ratios=[1.0] * maps + [1.35])
    xs = np.array([float(r.get(f"grid.{x[0]}", np.nan)) for r in rows])
    ys = np.array([float(r.get(f"grid.{y[0]}", np.nan)) for r in rows])
    for i, kind in enumerate(kinds):
        ax = fig.add_subplot(grid[i // cols, i % cols])
        m = np.array([_kind(r) == kind for r in rows])
        ax.scatter(
            xs[m],
            ys[m],
            c=[cmap[c] for c, k in zip(causes, m, strict=True) if k],
            marker="s",
            s=38,
            edgecolors="none",
        )
        unused = {p for r in rows if _kind(r) == kind for p in ignored_fields(r)}
        note = [axis for axis, (path, _) in zip("xy", (x, y), strict=True) if path in unused]
        title = _label(kind) + (f" (does not use {' or '.join(note)})" if note else "")
        ax.set_xlim(*_limits(xs if limits is None else limits[0]))
        ax.set_ylim(*_limits(ys if limits is None else limits[1]))
        ax.set_title(title, fontsize=12)
        ax.set_xlabel(x[1], fontsize=11)
        ax.set_ylabel(y[1], fontsize=11)
        ax.tick_params(labelsize=10)
    handles = [_patch(cmap[c], c) for c in legend]
    fig.legend(
        handles=handles,
        loc="outside upper center",
        ncols=min(4, len(handles)),
        fontsize=10,
        title="first limit broken",
        title_fontsize=10,
    )
    _pareto_panel(fig.add_subplot(grid[maps, :]), rows, names, front)
    return fig


def _pareto_panel(ax, rows: list[dict], names: list[str], front: np.ndarray) -> None:
    fa, fb = FIGURES[names[0]], FIGURES[names[1]]
    v = figure_values(rows, names[:2])
    valid = np.array([bool(r.get("valid")) for r in rows])
    for kind in dict.fromkeys(_kind(r) for r in rows):
        m = valid & np.array([_kind(r) == kind for r in rows])
        ax.scatter(
            v[m, 0],
            v[m, 1],
            s=14,
            alpha=0.55,
            label=_label(kind),
            marker=_MARKERS.get(_try_kind(kind), "o"),
        )
    if front.size:
        ax.plot(v[front, 0], v[front, 1], "k-", lw=0.8, alpha=0.6)
        span = np.nanmax(v[front], axis=0) - np.nanmin(v[front], axis=0)
        span = np.where(span > 0, span, 1.0)
        shown: list[np.ndarray] = []  # numbers closer than 4 % of the front's extent
        for n, i in enumerate(front[:30], start=1):  # would print over each other
            at = v[i, :2] / span
            if any(np.hypot(*(at - p)) < 0.04 for p in shown):
                continue
            shown.append(at)
            ax.annotate(
                str(n), (v[i, 0], v[i, 1]), fontsize=10, xytext=(3, 3), textcoords="offset points"
            )
    ax.set_xlabel(f"{fa.label} [{fa.unit}]", fontsize=11)
    ax.set_ylabel(f"{fb.label} [{fb.unit}]", fontsize=11)
    ax.set_title(
        "valid designs; the numbered line is the Pareto front (smaller is better)", fontsize=12
    )
    ax.tick_params(labelsize=10)
    if valid.any():
        ax.legend(fontsize=10)


def _try_kind(value: str) -> FollowerKind | None:
    try:
        return FollowerKind(value)
    except ValueError:
        return None


def _label(kind: str) -> str:
    k = _try_kind(kind)
    return k.label if k is not None else kind or "design"


def _colour(i: int) -> tuple[float, float, float]:
    palette = [
        (0.17, 0.63, 0.17),
        (0.84, 0.15, 0.16),
        (1.0, 0.5, 0.05),
        (0.58, 0.4, 0.74),
        (0.55, 0.34, 0.29),
        (0.89, 0.47, 0.76),
        (0.5, 0.5, 0.5),
        (0.74, 0.74, 0.13),
        (0.09, 0.75, 0.81),
        (0.12, 0.47, 0.71),
    ]
    return palette[i % len(palette)]


def _patch(colour, label: str):
    from matplotlib.patches import Patch

    return Patch(color=colour, label=label)
