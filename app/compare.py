"""The compare tab: the four followers on the current design (Table 1, Figs. 11, 13).

Shows what app.analyst.refined computed: per follower its summary and its contact
force and stress curves, or the reason it cannot be computed."""

from __future__ import annotations

import numpy as np

from camcore.model import PAPER_FOLLOWERS, Design
from camcore.report import paper_table1_N, unbounded_figures, unbounded_notes

from .panels import esc, largest_pressure_angle
from .plots import COLORS, Curve

KINDS = PAPER_FOLLOWERS  # the compare tab is the paper's Table 1


# what the table shows, in one plain paragraph above it (a teacher's review: a class
# read σ_H max cycle, 52.4 against 51.9 MPa, as "double does nothing")
WHY = (
    "**Why the faces win.** A concave face wraps around the cam: Eq. 42 takes "
    "1/ρ − 1/|r_f| for it against 1/ρ + 1/r_c for a roller, so at the same force its "
    "contact stress is far lower. A *double* follower adds the shared load: while both "
    "faces touch (in a dwell: in the paper's program between stations 2 and 3) each "
    "carries about half, which the *high dwell* rows show; elsewhere one face carries "
    "it all, so the cycle's maxima differ little from the single follower's."
)


def table_markdown(results: dict, design: Design) -> str:
    """The table of ``results`` (app.analyst.Refined.compare) for ``design``: a row per
    figure, a column per follower (a review: a column per figure ran out of the side
    panel); the paper's Table 1 row only where the design is the paper's example
    (report.paper_table1_N)."""

    def f(x, nd=2):
        return "–" if x is None else f"{x:.{nd}f}"

    def dwell(k, s: dict) -> float | None:
        fn = s["contact_force_max_N"]
        return fn["high_dwell_two_contact"] if k.is_double else fn["high_dwell"]

    def dwell_stress(k, s: dict) -> float | None:  # (where the paper's point shows)
        st = s["contact_stress_max_MPa"]
        return st["high_dwell_two_contact"] if k.is_double else st["high_dwell"]

    def bounded(s: dict, what: str, x: float | None, nd: int = 2) -> str:
        """A cycle maximum, or "unbounded²" where it has no bound (report's
        unbounded_figures, the key numbers' and the reports' rule; a review read
        2,004,164 MPa in the table unflagged)."""
        return "unbounded²" if what in unbounded_figures(s) else f(x, nd)

    table1 = {k: paper_table1_N(design, k) for k in results}
    rows = [  # (label, figure of a follower's summary)
        ("F_N high dwell [N]¹", lambda k, s: f(dwell(k, s), 3)),
        *(
            [("paper's Table 1 [N]", lambda k, s: f(table1[k], 3))]
            if any(v is not None for v in table1.values())
            else []
        ),
        ("σ_H high dwell [MPa]¹", lambda k, s: f(dwell_stress(k, s), 1)),
        ("F_N max cycle [N]", lambda k, s: bounded(s, "force", s["contact_force_max_N"]["cycle"])),
        (
            "σ_H max cycle [MPa]",
            lambda k, s: bounded(s, "stress", s["contact_stress_max_MPa"]["cycle"], 1),
        ),
        ("φ max [°]", lambda k, s: f(largest_pressure_angle(s), 2)),
        ("ρ convex min [mm]", lambda k, s: f(s["radius_of_curvature_mm"]["convex_min"], 1)),
        ("outer Ø [mm]", lambda k, s: f(s["profile"]["outer_diameter_mm"], 2)),
        (
            "wear max [µm/10⁶ cycles]",
            lambda k, s: bounded(s, "wear", s["wear_depth_max_um_per_Mcycle"], 4),
        ),
        ("limits", lambda k, s: "✔" if s["valid"] else f"⚠ {len(s['violations'])}"),
    ]
    kinds = list(results)
    lines = [
        "| | " + " | ".join(k.label for k in kinds) + " |",
        "|---|" + "---|" * len(kinds),
    ]
    for label, fig in rows:
        cells = [
            fig(k, {})  # the paper's figure needs no result of ours
            if label.startswith("paper's")
            else ("not computable" if label == "limits" else "–")
            if isinstance(results[k], str)
            else fig(k, results[k]["summary"])
            for k in kinds
        ]
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    notes = [f"- *{k.label}*: {esc(a)}" for k, a in results.items() if isinstance(a, str)]
    notes += [  # (our words only: nothing a user typed)
        f"- ² *{k.label}*: {note}"
        for k, a in results.items()
        if not isinstance(a, str)
        for _, note in unbounded_notes(a["summary"])
    ]
    text = WHY + "\n\n" + "\n".join(lines)
    text += "\n\n" + _fields_used(design)
    text += (
        "\n\n¹ The largest contact force and stress per face in the high dwell; for double "
        "followers while both faces touch (the load is shared; in the first and last 2ψ_h "
        "one face carries it all, see Key numbers). Wear: Archard's law along the profile "
        "(rollers roll and do not slide; README for the model). **Table 1** is the "
        "paper's value for its own example (the `paper_example` preset), shown for that "
        "design only (its motion, follower, dynamics, r_b and speed)"
    )
    if any(v is not None for v in table1.values()):
        text += (
            ", and ours differs from it: in the dwell Eqs. 29-38 give F_N = F_t = "
            "Mg + k(h + s_p) = 136.509 N for a single follower and F_t / (2 cos ψ_h) for a "
            "double one (68.397 N concave, 68.579 N rollers); the paper's 133.5 / 129.2 N "
            "lie below F_t and its 67.297 N for both doubles ignores cos ψ_h (README, "
            "*Reproducing the paper*)."
        )
    else:
        text += ": this design is not it."
    if notes:
        text += "\n\n" + "\n".join(notes)
    return text


