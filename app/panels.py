"""What the tab shows in words: the status panel, key numbers, where the cam is, the
segment sums and the download names. Pure functions of camcore results (no viser,
no session), so they are tested without a server.

Every user-provided string shown here goes through ``esc`` (viser's Markdown renders
raw HTML).
"""

from __future__ import annotations

import functools
import hashlib
import html
import math
import re
from typing import Any

import numpy as np

from camcore.model import Design, FollowerKind, design_to_json
from camcore.motion import segment_word
from camcore.report import (
    folds_back,
    machine_rows,
    rho_range_text,
    unbounded_figures,
    unbounded_notes,
)
from camcore.units import to_mm

from .controls import FOLDERS, LABEL_OF_LAW


def program_text(design: Design) -> str:
    """One line describing a program the classic sliders cannot edit."""
    parts = []
    for g in design.motion.segments:
        law = LABEL_OF_LAW[g.law.value] if g.law else ""
        lift = f" {g.lift_mm:g} mm {law}" if g.lift_mm and g.law else ""
        parts.append(f"{g.kind.value} {g.angle_deg:g}°{lift}")
    return (
        "Program of "
        + str(len(parts))
        + " segments (edit them in the segment table): "
        + "; ".join(parts)
    )


def low_dwell_text(values: dict[str, Any], design: Design | None = None) -> str:
    """The derived low dwell under the motion sliders: the design's (camcore.model) when
    the controls make one, else what the typed values imply (e.g. negative), so the user
    sees why the input is refused."""
    if design is not None and design.motion.classic is None:
        return program_text(design)
    if design is not None:
        bl = float(design.motion.low_dwell_deg)
    else:
        try:
            bl = (
                360.0
                - float(values["motion.rise_deg"])
                - float(values["motion.high_dwell_deg"])
                - float(values["motion.fall_deg"])
            )
        except (KeyError, TypeError, ValueError):
            return "Low dwell β_l: -"
    flag = "  ⚠ negative" if bl < 0 else ""
    return f"Low dwell β_l = 360 − β_r − β_h − β_f = **{bl:g}°**{flag}"


# --- status panel --------------------------------------------------------------------

_BOX = (
    "<div style='border-radius:6px;padding:6px 10px;margin:2px 0;font-size:0.85em;"
    "line-height:1.35;background:{bg};border:2px solid {fg};color:#222'>{body}</div>"
)


_MD_SPECIAL = re.compile(r"([\\`*_{}\[\]()#+\-!|~>])")
# GFM turns "https://...", "www.x" and "a@b.c" in text into links, escapes or not (a
# review: a design named "https://evil.example" became a link in the Files message): a
# word joiner (U+2060, invisible) inside each breaks the pattern
_AUTOLINK = re.compile(r"(?<=:)(?=//)|(?<=www)(?=\.)|(?<=@)", re.IGNORECASE)  # ("_www." too)


_BREAKS = re.compile(r"[\r\n\v\f\x85\u2028\u2029]+")


def esc(text: object) -> str:
    """User-provided text (a design or file name, a message quoting input) made safe for
    viser's Markdown, which renders raw HTML: HTML-escaped, Markdown's special
    characters backslash-escaped so they show as typed, and no link made of a URL or
    address in it, and on one line (Markdown reads a line break as a soft space, but
    a name like "x\\n===" or "a\\n1. b" would have started a heading or a list: a
    review). Every such string goes through here before it is shown."""
    one_line = _BREAKS.sub(" ", str(text))
    escaped = _MD_SPECIAL.sub(r"\\\1", html.escape(one_line, quote=False))
    return _AUTOLINK.sub("\u2060", escaped)


