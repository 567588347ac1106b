"""Live curves (uPlot) of one tab: motion, pressure angle, curvature, forces, stress.

Every plot has the cam angle [deg] on x, units on every axis, a vertical marker
at the current cam angle (two extra x samples at that angle carry the marker
series) and, where a design limit is broken, red shading over those angles; the
force and stress plots shade in gold where both faces of a double follower touch.

What each curve shows is a function of the analysis (``curve_specs``); the values are
computed with the analysis, in the worker (``curve_data``, via app.analyst), so the
server only hands arrays to the widgets (``Curve.show``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from camcore import machine, motion, train, wear
from camcore.checks import rho_reference_mm, violation_mask
from camcore.model import contact_stress_limit_MPa, omega_rad_s
from camcore.units import to_mm, to_mpa, to_um_per_mcycle

MAX_POINTS = 720
X_AXIS = {"label": "cam angle θ [°]", "size": 36}
RED_FILL = "rgba(220,20,30,0.18)"
SHARED_FILL = "rgba(230,160,0,0.3)"  # gold, as the contact points (0.16 was faint projected)
SHARED_LABEL = "both faces touch"
NONE = "rgba(0,0,0,0)"
MARK = "rgba(0,0,0,0.55)"
STATION_MARK = "rgba(90,90,90,0.45)"  # dashed: where the contacts change
STATION_LABEL_DEG = 15.0  # stations nearer than this: numbers on two rows (~12 px)
STATION_SAME_DEG = 0.5  # stations nearer than this share one number ("1,2")
COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b")


def wire(columns, flags: int = 0) -> tuple[np.ndarray, ...]:
    """Plot columns as the client gets them: float32 (app.viser_speedups keeps it),
    half the bytes of float64 and 7 significant digits, more than a plot shows; the
    last ``flags`` columns (the shading's 0/1, the lines' -1/2 spikes: small integers)
    as int8, a quarter of float32's bytes (viser sends arrays uncompressed: these
    columns were ~40 % of what a redraw, or a marker step while playing, sends)."""
    n = len(columns) - flags
    return tuple(
        np.asarray(c, dtype=np.float32) if i < n else np.rint(c).astype(np.int8)
        for i, c in enumerate(columns)
    )


def stride_index(n: int, max_points: int = MAX_POINTS) -> np.ndarray:
    step = max(1, int(np.ceil(n / max_points)))
    idx = np.arange(0, n, step)
    return idx if idx[-1] == n - 1 else np.append(idx, n - 1)


class Curve:
    """One uPlot: series (label, unit-scale, colour; values from curve_data), marker,
    shading."""

    def __init__(
        self,
        gui,
        title: str,
        axes: list[tuple[str, str]],
        series: list[dict],
        height: int = 190,
        shading: bool = True,
        shared: bool = False,
    ):
        """``shading``: a series that shades where a limit is broken (False: none,
        ``show``'s shade is then ignored); ``shared``: one that shades where both faces
        of a double follower touch (the load shared, Eqs. 36-38)."""
        self.gui, self.title = gui, title
        self.shading, self.shared_band = shading, shared
        ser: list[dict[str, Any]] = [{"label": "θ [°]"}]
        for s in series:
            cfg: dict[str, Any] = {
                "label": s["label"],
                "scale": s["scale"],
                "stroke": s["stroke"],
                "width": s.get("width", 1.5),
            }
            for key in ("dash", "show"):
                if key in s:
                    cfg[key] = s[key]
            ser.append(cfg)
        # shading and marker live on their own fixed [0, 1] scales (no axis): they never
        # disturb the auto-range of the curves
        if shared:  # (a teacher's review: where the load is shared, at a glance)
            ser.append(
                {
                    "label": SHARED_LABEL,
                    "scale": "shade",
                    "stroke": NONE,
                    "fill": SHARED_FILL,
                    "width": 0,
                    "points": {"show": False},
                }
            )
        if shading:
            ser.append(
                {
                    "label": "limit broken",
                    "scale": "shade",
                    "stroke": NONE,
                    "fill": RED_FILL,
                    "width": 0,
                    "points": {"show": False},
                }
            )
        ser.append(  # the stations (the paper's Fig. 4): where the contacts change
            {
                "label": "stations",
                "scale": "marker",
                "stroke": STATION_MARK,
                "width": 1,
                "dash": [4, 4],
                "points": {"show": False},
            }
        )
        ser.append(
            {
                "label": "θ now",
                "scale": "marker",
                "stroke": MARK,
                "width": 1.5,
                "points": {"show": False},
            }
        )
        ax = [X_AXIS]
        for j, (scale, label) in enumerate(axes):
            # ticks 20 px apart at least, not uPlot's 30: on a plot ~95 px high that
            # left one tick ("0" of J, "50" of F_t: a designer's review could not read
            # the scale)
            side = 3 if j == 0 else 1
            ax.append({"scale": scale, "label": label, "side": side, "size": 52, "space": 20})
        scales = {
            "x": {"time": False, "range": (0.0, 360.0)},
            "shade": {"auto": False, "range": (0.0, 1.0)},
            "marker": {"auto": False, "range": (0.0, 1.0)},
        }
        for scale, _ in axes:
            scales[scale] = {"auto": True}
        self._scales = scales
        self._axes = ax  # (the stations' numbers are added above them: station_axes)
        self._scale_of = [s["scale"] for s in series]  # per data series: its axis
        self._aligned = len(axes) > 1  # two or three y axes: one level for their zeros
        self.nser = len(ser)
        self.handle = gui.add_uplot(
            tuple(np.zeros(2) for _ in ser),
            tuple(ser),
            title=title,
            scales=scales,
            axes=tuple(ax),
            height=height,
            legend={"show": True, "live": False},
            cursor={"drag": {"x": False, "y": False}},
        )
        self.x: np.ndarray | None = None
        self.ys: list[np.ndarray] = []
        self.shade = np.zeros(0)
        self.shared = np.zeros(0)  # 1.0 where both faces touch (shared=True)
        self.stations = np.zeros(0)  # [deg]
        self._at = float("nan")  # the marker's cam angle [deg]

    def show(
        self,
        x: np.ndarray,
        ys: tuple[np.ndarray, ...],
        shade: np.ndarray,
        at: float,
        stations: np.ndarray | None = None,
        shared: np.ndarray | None = None,
    ):
        """New curves (from curve_data) with the marker at cam angle ``at`` [deg],
        dashed lines at the ``stations`` [deg] and, for a plot made with ``shared``,
        the angles where both faces touch shaded (``shared``, 1.0 there). Curves that
        did not change (S after a new speed, say) are not sent again: the data of all
        plots is most of what a redraw sends."""
        stations = np.zeros(0) if stations is None else stations
        shared = np.zeros_like(x) if shared is None else shared
        same = (
            self.x is not None
            and self._at == at
            and np.array_equal(x, self.x)
            and np.array_equal(stations, self.stations)
            and np.array_equal(shade, self.shade)
            and np.array_equal(shared, self.shared)
            and len(ys) == len(self.ys)
            and all(np.array_equal(u, v, equal_nan=True) for u, v in zip(ys, self.ys, strict=True))
        )
        if same:
            return
        if not np.array_equal(stations, self.stations):  # (numbers gone with the lines)
            numbers = station_axes(stations) if stations.size else ()
            self.handle.axes = (*self._axes, *numbers)
        self.x, self.ys, self.shade, self.stations = x, list(ys), shade, stations
        self.shared = shared
        if self._aligned:
            self._align_zeros()
        self.marker(at)

    def _align_zeros(self) -> None:
        """Ranges for the y axes that put their zeros on one level (uPlot ranges each
        axis alone: a teacher's review read A and J as non-zero in the dwells, their
        zero a few pixels off V's)."""
        spans = {}
        for scale in dict.fromkeys(self._scale_of):
            vals = [y for y, s in zip(self.ys, self._scale_of, strict=True) if s == scale]
            v = np.concatenate(vals) if vals else np.zeros(1)
            v = v[np.isfinite(v)]
            hi = max(float(v.max()), 0.0) if v.size else 1.0
            lo = min(float(v.min()), 0.0) if v.size else 0.0
            spans[scale] = (lo, hi) if hi > lo else (-1.0, 1.0)
        scales = dict(self._scales)
        for scale, (lo, hi) in zero_aligned(spans).items():
            scales[scale] = {"auto": False, "range": (lo, hi)}
        if scales != self.handle.scales:
            self.handle.scales = scales

    def marker(self, theta_deg: float) -> None:
        """Send the curves with the vertical lines: the stations and θ now."""
        if self.x is None:
            return
        self._at = theta_deg
        x = self.x
        # each line is a spike on its own [0, 1] scale: three samples at its angle,
        # below, above and below the plot area (a vertical line once clipped)
        at = np.concatenate([self.stations, [theta_deg]])
        xi = np.repeat(at, 3)
        order = np.argsort(np.concatenate([x, xi]), kind="stable")  # a spike's 3 stay together
        out = [np.concatenate([x, xi])[order]]
        columns = [*self.ys, *([self.shared] if self.shared_band else [])]
        columns += [self.shade] if self.shading else []
        for y in columns:
            out.append(np.concatenate([y, np.interp(xi, x, y)])[order])
        for first, last in ((0, self.stations.size), (self.stations.size, at.size)):
            mk = np.full(x.size + xi.size, -1.0)
            mk[x.size + 3 * np.arange(first, last) + 1] = 2.0
            out.append(mk[order])
        self.handle.data = wire(out, flags=len(out) - 1 - len(self.ys))


def station_axes(stations_deg: np.ndarray) -> tuple[dict, ...]:
    """Axes above the plot that number the dashed station lines (a teacher's review:
    the lines carried no numbers): uPlot's static ticks at the stations' angles [deg],
    labelled with their indices. Stations that coincide (within STATION_SAME_DEG: a
    single follower's) share one label ("1,2"); stations less than STATION_LABEL_DEG
    apart go on a second row above the first, each number over its own line (the
    paper's stations 1 and 2, 7.4 deg apart: a shared "1,2" between the lines could
    not tell the class which window is which, a later review)."""
    groups: list[list[tuple[int, float]]] = []
    for i, at in sorted(enumerate(map(float, stations_deg)), key=lambda p: p[1]):
        if groups and at - groups[-1][-1][1] < STATION_SAME_DEG:
            groups[-1].append((i, at))
        else:
            groups.append([(i, at)])
    rows: list[list[tuple[float, str]]] = [[], []]
    for g in groups:
        label = (sum(at for _, at in g) / len(g), ",".join(str(i) for i, _ in sorted(g)))
        free = [r for r in rows if not r or label[0] - r[-1][0] >= STATION_LABEL_DEG]
        if free:
            free[0].append(label)
        else:  # a third station within the distance: it joins the upper row's last
            at, text = rows[1][-1]
            rows[1][-1] = ((at + label[0]) / 2, f"{text},{label[1]}")
    return tuple(
        {
            "scale": "x",
            "side": 0,  # top (a second one stacks above the first)
            "size": 14,
            "gap": 1,
            "splits": [at for at, _ in row],
            "values": [text for _, text in row],
            "font": "11px sans-serif",
            "stroke": "#333333",
            "grid": {"show": False},
            "ticks": {"show": False},
        }
        for row in rows
        if row
    )


def zero_aligned(spans: dict[str, tuple[float, float]], pad: float = 0.05) -> dict:
    """Ranges (lo, hi) for axes with data spans (lo <= 0 <= hi, hi > lo) whose zeros sit
    at the same height: zero at the fraction f of the way up on every axis, f the mean
    of the spans' own (any f strictly between 0 and 1 holds every span: an axis all
    below zero gains room above it), each widened to hold its span, padded by ``pad``.
    """
    f = sum(-lo / (hi - lo) for lo, hi in spans.values()) / len(spans)
    out = {}
    for name, (lo, hi) in spans.items():
        total = max(-lo / f if f > 0 else 0.0, hi / (1 - f) if f < 1 else 0.0) * (1 + pad)
        out[name] = (-f * total, (1 - f) * total)
    return out


def _primary_deg(a):
    return np.degrees(a.primary(a.pressure_angle))


def _per_second(a):
    return motion.per_second(a.prog, omega_rad_s(a.design))


def _train_force(a) -> np.ndarray:
    """The elastic train's contact force on the analysis grid (the rigid load if none)."""
    if a.train is None:
        return a.Ft
    return train.on_grid(a.train, a.theta, a.train.contact_force)


@dataclass(frozen=True)
class CurveData:
    """What the Curves tab shows of one analysis, on the plots' strided angles."""

    x: np.ndarray  # cam angles [deg] (stride_index of the analysis grid)
    ys: tuple[tuple[np.ndarray, ...], ...]  # per curve, per series: its values on x
    shades: tuple[np.ndarray, ...]  # per curve: 1.0 where one of its limits is broken
    stations: np.ndarray = field(default_factory=lambda: np.zeros(0))  # [deg]
    shared: np.ndarray = field(default_factory=lambda: np.zeros(0))  # 1.0: both faces touch


def curve_data(a) -> CurveData:
    """The curves of ``a`` (a camcore.analysis.Analysis), as curve_specs defines them."""
    idx = stride_index(a.theta.size)
    x = np.degrees(a.theta[idx])
    specs = curve_specs(a)
    return CurveData(
        x,
        tuple(tuple(np.asarray(s["fn"](a), float)[idx] for s in c["series"]) for c in specs),
        tuple(violation_mask(a.violations, x, c["codes"]).astype(float) for c in specs),
        np.degrees(a.stations),
        (a.in_contact.sum(axis=0) >= 2)[idx].astype(float),
    )


def build_curves(gui, a) -> list[Curve]:
    """The plots of the Curves tab (empty until the first Curve.show)."""
    return [
        Curve(gui, c["title"], c["axes"], c["series"], shared=c["shared"]) for c in curve_specs(a)
    ]


def curve_specs(a) -> list[dict]:
    """Each plot: title, axes [(scale, label)], series [{label, scale, stroke, fn(a) ->
    values on the analysis grid, ...}] and the violation codes it shades."""
    lim = a.design.limits.max_pressure_angle_deg

    def rho_mm(a):
        r = to_mm(a.primary(a.rho))
        f = a.design.follower  # (a roller's concave flanks lie below -r_c: kept there,
        r_c = f.roller_radius_mm if f.kind.is_roller else 0.0  # not cut into its band)
        cap = max(3 * rho_reference_mm(a.design)[1], 2 * a.design.cam.base_radius_mm, 2 * r_c)
        return np.clip(np.nan_to_num(r, nan=cap, posinf=cap, neginf=-cap), -cap, cap)

    worn: list = [None, None]  # (analysis, wear of both faces): computed once per analysis

    def wear_um(a):
        if worn[0] is not a:
            worn[:] = [a, to_um_per_mcycle(wear.depth_per_pass(a))]
        return worn[1]

    def limit(a, which):
        v = rho_reference_mm(a.design)[1]
        return np.full(a.theta.size, v if which == "rho" else 0.0)

    return [
        _spec(
            "Displacement S",
            [("mm", "S [mm]")],
            [
                {
                    "label": "S [mm]",
                    "scale": "mm",
                    "stroke": COLORS[0],
                    "fn": lambda a: to_mm(a.prog.S),
                },
            ],
            codes=None,
        ),
        _spec(
            "Velocity V and acceleration A (per radian of cam angle)",
            [("V", "V [mm/rad]"), ("A", "A [mm/rad²]")],
            [
                {
                    "label": "V [mm/rad]",
                    "scale": "V",
                    "stroke": COLORS[1],
                    "fn": lambda a: to_mm(a.prog.V),
                },
                {
                    "label": "A [mm/rad²]",
                    "scale": "A",
                    "stroke": COLORS[2],
                    "fn": lambda a: to_mm(a.prog.A),
                },
            ],
            codes=set(),
        ),
        _spec(
            "Velocity, acceleration and jerk per second at the design speed",
            [("ms", "V [m/s]"), ("ms2", "A [m/s²]"), ("ms3", "J [m/s³]")],
            [
                {
                    "label": "V [m/s]",
                    "scale": "ms",
                    "stroke": COLORS[1],
                    "fn": lambda a: _per_second(a)[0],
                },
                {
                    "label": "A [m/s²]",
                    "scale": "ms2",
                    "stroke": COLORS[2],
                    "fn": lambda a: _per_second(a)[1],
                },
                {
                    "label": "J [m/s³]",
                    "scale": "ms3",
                    "stroke": COLORS[3],
                    "fn": lambda a: _per_second(a)[2],
                },
            ],
            codes={"velocity_jump", "acceleration_jump"},
        ),
        _spec(
            "Pressure angle φ (signed; the paper's φ is its size)",
            [("deg", "φ [°]")],
            [
                {"label": "φ [°]", "scale": "deg", "stroke": COLORS[0], "fn": _primary_deg},
                {
                    "label": f"+limit {lim:g}°",
                    "scale": "deg",
                    "stroke": "#d62728",
                    "dash": [6, 4],
                    "width": 1,
                    "fn": lambda a: np.full(a.theta.size, a.design.limits.max_pressure_angle_deg),
                },
                {
                    "label": "−limit",
                    "scale": "deg",
                    "stroke": "#d62728",
                    "dash": [6, 4],
                    "width": 1,
                    "fn": lambda a: np.full(a.theta.size, -a.design.limits.max_pressure_angle_deg),
                },
            ],
            codes={"pressure_angle"},
        ),
        _spec(
            "Radius of curvature ρ of the cam at the contact",
            [("mm", "ρ [mm]")],
            [
                {"label": "ρ [mm]", "scale": "mm", "stroke": COLORS[3], "fn": rho_mm},
                {
                    "label": rho_limit_label(a.design),
                    "scale": "mm",
                    "stroke": "#d62728",
                    "dash": [6, 4],
                    "width": 1,
                    "fn": lambda a: limit(a, "rho"),
                },
            ],
            codes={"curvature_convex", "curvature_face", "roller_undercut"},
        ),
        _spec(
            "Contact force F_N and guide forces F1, F2",
            [("N", "force [N]")],
            [
                {  # (a teacher's review: the status line says "per face", the curve did not)
                    "label": "F_N per contact [N]",
                    "scale": "N",
                    "stroke": COLORS[0],
                    "fn": lambda a: a.guide.FN,
                },
                {"label": "F1 [N]", "scale": "N", "stroke": COLORS[1], "fn": lambda a: a.guide.F1},
                {"label": "F2 [N]", "scale": "N", "stroke": COLORS[2], "fn": lambda a: a.guide.F2},
            ],
            codes={"jump", "guide_jam", "guide_overhang", "contact_lost"},
            shared=True,
        ),
        _spec(
            "Contact (Hertz) stress σ_H",
            [("MPa", "σ_H [MPa]")],
            [
                {
                    "label": "σ_H [MPa]",
                    "scale": "MPa",
                    "stroke": COLORS[4],
                    "fn": lambda a: to_mpa(a.stress.max(axis=0)),
                },
                {
                    "label": _stress_limit_label(a),
                    "scale": "MPa",
                    "stroke": "#d62728",
                    "dash": [6, 4],
                    "width": 1,
                    "show": _stress_limit_shown(a),
                    "fn": _stress_limit_line,
                },
            ],
            codes={"contact_stress", "jump"},
            shared=True,
        ),
        _spec(
            "Spring force and the force that keeps contact (jump where it wins)",
            [("N", "force [N]")],
            [
                {
                    "label": "spring k(S+s_p) [N]",
                    "scale": "N",
                    "stroke": COLORS[2],
                    "fn": lambda a: machine.spring_force(a.design, a.prog),
                },
                {
                    "label": "needed −(M(g+Aω²)+F_e) [N]",
                    "scale": "N",
                    "stroke": "#d62728",
                    "dash": [6, 4],
                    "fn": lambda a: -machine.spring_free_load(a.design, a.prog),
                },
            ],
            codes={"jump"},
        ),
        _spec(
            "Axial load: rigid F_t (Eq. 29) and elastic train F_c (set its stiffness in Dynamics)",
            [("N", "force [N]")],
            [
                {"label": "rigid F_t [N]", "scale": "N", "stroke": COLORS[0], "fn": lambda a: a.Ft},
                {  # dashed: on a rigid train it lies exactly on F_t, which must still show
                    "label": "elastic F_c [N]",
                    "scale": "N",
                    "stroke": COLORS[1],
                    "dash": [6, 4],
                    "fn": _train_force,
                },
            ],
            codes={"dynamic_jump"},
        ),
        _spec(
            "Shaft torque T (positive: the shaft drives)",
            [("Nm", "T [N·m]")],
            [
                {
                    "label": "T [N·m]",
                    "scale": "Nm",
                    "stroke": COLORS[0],
                    "fn": lambda a: a.torque.sum(axis=0),
                },
            ],
            codes=set(),
        ),
        _spec(
            "Cam wear per 10⁶ cycles (Archard): each face's passes, and the cam point's "
            "total (both faces; its peak is Key numbers' wear max)",
            [("um", "wear [µm]")],
            [
                {
                    "label": "total at the touched point [µm]",
                    "scale": "um",
                    "stroke": COLORS[0],
                    "fn": lambda a: to_um_per_mcycle(wear.total_at_contacts(a)),
                },
                {
                    "label": "S1 [µm]",
                    "scale": "um",
                    "stroke": COLORS[3],
                    "fn": lambda a: wear_um(a)[0],
                },
                {
                    "label": "S2 (double followers) [µm]",
                    "scale": "um",
                    "stroke": COLORS[4],
                    "fn": lambda a: wear_um(a)[-1] if a.FN.shape[0] == 2 else 0 * a.theta,
                },
            ],
            codes=set(),
        ),
    ]


def _spec(
    title: str, axes: list, series: list[dict], codes: set[str] | None, shared: bool = False
) -> dict:
    """``shared``: the plot shades where both faces touch (Curve's)."""
    return {"title": title, "axes": axes, "series": series, "codes": codes, "shared": shared}


LIMIT_IN_VIEW = 0.5  # a limit line is drawn once the curve reaches this share of it


def _stress_limit_shown(a) -> bool:
    """Whether the stress plot draws its limit: not while the stress stays far below
    it (the default concave cam's 52 MPa under an 800 MPa line filled 7 % of the
    plot's height, its shape flattened)."""
    top = np.nanmax(a.stress, initial=0.0) / 1e6
    return bool(top >= LIMIT_IN_VIEW * contact_stress_limit_MPa(a.design))


def _stress_limit_label(a) -> str:
    if a.design.follower.radius_mm == 0.0:
        return "no Hertz stress (knife edge)"
    far = "" if _stress_limit_shown(a) else " (far above: hidden)"
    return f"limit {contact_stress_limit_MPa(a.design):.4g} MPa{far}"


def rho_limit_label(design) -> str:
    """The legend of the ρ plot's limit line (checks.rho_reference_mm): a roller's
    says which side of it is wrong (undercut between -r_c and 0; a concave flank lies
    below -r_c)."""
    label, ref = rho_reference_mm(design)
    if design.follower.kind.is_roller:
        r_c = design.follower.roller_radius_mm
        return f"0 (limit: undercut for −{r_c:g} < ρ ≤ 0 mm)"
    return f"{label} = {ref:g} mm (limit)"


def _stress_limit_line(a) -> np.ndarray:
    # (hidden by the series' show flag, not by NaN: uPlot cannot range a scale with a
    # NaN series, and the whole plot went blank)
    return np.full(a.theta.size, contact_stress_limit_MPa(a.design))


def _show_shared(curves: list[Curve], double: bool) -> None:
    """The 'both faces touch' band in the legends of a double follower only (a single
    one has no second face: an entry that never shades would puzzle)."""
    for c in curves:
        if not c.shared_band:
            continue
        ser = list(c.handle.series)
        i = next(i for i, x in enumerate(ser) if x.get("label") == SHARED_LABEL)
        if ser[i].get("show", True) != double:
            ser[i] = {**ser[i], "show": double}
            c.handle.series = tuple(ser)


def relabel_limits(curves: list[Curve], a) -> None:
    """Legend labels that carry the current limit values."""
    lim = a.design.limits.max_pressure_angle_deg
    labels = {
        "Pressure angle": (2, f"+limit {lim:g}°"),
        "Radius of curvature": (2, rho_limit_label(a.design)),
        "Contact (Hertz) stress": (2, _stress_limit_label(a)),
    }
    shown = {"Contact (Hertz) stress": _stress_limit_shown(a)}  # (a far limit: hidden)
    _show_shared(curves, len(a.geo.faces) == 2)
    for title, (si, text) in labels.items():
        h = next(c for c in curves if c.title.startswith(title)).handle
        ser = list(h.series)
        want = {**ser[si], "label": text}
        if title in shown:
            want["show"] = shown[title]
        if ser[si] != want:
            ser[si] = want
            h.series = tuple(ser)