def _fields_used(design: Design) -> str:
    """Which of the design's follower fields each compared follower takes (a
    designer's review: the rollers ran with a roller radius greyed out on the Design
    tab, and nothing said which); and that the limits counted are the paper's and the
    profile's, without the geometric check (it runs for the design on screen)."""
    f = design.follower
    return (
        f"Each follower takes this design's own values: rollers r_c = {f.roller_radius_mm:g} "
        f"mm, concave faces r_f = {f.face_radius_mm:g} mm, double followers' offset e = "
        f"{f.offset_mm:g} mm, single followers' axis offset e_s = {f.single_offset_mm:g} mm "
        "(set on the Design tab: a field the follower on screen does not use is greyed "
        "there, and still used here). *Limits* counts the broken limits without the "
        "geometric check, which runs for the design on screen."
    )


class CompareView:
    """The table and two plots (Figs. 11 and 13) of the four followers, each plot with
    the stations of the design on screen dashed and its cam angle marked, as the
    Curves tab's: a teacher steps through the stations and watches the four curves."""

    def __init__(self, gui):
        self.gui = gui
        self.md = gui.add_markdown("*Computing the four followers…*")
        ser = [{"label": k.label, "stroke": COLORS[i], "scale": "y"} for i, k in enumerate(KINDS)]
        self.fn = Curve(
            gui,
            "Contact force F_N (per contact) of the four followers (Fig. 11)",
            [("y", "F_N per contact [N]")],
            ser,
            height=210,
            shading=False,
        )
        self.stress = Curve(
            gui,
            "Contact stress σ_H of the four followers (Fig. 13)",
            [("y", "σ_H [MPa]")],
            ser,
            height=210,
            shading=False,
        )
        self.results: dict = {}

    def update(self, results: dict, design: Design, at: float, stations: np.ndarray) -> None:
        """Show ``results`` (app.analyst.Refined.compare) of ``design`` with the marker at
        cam angle ``at`` [deg] and the ``stations`` [deg] of the design on screen."""
        self.results = results
        self.md.content = table_markdown(results, design)
        ok = [r for r in results.values() if not isinstance(r, str)]
        # camcore's compare puts every follower on one grid; with none computable the
        # plots keep the stations and the marker of this design, and no curve
        x = ok[0]["theta_deg"] if ok else np.array([0.0, 360.0])
        zero = np.zeros(x.shape)
        failed = [isinstance(r, str) for r in results.values()]
        for curve, key in ((self.fn, "FN_N"), (self.stress, "stress_MPa")):
            ys = tuple(zero if isinstance(r, str) else r[key] for r in results.values())
            _hide(curve, failed)  # (not NaN: uPlot cannot range a NaN series: blank plot)
            curve.show(x, ys, zero, at, stations)

    def marker(self, theta_deg: float) -> None:
        """The cam angle on both plots."""
        self.fn.marker(theta_deg)
        self.stress.marker(theta_deg)


def _hide(curve: Curve, hidden: list[bool]) -> None:
    """Hide the follower series of ``curve`` that have no curve (not computable)."""
    ser = list(curve.handle.series)
    for i, off in enumerate(hidden, start=1):  # (series 0 is the cam angle)
        ser[i] = {**ser[i], "show": not off}
    if ser != list(curve.handle.series):
        curve.handle.series = tuple(ser)