# The status box stays at the top of the panel while the panel scrolls (its wrapper is
# made sticky; viser nests it in a box with overflow: hidden, which would make that box
# the one it sticks in, so every box around it clips instead: the same look, and
# "clip" makes no scroll container), and scrolls inside itself past a third of the
# window (a fifth on a window 800 px high or less: at 1280x720 the status and the
# Animation block had taken 530 px of the panel, a teacher's review): a long list of
# violations never hides the controls. The panel itself stays 80 px narrower than the
# window, and the wide one within 62 % of it (app.layout reckons the wide panel in
# device pixels: on a high-DPI screen, or zoomed in, it would cover the mechanism).
# On such a short window the line under the angle slider keeps room for
# SHORT_WHERE_LINES only (a teacher's review at 1280x720: with 8 lines kept, the tabs'
# contents began 13 px above the panel's bottom, and a click on a tab seemed to do
# nothing); a station's sentence then moves the tabs down while it shows.
# The controls' labels are dark grey (Mantine's "dimmed" #868e96 on white is 3.3:1, a
# teacher's review found them hard to read projected; #495057 is 8:1).
SHORT_WHERE_LINES = 3  # the room it keeps on a window 800 px high or less (STATUS_CSS)
STATUS_CSS = (
    "<style>.mantine-ScrollArea-content div:has(#cam-status){overflow:clip!important;min-width:0}"
    "div:has(> #cam-status){position:sticky;top:0;z-index:10;background:#fff}"
    "#cam-status{max-height:32vh;overflow-y:auto}"
    "@media (max-height:800px){#cam-status{max-height:20vh}"
    f".cam-where{{min-height:{SHORT_WHERE_LINES * 1.35:.2f}em!important;font-size:0.9em}}}}"
    "[data-testid='floating-panel']{max-width:min(calc(100vw - 80px),max(384px,62vw));"
    "--mantine-color-dimmed:#495057}</style>"
)


def status_html(
    error: str | None,
    violations,
    lift_error: float | None,
    verified: bool,
    mesh_error: str | None = None,
    file_error: str | None = None,
    cutter_note: str | None = None,
    headline: str = "",
    accepted: str | None = None,
) -> str:
    """The always-visible panel (STATUS_CSS): input errors (red), limit violations
    (amber), or OK; a file that could not be opened (``file_error``) above them, the
    design's headline figures (``headline``, see headline_html) above all.

    With an input error the panel says so and nothing green: the limits shown below it
    are those of the last valid design, which stays on screen (and in the downloads'
    refusal) until the input is fixed. A file that could not be opened changes nothing:
    the design on screen is still the one the controls describe. ``cutter_note``: the
    design's cutter does not fit its concave stretches (the G-code download refuses).
    ``accepted``: what the design's limits accept that the checks would refuse
    (camcore.checks.accepted_jumps), under the verdict.
    """
    file_box = (
        _BOX.format(
            bg="#fde2e2",
            fg="#d62728",
            body="<b>✖ Could not open the file — the design on screen is unchanged</b>"
            f"<br>{html.escape(file_error)}",
        )
        if file_error
        else ""
    )
    boxes = _status_boxes(error, violations, lift_error, verified, mesh_error)
    # the headline first: the box scrolls inside its 32vh, and below four violations
    # it had been out of view (a review)
    # (after an input error, below it: its figures are the last valid design's)
    first, last = ("", headline) if error else (headline, "")
    return (
        f"{STATUS_CSS}<div id='cam-status'>{first}{file_box}{boxes}"
        f"{_cutter_box(cutter_note)}{_accepted_line(accepted)}{last}</div>"
    )


def _field_name(path: str) -> str:
    """An error's field as the panel labels it, its path beside it ("Roller radius r_c
    [mm] <code>follower.roller_radius_mm</code>"); the path alone where no control shows
    it. Escaped: the path comes from the validation of what a client sent."""
    from .controls import SPEC_BY_PATH

    spec = SPEC_BY_PATH.get(path)
    label = spec.label if spec is not None else None
    if label is None and re.fullmatch(SEGMENT_FIELD, path):
        label = in_words(path)
    code = f"<code>{html.escape(path)}</code>"
    return f"<b>{html.escape(label)}</b> {code}" if label else code


def in_words(text: str) -> str:
    """An input error's text with the design's field names as the panel labels them
    ("rise_deg + high_dwell_deg" -> "Rise β_r [°] + High dwell β_h [°]": a student reads
    the controls, not the file format). Whole names only (dotted paths first; a name
    without "_" is an ordinary word)."""
    words, pattern = _field_words()
    text, got, value = text.partition(" (got ")  # the value the user wrote: as written
    text = re.sub(SEGMENT_FIELD, _segment_words, text)
    return pattern.sub(lambda m: words[m.group(1)], text) + got + value


