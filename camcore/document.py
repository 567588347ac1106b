"""The printable design report: one self-contained HTML page (or a PDF) with the key
numbers, the broken limits and the curves, for a designer to file or send.

The plots are drawn with matplotlib's object API (``matplotlib.figure.Figure``, no
pyplot and no global state, so it is safe in the app's worker threads) and embedded as
inline SVG: the page needs no other file and no network. Every string that comes from
the user (the design name, violation messages that quote input) is HTML-escaped.
"""

from __future__ import annotations

import html
import io
from collections.abc import Iterator

import numpy as np

from . import profile
from .analysis import Analysis
from .checks import accepted_jumps
from .model import FollowerKind, edited_note
from .report import inputs_text, report_text, summary
from .units import to_deg, to_mm

CONTACT = "#ffc800"  # a contact point (app.scene.CONTACT_RGB)
MAX_POINTS = 1500  # per curve in the embedded plots: the page stays a few hundred kB


def _decimate(n: int) -> np.ndarray:
    return np.unique(np.linspace(0, n - 1, min(n, MAX_POINTS)).astype(int))


def _face_curves(a: Analysis, values: np.ndarray, scale: float) -> list[tuple[str, np.ndarray]]:
    """One curve per face, NaN where the face does not touch (so gaps show)."""
    names = ["S1 (rise face)", "S2 (fall face)"] if values.shape[0] == 2 else ["contact"]
    return [(n, np.where(a.in_contact[i], values[i] * scale, np.nan)) for i, n in enumerate(names)]


def _panels(a: Analysis) -> Iterator[tuple[str, str, list[tuple[str, np.ndarray]]]]:
    """(title, y label, [(legend, values over a.theta)]) for each plot."""
    p = a.prog
    yield "Displacement", "S [mm]", [("S", to_mm(p.S))]
    yield "Velocity", "V [mm/rad]", [("V", to_mm(p.V))]
    yield "Acceleration", "A [mm/rad^2]", [("A", to_mm(p.A))]
    yield "Jerk", "J [mm/rad^3]", [("J", to_mm(p.J))]
    yield "Pressure angle (Eqs. 5, 13)", "phi [deg]", _face_curves(a, a.pressure_angle, to_deg(1.0))
    yield "Radius of curvature (Eq. 21)", "rho [mm]", _face_curves(a, a.rho, to_mm(1.0))
    yield (
        "Forces (Eqs. 29-41)",
        "F [N]",
        [
            ("F_t total load", a.Ft),
            ("F1 guide", a.guide.F1),
            ("F2 guide", a.guide.F2),
            *_face_curves(a, a.FN, 1.0),
        ],
    )
    yield "Hertz contact stress (Eq. 42)", "sigma [MPa]", _face_curves(a, a.stress, 1e-6)


def _limit_lines(a: Analysis) -> dict[str, list[tuple[float, str]]]:
    """Per plot title, the limits drawn on it as (value, legend): the pressure angle's
    +-limit and the stress the design may reach (allowable / safety factor), as the
    app's curves draw them (a designer's review: the report's plots had none)."""
    from .model import allowable_contact_stress_MPa

    lim = a.design.limits
    phi = lim.max_pressure_angle_deg
    out = {"Pressure angle (Eqs. 5, 13)": [(phi, f"limit +-{phi:g} deg"), (-phi, "")]}
    if np.isfinite(a.stress).any():  # (a knife edge has no Hertz stress to limit)
        sigma = allowable_contact_stress_MPa(a.design) / lim.contact_stress_safety_factor
        out["Hertz contact stress (Eq. 42)"] = [(sigma, f"limit {sigma:.4g} MPa")]
    return out


