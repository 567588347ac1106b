"""The design controls as data: which design field each control edits, and how the
controls' values become a design. Pure functions, no viser: app.layout builds the
widgets from these tables, app.session reads them back.

A design is rebuilt from *all* control values on every change (``merged``), so a
value that is invalid alone or in combination stays invalid until it is fixed, and
the last valid design stays on screen meanwhile.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pydantic import ValidationError

from camcore.model import (
    ALLOWABLE_CONTACT_STRESS_MPa,
    Design,
    FollowerKind,
    MaterialGrade,
    MotionLaw,
    format_validation_error,
)


@dataclass(frozen=True)
class Spec:
    """One control: design path ("motion.lift_mm"), label, widget and its options."""

    path: str
    label: str
    widget: str  # slider | number | dropdown | checkbox | text
    lo: float | None = None
    hi: float | None = None
    step: float | None = None
    options: tuple[str, ...] = ()
    hint: str | None = None
    extra: dict = field(default_factory=dict)
    zero_is_none: bool = False  # an optional field: the control shows 0 for "not set"
    scale: float = 1.0  # design value = control value x scale (see control_value)
    labels: tuple[str, ...] = ()  # a dropdown's words for its options, in their order


LAWS = tuple(m.value for m in MotionLaw)
KINDS = tuple(k.value for k in FollowerKind)
_LAW_WORDS = {
    "poly_345": "3-4-5 polynomial",
    "poly_4567": "4-5-6-7 polynomial",
    # (between two dwells it is the 3-4-5: a review's teacher saw two laws alike)
    "polynomial": "polynomial fitted to its neighbours",
}
LAW_LABELS = tuple(_LAW_WORDS.get(v, v.replace("_", " ")) for v in LAWS)
LABEL_OF_LAW = dict(zip(LAWS, LAW_LABELS, strict=True))  # "poly_345" -> "3-4-5 polynomial"
LAW_OF_LABEL = dict(zip(LAW_LABELS, LAWS, strict=True))  # and back
KIND_LABELS = tuple(FollowerKind(k).label for k in KINDS)
GRADES = tuple(g.value for g in MaterialGrade)
GRADE_LABELS = tuple(
    f"{g.replace('_', ' ')} ({ALLOWABLE_CONTACT_STRESS_MPa[MaterialGrade(g)]:g} MPa)"
    for g in GRADES
)

# folder title, expanded?, specs
FOLDERS: tuple[tuple[str, bool, tuple[Spec, ...]], ...] = (
    (
        "Name",
        False,
        (
            Spec(
                "name",
                "Design name",
                "text",
                hint="names the downloads and the report (up to 200 characters)",
            ),
        ),
    ),
    (
        "Motion program",
        True,
        (
            Spec("motion.lift_mm", "Lift h [mm]", "slider", 1, 60, 0.5),
            Spec("motion.rise_deg", "Rise β_r [°]", "slider", 5, 300, 1),
            Spec("motion.high_dwell_deg", "High dwell β_h [°]", "slider", 0, 300, 1),
            Spec("motion.fall_deg", "Fall β_f [°]", "slider", 5, 300, 1),
            Spec("motion.rise_law", "Rise law", "dropdown", options=LAWS, labels=LAW_LABELS),
            Spec("motion.fall_law", "Fall law", "dropdown", options=LAWS, labels=LAW_LABELS),
        ),
    ),
    (
        "Follower",
        True,
        (
            Spec("follower.kind", "Kind", "dropdown", options=KINDS, labels=KIND_LABELS),
            Spec(
                "follower.offset_mm",
                "Offset e [mm]",
                "slider",
                0,
                60,
                0.5,
                hint="offset of each face/roller of a double follower",
            ),
            Spec(
                "follower.single_offset_mm",
                "Axis offset e_s [mm]",
                "slider",
                -60,
                60,
                0.5,
                hint="single followers: the axis moved left (> 0) lowers the rise's pressure angle",
            ),
            Spec(
                "follower.face_radius_mm",
                "Face radius r_f [mm]",
                "slider",
                -1000,
                -20,
                1,
                hint="concave faces: negative, |r_f| must exceed r_b",
            ),
            Spec("follower.roller_radius_mm", "Roller radius r_c [mm]", "slider", 1, 50, 0.5),
        ),
    ),
    (
        "Cam",
        True,
        (
            Spec("cam.base_radius_mm", "Base radius r_b [mm]", "slider", 10, 300, 1),
            Spec("cam.width_mm", "Width w [mm]", "slider", 1, 100, 0.5),
            Spec("cam.speed_rpm", "Cam speed [rpm]", "number", step=10),
            Spec(
                "cam.bore_diameter_mm",
                "Bore diameter [mm]",
                "number",
                step=1,
                hint="shaft bore of the exported solid; 0 = solid blank",
            ),
            Spec(
                "cam.keyway_width_mm",
                "Keyway width b [mm]",
                "number",
                step=0.1,
                hint="in the bore, on the theta = 0 ray (e.g. 8 in a 30 mm bore, DIN 6885), "
                "with its depth below; 0 = none",
            ),
            Spec(
                "cam.keyway_depth_mm",
                "Keyway depth t2 [mm]",
                "number",
                step=0.1,
                hint="beyond the bore radius (e.g. 3.3 for an 8 mm key)",
            ),
            Spec(
                "cam.bore_flat_mm",
                "Bore flat (D shaft) [mm]",
                "number",
                step=0.1,
                hint="size across the flat, facing theta = 0 (e.g. 4.5 for a 5 mm D shaft); "
                "0 = round",
            ),
            Spec(
                "cam.cutter_diameter_mm",
                "Cutter diameter [mm]",
                "number",
                step=1,
                hint="end mill for the G-code download; refused where it would gouge",
            ),
            Spec(
                "cam.pass_depth_mm",
                "Depth per pass [mm]",
                "number",
                step=0.01,  # (the browser rounds a typed value to the step's decimals)
                hint="G-code: largest cut per pass; 0 = the whole depth at once",
            ),
            Spec(
                "cam.breakthrough_mm",
                "Breakthrough [mm]",
                "number",
                step=0.01,
                hint="G-code: how far the last pass goes below the blank",
            ),
            Spec(
                "cam.feed_mm_per_min",
                "Feed [mm/min]",
                "number",
                step=1,
                hint="G-code: cutting feed along the contour, for your machine and material",
            ),
            Spec(
                "cam.plunge_mm_per_min",
                "Plunge feed [mm/min]",
                "number",
                step=1,
                hint="G-code: feed down into the blank",
            ),
            Spec(
                "cam.spindle_rpm",
                "Spindle speed [rpm]",
                "number",
                step=10,
                hint="G-code: S on M3; 0 = none written (set it at the machine)",
            ),
            Spec(
                "cam.safe_height_mm",
                "Rapid height [mm]",
                "number",
                step=1,
                hint="G-code: moves between cuts this high above the blank, above every clamp",
            ),
        ),
    ),
    (
        "Dynamics",
        False,
        (
            Spec("dynamics.mass_g", "Mass M [g]", "number", step=1),
            Spec("dynamics.spring_rate_N_per_m", "Spring rate k [N/m]", "number", step=10),
            Spec("dynamics.preload_mm", "Preload s_p [mm]", "number", step=0.5),
            Spec("dynamics.guide_friction", "Guide friction μ", "number", step=0.01),
            Spec(
                "dynamics.contact_friction",
                "Contact friction μ_c",
                "number",
                step=0.01,
                hint="sliding friction at the cam–face contact; 0 as in the paper; rollers roll",
            ),
            Spec(
                "dynamics.guide_width_mm",
                "Guide width d [mm]",
                "number",
                step=0.5,
                hint="the stem's width (diameter) in its guide: the arm of the guide friction "
                "(the paper's Fig. 5; its example 8 mm)",
            ),
            Spec(
                "dynamics.guide_length_mm",
                "Guide length l2 [mm]",
                "number",
                step=1,
                hint="the length of the guide bearing the stem: the two guide reactions F1, "
                "F2 act at its ends (Fig. 5; 80 mm in the paper)",
            ),
            Spec(
                "dynamics.overhang_mm",
                "Overhang l1 [mm]",
                "number",
                step=1,
                hint="from the guide's cam-side end to the face's vertex (a roller's lowest "
                "point) at the lowest position: longer tilts the stem more (Fig. 5; 30 mm)",
            ),
            Spec("dynamics.gravity_m_s2", "Gravity g [m/s²]", "number", step=0.01),
            Spec(
                "dynamics.external_load_N",
                "External load F_e [N]",
                "number",
                step=1.0,
                hint="a constant load on the follower toward the cam (a process force, a "
                "cylinder), added to F_t of Eq. 29 as the weight is; negative pulls it off "
                "the cam (0 in the paper)",
            ),
            Spec("dynamics.overhang_shrinks", "Overhang shrinks with lift", "checkbox"),
            Spec(
                "dynamics.train_stiffness_N_per_m",
                "Train stiffness k₁ [N/m]",
                "number",
                step=1e4,
                hint="0 = rigid follower (the paper); else the elastic train model",
                zero_is_none=True,
            ),
            Spec("dynamics.damping_ratio", "Train damping ratio ζ", "number", step=0.01),
            Spec(
                "dynamics.spring_mass_g",
                "Spring mass [g]",
                "number",
                step=1,
                hint="a third moves with the follower (elastic train)",
            ),
            Spec(
                "dynamics.spring_safety_factor",
                "Spring safety factor n",
                "number",
                step=0.1,
                hint="proposed spring: its force is n times what just keeps contact",
            ),
            Spec(
                "dynamics.speed_fluctuation",
                "Speed fluctuation C_s",
                "number",
                step=0.005,
                hint="for the flywheel inertia ΔE / (C_s ω²)",
            ),
        ),
    ),
    (
        "Wear & life",
        False,
        (
            Spec(
                "wear.coefficient_mm3_per_N_m",
                "Archard k [10⁻⁹ mm³/(N·m)]",
                "number",
                step=0.01,  # viser fixes the box's decimals from the step at creation
                hint="lubricated hardened steel ~1…100 (1e-9…1e-7 mm³/(N·m)); dry steel ~1e4",
                scale=1e-9,
            ),
            Spec("wear.pitting_reference_cycles", "Pitting N_ref [cycles]", "number", step=1e7),
            Spec("wear.pitting_exponent", "Pitting exponent m", "number", step=0.1),
        ),
    ),
    (
        "Material & limits",
        False,
        (
            Spec(
                "material.grade",
                "Cam surface",
                "dropdown",
                options=GRADES,
                labels=GRADE_LABELS,
                hint="sets the default allowable contact stress (in brackets); the cam's "
                "E1 and ν1 below are yours to set for it",
            ),
            Spec(
                "limits.allowable_contact_stress_MPa",
                "Allowable stress [MPa]",
                "number",
                step=10,
                hint="your material's figure; 0 = the cam surface's default",
                zero_is_none=True,
            ),
            Spec(
                "limits.contact_stress_safety_factor",
                "Stress safety factor",
                "number",
                step=0.05,
                hint="the largest Hertz stress times this must stay within the allowable",
            ),
            Spec("material.cam_E_GPa", "Cam E1 [GPa]", "number", step=1),
            Spec("material.cam_nu", "Cam ν1", "number", step=0.01),
            Spec("material.follower_E_GPa", "Follower E2 [GPa]", "number", step=1),
            Spec("material.follower_nu", "Follower ν2", "number", step=0.01),
            Spec("limits.max_pressure_angle_deg", "Max pressure angle [°]", "number", step=1),
            Spec(
                "limits.require_continuous_acceleration",
                "Require continuous acceleration",
                "checkbox",
                hint="off: accept jumps in the acceleration (an infinite jerk), e.g. simple "
                "harmonic next to a dwell; the status then says where",
            ),
            Spec(
                "limits.min_jump_speed_ratio",
                "Min jump-speed ratio",
                "number",
                step=0.1,
                hint="the rigid follower must keep contact up to this many times the cam "
                "speed (e.g. 1.2; the spring proposed meets it); 0 = only at the speed itself",
                zero_is_none=True,
            ),
            Spec("limits.resolution_deg", "Resolution [°]", "number", step=0.05),
            Spec(
                "limits.max_outer_diameter_mm",
                "Max outer Ø [mm]",
                "number",
                step=1,
                hint="the largest the cam may be across (its envelope, or your stock); "
                "0 = not checked",
                zero_is_none=True,
            ),
            Spec(
                "limits.min_hub_wall_mm",
                "Min hub wall [mm]",
                "number",
                step=0.5,
                hint="thinnest material between the bore (and keyway) and the profile",
            ),
        ),
    ),
)

SPECS: tuple[Spec, ...] = tuple(s for _, _, specs in FOLDERS for s in specs)
SPEC_BY_PATH: dict[str, Spec] = {s.path: s for s in SPECS}
NONE_AS_ZERO = frozenset(s.path for s in SPECS if s.zero_is_none)
SCALES = {s.path: s.scale for s in SPECS if s.scale != 1.0}
# a dropdown's word -> the design's value (a value itself is taken as it is)
VALUE_OF = {s.path: dict(zip(s.labels, s.options, strict=True)) for s in SPECS if s.labels}


def get_path(design: Design, path: str):
    """The design's value at a control's path, or None where the design has none (the
    classic motion sliders on a program that is not rise-dwell-fall-dwell)."""
    obj = design
    try:
        for part in path.split("."):  # (a list by index: motion.segments.0.angle_deg)
            obj = obj[int(part)] if isinstance(obj, list) else getattr(obj, part)
    except (ValueError, IndexError):  # (no such segment)
        return None
    if obj is None and path in NONE_AS_ZERO:
        return 0.0
    return obj.value if hasattr(obj, "value") else obj


def control_value(design: Design, spec: Spec):
    """What the control of ``spec`` shows for ``design``: get_path in the control's
    unit, or a dropdown's word for it. A scaled control (a tiny quantity such as
    Archard's k, which the browser's number box would round to 0 at its 7 decimals)
    shows 12 significant digits."""
    v = get_path(design, spec.path)
    if spec.labels and v in spec.options:
        return spec.labels[spec.options.index(v)]
    if spec.scale == 1.0 or not isinstance(v, int | float):
        return v
    return float(f"{v / spec.scale:.12g}")


def _unscaled(path: str, v: object, current: object) -> object:
    """A scaled control's value in the design's unit; the design's own value while the
    control still shows it (10 x 1e-9 is not 1e-8 to the last bit: no drift)."""
    scale = SCALES.get(path)
    if scale is None or not isinstance(v, int | float):
        return v
    if isinstance(current, int | float) and v == float(f"{current / scale:.12g}"):
        return current
    return float(f"{v * scale:.15g}")  # the decimal typed (3 x 1e-9 is 3.0000000000000004e-09)


def merged(base: Design, values: dict[str, object]) -> dict:
    """The design dict of ``base`` with control values (by path) written in. The
    classic motion sliders only edit a classic program; another program keeps its
    segments (edited as a whole, e.g. through a design file)."""
    data = base.model_dump(mode="json")
    classic = base.motion.classic is not None
    for path, v in values.items():
        if "." not in path:  # a top-level field (the name)
            data[path] = v
            continue
        group, key = path.split(".")
        if group == "motion" and not classic:
            continue
        v = _unscaled(path, v, data[group].get(key))
        if path in VALUE_OF and isinstance(v, str):
            v = VALUE_OF[path].get(v, v)
        data[group][key] = None if path in NONE_AS_ZERO and v == 0 else v
    _keep_unused(data, base)
    return data


def _keep_unused(data: dict, base: Design) -> None:
    """A follower field the (new) kind does not use keeps the base design's value: its
    control is greyed out, but a value typed into its box must not make the design
    invalid (0 typed as the roller radius of a concave face had blocked everything)."""
    try:
        kind = FollowerKind(data["follower"]["kind"])
    except (ValueError, TypeError):  # not a kind: the validation says so
        return
    old = base.follower.model_dump(mode="json")
    for key in old:
        if not kind.uses(key):
            data["follower"][key] = old[key]


def try_design_dict(data: dict) -> tuple[Design | None, str | None]:
    """(design, None) if ``data`` is a valid design, else (None, message)."""
    try:
        return Design.model_validate(data), None
    except ValidationError as exc:
        return None, format_validation_error(exc)


def try_design(
    base: Design, values: dict[str, object], program: list[dict] | None = None
) -> tuple[Design | None, str | None]:
    """(design, None) if the control values make a valid design, else (None, message).
    ``program``: the segment table's segments as the motion (the table's edit, with
    every other control as it shows)."""
    data = merged(base, values)
    if program is not None:
        data["motion"] = {"segments": program}
    return try_design_dict(data)


TYPED_DECIMALS = 6  # what a number box keeps of a typed value


def fine(handle):
    """A number box (or a slider's) that keeps TYPED_DECIMALS decimals of what is typed:
    viser takes the box's decimals from its step and values at creation and the browser
    rounds typed input to them (a 6.35 mm cutter became 6, a 0.01 mm pass depth 0)."""
    handle.precision = max(handle.precision, TYPED_DECIMALS)
    return handle