@functools.cache
def _field_words() -> tuple[dict[str, str], re.Pattern]:
    """in_words' table (field path or unambiguous name -> label) and its pattern, made
    once (an invalid value redraws the status at every slider event)."""
    from .controls import SPECS

    labels = {s.path: s.label for s in SPECS if "_" in s.path.split(".")[-1]}
    bare: dict[str, str | None] = {}
    for path, label in labels.items():
        key = path.split(".")[-1]
        bare[key] = None if key in bare and bare[key] != label else label  # ambiguous
    words = {**labels, **{k: v for k, v in bare.items() if v is not None}}
    names = "|".join(map(re.escape, sorted(words, key=len, reverse=True)))
    return words, re.compile(r"(?<![\w.])(" + names + r")(?![\w])")


# a segment's field ("motion.segments.4.angle_deg", counted from 0) as the segment
# table labels it, its rows counted from 1 (a review read row 5's error as row 4's)
SEGMENT_FIELD = r"(?<![\w.])(?:motion\.)?segments\.(\d+)(?:\.(\w+))?(?![\w])"
SEGMENT_WORDS = {"angle_deg": "angle [°]", "lift_mm": "lift [mm]", "law": "law", "kind": "kind"}


def _segment_words(m: re.Match) -> str:
    row, key = int(m.group(1)) + 1, m.group(2)
    return f"segment {row}" + (f" {SEGMENT_WORDS.get(key, key)}" if key else "")


def _status_boxes(error, violations, lift_error, verified, mesh_error) -> str:
    parts = []
    if error:
        items = "".join(
            f"<li>{_field_name(p.split(': ', 1)[0])}: "
            f"{html.escape(in_words(p.split(': ', 1)[-1]))}</li>"
            for p in error.split("; ")
        )
        parts.append(
            _BOX.format(
                bg="#fde2e2",
                fg="#d62728",
                body="<b>✖ Invalid input — the last valid design stays on screen</b>"
                f"<ul style='margin:4px 0 0 0;padding-left:18px'>{items}</ul>",
            )
        )
    if violations:
        items = "".join(
            f"<li><b>{html.escape(v.equation)}</b> <code>{html.escape(v.code)}</code>: "
            f"{html.escape(_typeset_units(v.message))}</li>"
            for v in violations
        )
        parts.append(
            _BOX.format(
                bg="#fff3d6",
                fg="#e08a00",
                body=f"<b>⚠ {len(violations)} design-limit violation"
                f"{'s' if len(violations) > 1 else ''}</b> ({_where_red(violations)})"
                f"<ul style='margin:4px 0 0 0;padding-left:18px'>{items}</ul>",
            )
        )
    if error:
        parts.append(
            _BOX.format(
                bg="#eeeeee",
                fg="#555555",
                body=f"Last valid design: {len(violations) or 'no'} limit violation"
                f"{'' if len(violations) == 1 else 's'}. Downloads are refused until the "
                "input is valid.",
            )
        )
        return "".join(parts) + _mesh_box(mesh_error)
    if not violations:
        check = ""
        if verified and lift_error is not None:
            check = f"; geometric check max |lift − S| = {to_mm(lift_error):.2g} mm"
        elif not verified:
            check = "; geometric check running…"
        parts.append(
            _BOX.format(bg="#e3f5e1", fg="#2ca02c", body=f"<b>✔ All design limits met</b>{check}")
        )
    return "".join(parts) + _mesh_box(mesh_error)


def _mesh_box(mesh_error: str | None) -> str:
    """The cam has no solid to draw or export (e.g. a self-intersecting profile)."""
    if not mesh_error:
        return ""
    return _BOX.format(
        bg="#fde2e2", fg="#d62728", body=f"<b>No solid:</b> {html.escape(mesh_error)}"
    )