def _figure(a: Analysis):
    from matplotlib.figure import Figure

    panels = list(_panels(a))
    fig = Figure(figsize=(11, 2.4 * ((len(panels) + 1) // 2)), layout="constrained")
    axes = fig.subplots((len(panels) + 1) // 2, 2, sharex=True).ravel()
    k = _decimate(a.theta.size)
    th = to_deg(a.theta[k])
    limits = _limit_lines(a)
    for ax, (title, ylabel, curves) in zip(axes, panels, strict=False):
        for label, y in curves:
            ax.plot(th, y[k], lw=1.2, label=label)
        for value, label in limits.get(title, []):
            ax.axhline(value, color="#d62728", ls="--", lw=0.9, label=label or None)
        for s in to_deg(a.stations):
            ax.axvline(s, color="0.8", lw=0.6, zorder=0)
        ax.set_title(title, fontsize=10)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        if len(curves) > 1 or title in limits:
            ax.legend(fontsize=7, loc="best")
    for ax in axes[-2:]:
        ax.set_xlabel("cam angle theta [deg] (grey: stations)")
        ax.set_xlim(0, 360)
    for ax in axes[len(panels) :]:
        ax.set_visible(False)
    return fig


def _profile_figure(a: Analysis):
    from matplotlib.figure import Figure

    fig = Figure(figsize=(5, 5), layout="constrained")
    ax = fig.subplots()
    P = to_mm(a.profile.points)
    ax.fill(P[:, 0], P[:, 1], color="#c8d4e6", ec="#28508c", lw=1)
    t = np.linspace(0, 2 * np.pi, 361)
    rb = to_mm(a.geo.r_b)
    ax.plot(rb * np.cos(t), rb * np.sin(t), ls="--", lw=0.7, color="0.5", label="base circle")
    ax.plot([0], [0], "k+")
    ax.set_aspect("equal")
    ax.set_title("Cam profile as made (cam frame, mm)", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    return fig


CAM_FILL, CAM_EDGE, FOLLOWER = "#c8d4e6", "#28508c", "#cd6e1e"  # the stations' colours


def stations_figure(a: Analysis, width_in: float = 11.0, cols: int = 3):
    """The paper's Fig. 4 for this design: the mechanism at each station side by side,
    zoomed on the contact region, with the contact points of the faces touching at the
    station filled and labelled (open where a face is near but not touching) and what
    happens there in words.

    A face touches at a station if it touches just before or just after it: at station
    0 of the paper's program S2 leaves as S1 takes over, and both touch (a teacher's
    review found S2 drawn open there, as the state just after the station was drawn).

    Each panel has an inset of the whole cam at the station's angle, with its axis (+),
    its theta = 0 datum (the cam frame's +Y ray), the follower's line of travel and the
    panel's crop as a box: a teacher's review found that a crop alone does not show where
    the cam is in its turn. It sits in a bottom corner, on the cam's fill, on the side
    away from the contact points, where no face, contact point or label is drawn.
    """
    from matplotlib.figure import Figure

    from .report import summary

    events = [st["event"] for st in summary(a)["stations"]]
    n = len(a.stations)
    cols = min(n, cols)
    rows = -(-n // cols)
    fig = Figure(figsize=(width_in, 0.8 * rows * width_in / cols), layout="constrained")
    # room below the last captions: the app's full-size icon sits on the bottom-right
    # corner of the image and had covered station 5's words (a review)
    fig.supxlabel(" ", fontsize=22)  # (an empty line the layout keeps room for)
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    P = a.profile.points
    rb = a.geo.r_b
    t = np.linspace(0, 2 * np.pi, 721)
    for ax in axes[n:]:
        ax.set_axis_off()
    at = a.local(np.mod(a.stations, 2 * np.pi))
    n_st = a.stations.size
    near = a.local(np.mod(np.concatenate([a.stations - 1e-7, a.stations + 1e-7]), 2 * np.pi))
    touching = near.in_contact[:, :n_st] | near.in_contact[:, n_st:]
    loads = station_loads(a, near)
    # the insets' Y range [mm], one for all panels: the whole cam below, the highest
    # panel's crop above (the crop's top is r_b + S + 0.2 r_b, as set below)
    r_max = to_mm(float(np.max(np.hypot(P[:, 0], P[:, 1]))))
    top = max(r_max, to_mm(rb + float(np.max(at.prog.S)) + 0.2 * rb))
    frame = (-1.05 * r_max, 1.12 * top)
    # the crops' middle: the contact points' mean X over the stations, the same for all
    # panels (the axis for a symmetric follower; a single follower set off 30 mm had
    # its roller at the crop's edge, and one set off further would have left it)
    mid = to_mm(float(np.mean(at.point_world[..., 0])))
    # the inset's corner: the right one, unless the contact points lie right of the
    # axis (a single follower's offset; a concave face's contact is on the side away
    # from its stem): then the cam's low side, under the inset, is on the left
    left = bool(mid > to_mm(0.05 * rb))
    for k, (ax, th) in enumerate(zip(axes, a.stations, strict=False)):
        c, s_ = np.cos(th), np.sin(th)
        X, Y = c * P[:, 0] + s_ * P[:, 1], -s_ * P[:, 0] + c * P[:, 1]  # R(-theta), Eq. 11
        ax.fill(to_mm(X), to_mm(Y), color=CAM_FILL, ec=CAM_EDGE, lw=1)
        S = float(at.prog.S[k])
        for i, f in enumerate(a.geo.faces):
            yc = a.geo.y0 + S
            if a.geo.flat:
                ax.plot(
                    to_mm(np.array([-0.6, 0.6]) * rb),
                    to_mm(np.array([yc, yc])),
                    color=FOLLOWER,
                    lw=2,
                )
            p = at.point_world[i, k]
            if not a.geo.flat and f.r != 0:  # the face near its contact, not its whole circle
                near = np.abs(f.x_c + abs(f.r) * np.cos(t) - p[0]) < 0.22 * rb
                arc = np.where(near & (np.sign(np.sin(t)) == np.sign(p[1] - yc)), 1.0, np.nan)
                ax.plot(
                    to_mm(f.x_c + abs(f.r) * np.cos(t) * arc),
                    to_mm(yc + abs(f.r) * np.sin(t) * arc),
                    color=FOLLOWER,
                    lw=2,
                )
            on = bool(touching[i, k])
            ax.plot(  # gold, as the app's 3D view: there red marks a broken limit
                to_mm(p[0]), to_mm(p[1]), "o", ms=7, mfc=CONTACT if on else "white", mec="#7a5c00"
            )
            ax.annotate(
                f.name.split(" ")[0],  # "S1", "S2": the names the app and the report use
                (to_mm(p[0]), to_mm(p[1])),
                xytext=(0, -14),
                textcoords="offset points",
                ha="center",
                fontsize=9,
                color="#5a4400" if on else "#888888",
                fontweight="bold" if on else "normal",
            )
        y = to_mm(rb + S)
        ax.set_xlim(mid - 0.45 * to_mm(rb), mid + 0.45 * to_mm(rb))
        ax.set_ylim(y - 0.25 * to_mm(rb), y + 0.2 * to_mm(rb))
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        # the lift too: the crops follow the contacts, so S = 0 and S = h look alike
        ax.set_title(f"station {k}: θ = {to_deg(th):.1f}°, S = {to_mm(S):.2f} mm", fontsize=11)
        text = events[k].split(": ", 1)[-1]
        ax.set_xlabel(f"{text}\n{loads[k]}", fontsize=9.5, wrap=True)
        _whole_cam_inset(ax, a, float(th), frame, left=left)
    return fig


def station_loads(a: Analysis, near) -> list[str]:
    """Per station, each touching face's contact force F_N (Eqs. 29-41) and Hertz
    stress (Eq. 42) just before -> just after it, one value where they agree: what a
    class reads off the diagram (a teacher's review asked for the numbers of the
    transitions: at the paper's station 2, S2 takes half of S1's load).

    ``near``: a.local at the stations less, then plus, 1e-7 rad (stations_figure's).
    """
    n = a.stations.size
    out = []
    for k in range(n):
        parts = []
        for i, f in enumerate(a.geo.faces):
            if not (near.in_contact[i, k] or near.in_contact[i, n + k]):
                continue
            fn = _before_after(near.FN[i, k], near.FN[i, n + k], 1.0, "N")
            if min(near.FN[i, k], near.FN[i, n + k]) < 0:  # (the jump check's Eq. 29 sign)
                fn += " (< 0: the follower leaves the cam)"
            sigma = _before_after(near.stress[i, k], near.stress[i, n + k], 1e-6, "MPa")
            name = f.name.split(" ")[0] + ": " if len(a.geo.faces) == 2 else ""
            parts.append(f"{name}F_N {fn}, σ_H {sigma}")
        out.append("\n".join(parts))  # a line per face: a wrap had cut one mid-figure
    return out


def _before_after(before: float, after: float, scale: float, unit: str) -> str:
    """One value with its unit ('98.0 N'), or two ('196.0 → 98.0 N') where they print
    apart; to 0.1, as the app's status line prints F_N (a review compared them)."""
    b, a = f"{before * scale:.1f}", f"{after * scale:.1f}"  # (as the app's status line)
    return f"{a} {unit}" if a == b else f"{b} → {a} {unit}"


def _whole_cam_inset(ax, a: Analysis, th: float, frame: tuple[float, float], left: bool) -> None:
    """The whole cam at angle ``th`` in a bottom corner of a station panel ``ax``: its
    outline turned as the panel's (Eq. 11), its axis (+), its theta = 0 datum (the cam
    frame's +Y ray, a line from the axis to the rim), the follower's line of travel
    (X = stem_x, upward from the crop's middle) and the panel's crop as a box.

    ``frame`` = (bottom, top) of the inset's Y range [mm], the same for every station so
    the cam keeps its size and place from panel to panel while it turns.
    """
    from matplotlib.patches import Rectangle

    P = a.profile.points
    c, s_ = np.cos(th), np.sin(th)
    X, Y = to_mm(c * P[:, 0] + s_ * P[:, 1]), to_mm(-s_ * P[:, 0] + c * P[:, 1])
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    # the panel's box is (y1 - y0) : (x1 - x0) tall (equal aspect): a square inset is
    # h tall and h * that ratio wide, in the panel's axes fraction; flush with the
    # corner, so no sliver of the panel's cam shows beside it
    h = 0.48
    w = h * (y1 - y0) / (x1 - x0)
    ins = ax.inset_axes([0.0 if left else 1.0 - w, 0.0, w, h])
    ins.fill(X, Y, color=CAM_FILL, ec=CAM_EDGE, lw=0.8, label="cam")
    ins.plot(0, 0, "+", ms=6, mew=1, color="#222222", label="cam axis")
    # the datum: where the cam frame's +Y ray meets the profile, turned with the cam
    r0 = profile.datum_radius(P)
    tip = to_mm(np.array([s_ * r0, c * r0]))
    ins.plot([0, tip[0]], [0, tip[1]], color=CAM_EDGE, lw=1.3, label="θ = 0")
    ins.plot(*tip, "o", ms=3, color=CAM_EDGE)
    # the label beside the datum line, on its lower side (the crop's box and the
    # follower's line are above the cam), its centre as far off the line as its half
    # size that way and 3 points more (the label is about 13 x 7 points)
    side = np.array([c, -s_] if -s_ <= 0 else [-c, s_])
    off = (3 + 6.5 * abs(side[0]) + 3.5 * abs(side[1])) * side
    ins.annotate(
        "θ=0",
        tuple(0.4 * tip),
        xytext=tuple(off),
        textcoords="offset points",
        ha="center",
        va="center",
        fontsize=6.5,
        color=CAM_EDGE,
    )
    # the way the cam turns (clockwise, as in the paper), in the inset's free corner
    ins.text(0.05, 0.95, "↻", transform=ins.transAxes, ha="left", va="top", fontsize=10)
    stem = to_mm(a.geo.stem_x)
    ins.plot([stem, stem], [0.5 * (y0 + y1), frame[1]], color=FOLLOWER, lw=1.2, label="travel")
    ins.add_patch(
        Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="#222222", lw=0.8, label="crop")
    )
    half = 0.5 * (frame[1] - frame[0])
    ins.set_xlim(-half, half)
    ins.set_ylim(*frame)
    ins.set_aspect("equal")
    ins.set_xticks([])
    ins.set_yticks([])
    for spine in ins.spines.values():
        spine.set_color("#888888")


def stations_png(a: Analysis, width_px: int = 1100) -> bytes:
    """stations_figure as PNG bytes (100 dpi)."""
    fig = stations_figure(a, width_in=width_px / 100)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def stations_image(a: Analysis, width_px: int = 1200) -> np.ndarray:
    """stations_figure as an (H, W, 3) uint8 array, three panels a row: drawn for the
    app's full-size view, to project (a teacher's review: 700 px wide in two columns,
    it needed scrolling on a 1280 x 720 projector; up to six stations now fit). In the
    narrow side panel it is smaller than before: full size or the wide panel reads it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = stations_figure(a, width_in=width_px / 100, cols=3)
    canvas = FigureCanvasAgg(fig)
    fig.set_dpi(100)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _svg(fig) -> str:
    buf = io.StringIO()
    fig.savefig(buf, format="svg")
    text = buf.getvalue()
    return text[text.index("<svg") :]  # drop the XML prolog and doctype: inline SVG


def html_report(a: Analysis) -> str:
    """The report of one analysis as a self-contained HTML document."""
    s = summary(a)
    esc = html.escape
    verdict = (
        "<p class=ok>All limits met.</p>"
        if s["valid"]
        else "<ul class=bad>"
        + "".join(
            f"<li><b>{esc(v['equation'])}</b> ({esc(v['code'])}): {esc(v['message'])}</li>"
            for v in s["violations"]
        )
        + "</ul>"
    )
    if (accepted := accepted_jumps(a.design)) is not None:  # said, not passed over
        verdict += f"<p>{esc(accepted)}</p>"
    kind = FollowerKind(s["follower"]).label  # (in words: a review read "double_concave")
    edited = edited_note(a.design)
    edited_html = f" ({esc(edited)})" if edited else ""
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>Cam design report: {esc(s["design"])}{edited_html}</title>
<style>
body {{ font-family: system-ui, sans-serif; margin: 2em auto; max-width: 60em; color: #222; }}
pre {{ background: #f6f7f9; padding: 1em; font-size: 0.85em; white-space: pre-wrap;
  overflow-wrap: anywhere; }}
.ok {{ color: #17692e; font-weight: bold; }} .bad {{ color: #a11; }}
svg {{ max-width: 100%; height: auto; }}
@media print {{ body {{ margin: 0; }} }}
</style></head><body>
<h1>Cam design report</h1>
<p><b>Design:</b> {esc(s["design"])}{edited_html} &nbsp; <b>Follower:</b> {esc(kind)}</p>
<h2>Verdict</h2>
{verdict}
<h2>Inputs</h2>
<pre>{esc(inputs_text(a.design))}</pre>
<h2>Key numbers</h2>
<pre>{esc(report_text(s))}</pre>
<h2>Curves</h2>
{_svg(_figure(a))}
<h2>Profile</h2>
{_svg(_profile_figure(a))}
<h2>Stations (the paper's Fig. 4 for this design)</h2>
{_svg(stations_figure(a))}
<p><small>Method: Chuang, Hsu &amp; Chang, disk cams with a translating follower having
symmetrical double-concave faces (Eqs. 1-42). Generated by camcore.</small></p>
</body></html>
"""


A4_IN = (8.27, 11.69)  # portrait [in]


def pdf_report(a: Analysis) -> bytes:
    """The same report as a PDF: a page of key numbers, then the curves and the profile."""
    from matplotlib.backends.backend_pdf import PdfPages
    from matplotlib.figure import Figure

    s = summary(a)
    text = report_text(s, a.design)
    edited = edited_note(a.design)
    title = s["design"] + (f" ({edited})" if edited else "")
    if not s["valid"]:
        text += "\n\nThe design breaks the limits listed above (lines starting with '!')."
    page = Figure(figsize=A4_IN)
    page.text(0.06, 0.96, "Cam design report", fontsize=16, va="top")
    # "$" escaped: matplotlib reads $...$ as math, even with parse_math=False when it
    # wraps, and a name such as "a $\foo$ b" (user input) had made the PDF fail
    page.text(
        0.06, 0.92, text.replace("$", r"\$"), family="monospace", fontsize=7, va="top", wrap=True
    )
    buf = io.BytesIO()
    with PdfPages(
        buf, metadata={"Title": f"Cam design report: {title}", "Creator": "camcore"}
    ) as pdf:
        for fig in (page, _figure(a), _profile_figure(a), stations_figure(a)):
            w, h = fig.get_size_inches()  # every page A4, a wide figure's turned
            fig.set_size_inches(A4_IN[::-1] if w > h else A4_IN)
            pdf.savefig(fig)
    return buf.getvalue()