def _accepted_line(note: str | None) -> str:
    """One grey line: what the design accepts that the checks would refuse, and the
    control that says so."""
    if not note:
        return ""
    text = html.escape(_typeset_units(note))
    return f"<div style='font-size:0.8em;color:#555;margin:2px 12px 0 2px'>ℹ {text}</div>"


def _cutter_box(note: str | None) -> str:
    """The G-code would be refused: the cutter does not fit the cam, or too many passes
    (found when the tab is still, with the check)."""
    if not note:
        return ""
    return _BOX.format(
        bg="#fff3d6",
        fg="#e08a00",
        body=f"<b>⚠ G-code:</b> {html.escape(note)}. The G-code download refuses it: "
        "change <i>Cutter diameter [mm]</i> or <i>Depth per pass [mm]</i> (Cam), or the "
        "design.",
    )


_APP_WORDS = (
    (" um ", " µm "),
    (" N m", " N·m"),
    (" kg m2", " kg·m²"),
    # a field as its control names it (a teacher's review read the design path)
    ("(dynamics.train_stiffness_N_per_m not set)", "(Train stiffness k₁ not set)"),
    (
        "limits.require_continuous_acceleration = false to accept it",
        "untick Require continuous acceleration (Material & limits) to accept it",
    ),
    (
        "limits.require_continuous_acceleration is off",
        "Require continuous acceleration is off (Material & limits)",
    ),
)


# "(limits.min_hub_wall_mm)" in a message -> "(Min hub wall [mm], Material & limits)":
# every field a control sets, named as the panel names it (a teacher's review)
_CONTROL_OF = {
    f"({spec.path})": f"({spec.label}, {folder})" for folder, _, specs in FOLDERS for spec in specs
}


def _typeset_units(text: str) -> str:
    """The text report's ASCII units (a terminal's) as the curves and Compare write
    them, and a field's path as its control's label."""
    for a, b in _APP_WORDS:
        text = text.replace(a, b)
    for path in re.findall(r"\([a-z_]+\.[a-z0-9_.]+\)", text):
        text = text.replace(path, _CONTROL_OF.get(path, path))
    return text


def _stress_limit_MPa(s: dict) -> float:
    """The largest contact stress the design may reach [MPa] (the check's limit)."""
    return s["contact_stress_allowable_MPa"] / s["contact_stress_safety_factor"]


def largest_pressure_angle(s: dict) -> float | None:
    """The summary's largest pressure angle of the rise and fall [deg], None if neither."""
    angles = [v for v in s["pressure_angle_max_deg"].values() if v is not None]
    return max(angles) if angles else None


def headline_html(s: dict) -> str:
    """The figures a designer watches while moving a slider, in one line that stays in
    view with the status (the key numbers' table sits below the Design tab's controls):
    the largest pressure angle, the smallest radius of curvature, the largest contact
    stress against its limit and the jump speed. Numbers only (nothing typed by a user).
    """

    def mm(x: float | None) -> str:
        return "–" if x is None else f"{x:.1f}"

    phi = largest_pressure_angle(s)
    rho = s["radius_of_curvature_mm"]
    concave = "" if rho["concave_min"] is None else f", concave ≥ {mm(rho['concave_min'])}"
    jump, stress = s["jump_speed_rpm"], s["contact_stress_max_MPa"]["cycle"]
    if stress is None:  # (a knife edge: no Hertz stress)
        sigma = "σ<sub>H</sub> none: a knife edge's point has no Hertz contact"
    elif unbounded := unbounded_notes(s):  # an impulse, a cusp, a jam (report.py)
        sigma = f"σ<sub>H</sub> unbounded: {unbounded[0][0]}"
    else:
        sigma = f"σ<sub>H</sub> ≤ {stress:.1f} / {_stress_limit_MPa(s):.6g} MPa"
    codes = {v["code"] for v in s["violations"]}
    if folds_back(s):  # (a teacher's review read "ρ ≥ 0.0, concave ≥ 0.0 mm" as harmless)
        rho_item = "ρ → 0: the profile folds back"
    elif "profile_crossing" in codes:  # (... and "ρ ≥ 38.6 mm" beside no solid at all)
        rho_item = "ρ: the profile crosses itself"
    else:
        rho_item = f"ρ ≥ {mm(rho['convex_min'])}{concave} mm"
    items = (
        "φ –" if phi is None else f"φ ≤ {phi:.1f}°",
        rho_item,
        sigma,
        "no jump"
        if jump is None
        else "jumps at any speed"
        if jump == 0.0
        else f"jumps at {jump:.0f} rpm",
    )
    # an item breaks only between items (a review: "rpm" alone on a second line)
    kept = [item.replace(" ", "\u00a0") for item in items]
    return (
        "<div id='cam-headline' style='font-size:0.9em;color:#333;margin:0 12px 3px 2px' "
        "title='the design on screen: largest pressure angle, smallest radius of "
        "curvature, largest contact stress / its limit, the speed where the follower "
        "leaves the cam; all figures in Design › Key numbers'>" + " · ".join(kept) + "</div>"
    )


def _where_red(violations) -> str:
    """Where the status's violations are marked: red spans on the cam and the curves,
    but a jump at one cam angle spans none (a teacher's review: the promised red was
    nowhere for a harmonic law's acceleration jumps)."""
    spans = [hi - lo > SPAN_DEG for v in violations for lo, hi in v.ranges_deg]
    if not spans:  # (a hub wall, a self-crossing profile: no cam angle)
        return "listed below"
    if all(spans):
        return "red on the cam and the curves"
    if any(spans):
        return "red on the cam and the curves where they span an angle"
    return "at the cam angles listed"


SPAN_DEG = 0.05  # a violation's range narrower than this is a single angle [deg]


def summary_markdown(s: dict) -> str:
    """Key numbers of camcore.report.summary as a compact table."""

    def f(x, nd=2):
        if x is None:
            return "–"
        if isinstance(x, list):
            return " … ".join(f(v, nd) for v in x)
        return f"{x:.{nd}f}"

    pa, rho = s["pressure_angle_max_deg"], s["curvature_radius_mm"]
    fn, st = s["contact_force_max_N"], s["contact_stress_max_MPa"]
    free = unbounded_figures(s)  # (a review: "101036570.5 MPa" beside "unbounded")
    rows = [
        ("High-dwell radius R", f"{f(s['dwell_radius_mm'], 3)} mm"),
        (
            "ψ_h / ψ_l",
            f"{f(s['psi_h_deg'], 3)} / {f(s['psi_l_deg'], 3)} °"
            if FollowerKind(s["follower"]).is_double
            else "– (one contact)",
        ),
        ("Max pressure angle rise / fall", f"{f(pa['rise'])} / {f(pa['fall'])} °"),
        ("ρ rise", rho_range_text(rho["rise"], lambda x, _nd: f(x, 1), folds_back(s))),
        ("ρ fall", rho_range_text(rho["fall"], lambda x, _nd: f(x, 1), folds_back(s))),
        (
            "ρ convex min / concave min (cutter at most 2×)",
            f"{f(s['radius_of_curvature_mm']['convex_min'], 1)} / "
            f"{f(s['radius_of_curvature_mm']['concave_min'], 1)} mm",
        ),
        (
            "Max F_N per contact: whole cycle / high dwell (one-face windows included)",
            f"{'unbounded' if 'force' in free else f(fn['cycle'])} / {f(fn['high_dwell'])} N",
        ),
        (
            "Max F_N per face while both faces touch the high dwell (Table 1's figure)",
            f"{f(fn['high_dwell_two_contact'])} N"
            if fn["high_dwell_two_contact"] is not None
            else "– (one face only)",
        ),
        (
            "Max F1 / F2",
            "unbounded"
            if "guide" in free
            else f"{f(s['guide_force_max_N']['F1'])} / {f(s['guide_force_max_N']['F2'])} N",
        ),
        (
            "Max stress cycle / high dwell",
            f"{'unbounded' if 'stress' in free else f(st['cycle'], 1)} / "
            f"{f(st['high_dwell'], 1)} MPa",
        ),
        (
            "Stress limit: allowable / safety factor",
            # (significant figures: an allowable of 1e-300 MPa had read "0 MPa")
            f"{s['contact_stress_allowable_MPa']:.6g} MPa / "
            f"{s['contact_stress_safety_factor']:.6g} = {_stress_limit_MPa(s):.6g} MPa",
        ),
        *((k, _typeset_units(v)) for k, v in machine_rows(s)),
        (
            "Contact half-width max",
            (
                "–"
                if s["contact_half_width_max_mm"] is None
                else f"{f(s['contact_half_width_max_mm'], 4)} mm"
            )
            + (
                " (Hertz beyond validity: conservative stress)"
                if s["hertz_beyond_validity_deg"]
                else ""
            ),
        ),
        ("Profile area", f"{f(s['profile']['area_mm2'], 1)} mm²"),
        ("Outer diameter (stock)", f"{f(s['profile']['outer_diameter_mm'], 2)} mm"),
    ]
    double = FollowerKind(s["follower"]).is_double
    spans = [
        f"{f'S{i} ' if double else ''}{f(v[0])} … {f(v[1])}"
        for i, v in enumerate(s["face_contact_x_mm"].values(), start=1)
        if v is not None
    ]
    if spans:  # a concave pad's or a flat face's stretch in contact (not a roller's)
        rows.append(("Contact on the face(s): x from the axis", f"{' / '.join(spans)} mm"))
    if s["profile"]["hub_wall_mm"] is not None:
        rows.append(
            ("Hub wall (thinnest, bore to profile)", f"{f(s['profile']['hub_wall_mm'], 2)} mm")
        )
    table = "| Quantity | Value |\n|---|---|\n" + "\n".join(f"| {k} | {v} |" for k, v in rows)
    notes = [n for _, n in unbounded_notes(s)]  # (our words only: nothing a user typed)
    head = "".join(f"**⚠ {n[0].upper()}{n[1:]}.**\n\n" for n in notes)
    return head + table


# --- where the cam is ----------------------------------------------------------------


def _contact_word(a) -> str:
    """What touches the cam: a roller or a face (a review read 'per face' of rollers)."""
    return "roller" if a.design.follower.kind.is_roller else "face"


def nearest_index(theta: np.ndarray, theta_deg: float) -> int:
    """Index of the grid angle (rad, increasing over one turn) nearest theta_deg."""
    x = math.radians(theta_deg % 360.0)
    j = int(np.clip(np.searchsorted(theta, x), 1, theta.size - 1))
    return j - 1 if x - theta[j - 1] < theta[j] - x else j


# no face touches: the follower is drawn where its program puts it, unsupported (a
# teacher's review read the picture of a broken dwell as resting on the cam)
UNSUPPORTED = "none: the follower is unsupported here (see the status)"
WHERE_LINES = 8  # the line under the slider wraps to 8 lines at most in the narrow panel
WIDE_WHERE_LINES = 4  # and 4 in the wide one


def where_markdown(
    a,
    k: int,
    events: list[str],
    after: list[list[str]] | None = None,
    room_lines: int = WHERE_LINES,
    paused_s: float = 0.0,
) -> str:
    """The line under the angle slider: angle, segment (both names at a boundary), the
    station reached or the two it lies between, what happens there in words, the
    faces in contact, S and F_N at grid index k of analysis ``a``.

    ``after``: per station, the faces touching just after it (report's "contacts"). At
    a station a face that touches now but not after it is marked as leaving (the
    stations diagram draws it idle there: the text had said both faces touch, no more).
    ``room_lines``: the lines of room the block keeps, whatever it says (WHERE_LINES in
    the narrow panel, WIDE_WHERE_LINES in the wide one). ``paused_s``: the animation
    stops that long at the station (Pause at stations): said, as a still cam had
    looked stuck (a teacher's review)."""
    th = math.degrees(a.theta[k])
    st = np.degrees(a.stations)
    step = a.design.limits.resolution_deg
    at = [i for i, s in enumerate(st) if abs(th - s) <= step / 2 + 1e-9]
    said = ""
    if at:
        where = f"at station{'s' if len(at) > 1 else ''} " + " and ".join(str(i) for i in at)
        if paused_s > 0:
            where = f"‖ paused {paused_s:g} s {where}"
        # (HTML-escaped only: the block is HTML, where Markdown's backslashes would show)
        said = "<br>".join(f"<i>{html.escape(events[i])}</i>" for i in at if i < len(events))
    else:
        i, n = int(np.searchsorted(st, th)), len(st)
        where = (
            f"between stations {i - 1} and {i}" if 0 < i < n else f"between stations {n - 1} and 0"
        )
    faces = [a.geo.faces[i].name for i in np.flatnonzero(a.in_contact[:, k])]
    if at and after:
        stay = {face for i in at if i < len(after) for face in after[i]}
        faces = [f if f.split(" ")[0] in stay else f"{f} leaving the cam" for f in faces]
    j, n = int(a.prog.index[k]), len(a.segments)
    seg = segment_word(a.segments, j)

    def here(angle: float) -> bool:
        return abs(math.remainder(angle - a.theta[k], 2 * math.pi)) < 1e-9

    def neighbour(step: int) -> str:  # the next segment that has a length (a fall
        i = (j + step) % n  # meets a rise through an empty dwell, motion.segments)
        while a.segments[i].length <= 1e-12 and i != j:
            i = (i + step) % n
        return segment_word(a.segments, i)

    # a boundary belongs to one of its segments (motion.segment_index): say both
    if here(a.segments[j].start):
        seg = f"{neighbour(-1)} ends, {seg} begins"
    elif here(a.segments[j].end):
        seg = f"{seg} ends, {neighbour(1)} begins"
    body = (
        f"<b>θ = {th:.1f}°</b> · {seg} · <b>{where}</b><br>"
        f"In contact: <b>{', '.join(faces) if faces else UNSUPPORTED}</b> · "
        f"S = {to_mm(a.prog.S[k]):.3f} mm · F_N = {a.guide.FN[k]:.1f} N"
        # two faces touching share the load (Eqs. 36-38): a teacher read station 0's
        # 17.5 N beside "from here S1 carries the load alone" as S1's whole load
        + (f" per {_contact_word(a)}" if int(a.in_contact[:, k].sum()) > 1 else "")
        + (f"<br>{said}" if said else "")
    )
    # in room kept for the longest of these lines (they wrap by their lengths, the
    # station's words come and go): the panel below does not jump during play
    return f"<div class='cam-where' style='min-height:{room_lines * 1.35:.2f}em'>{body}</div>"


# --- the segment table ---------------------------------------------------------------


def segment_sums_markdown(segs: list[dict]) -> str:
    """The two sums a program must meet, under the segment table (segments as dicts
    of the table: kind, angle_deg, lift_mm)."""
    total = sum(float(g["angle_deg"]) for g in segs)
    sign = {"rise": 1, "fall": -1}
    net = sum(sign.get(g["kind"], 0) * float(g.get("lift_mm") or 0) for g in segs)
    ok = abs(total - 360) <= 1e-6 and abs(net) <= 1e-9
    return (
        f"Σ angles = **{total:g}°** (must be 360) · rises − falls = "
        f"**{net:g} mm** (must be 0){'' if ok else ' ⚠'}"
    )


# --- download names ------------------------------------------------------------------


def slug(name: str) -> str:
    """A file-name-safe form of a design's name: letters, digits and "_", at most 40
    characters, cut at a word where one ends past the 20th (not "..._doubl")."""
    s = re.sub(r"[^A-Za-z0-9]+", "_", name).strip("_").lower() or "cam"
    if len(s) <= 40:
        return s
    cut = s[:41].rfind("_")  # (a word ending at the 40th character keeps it)
    return (s[:cut] if cut >= 20 else s[:40]).rstrip("_")


def file_stem(design: Design) -> str:
    """A download's name: the design, its follower, and a short fingerprint of the
    whole design, so two files of different (edited) designs never share a name and a
    file says which design it holds."""
    digest = hashlib.sha256(design_to_json(design).encode()).hexdigest()[:6]
    return f"{slug(design.name)}-{design.follower.kind.value}-{digest}"
