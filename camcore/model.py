"""The design model: one typed pydantic object is the single source of truth.

Every field carries its unit in its name (``_mm``, ``_deg``, ``_rpm``, ``_g``,
``_GPa``, ``_N_per_m``). Computation happens in SI inside camcore; the helpers
at the bottom of this module convert at that edge.

Geometry that the equations cannot even be evaluated for (a negative radius,
angles that do not fit in 360 deg, an offset too large for the square root in
Eq. 3, ...) is rejected here with a ``pydantic.ValidationError`` naming the
field and the limit. Design *limits* of a computable design (curvature,
pressure angle, dwell-arc size, jump) are not validation errors: the analysis
reports them as violations, so the user can still see the design.
"""

from __future__ import annotations

import functools
import json
import math
import re
import unicodedata
from enum import Enum, StrEnum
from pathlib import Path
from typing import Final, Literal, get_args

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from pydantic_core import PydanticCustomError

from .files import printable
from .units import DEG, MM, RPM  # noqa: F401  (MM, DEG re-exported for older imports)

SCHEMA_VERSION: Final = 2
# Upgrades of older design files: MIGRATIONS[v] turns a format-v dict into format v + 1.
# Format 1 -> 2: motion became a list of segments (the classic keys still load, see
# Motion), so the upgrade only restates the version.
MIGRATIONS: dict = {1: lambda data: data}
MAX_DESIGN_BYTES = 1_000_000  # a design is a few hundred bytes; refuse absurd files
# Smallest length and modulus a design may have: 1 um and 1 MPa. Below these the SI
# arithmetic underflows (a radius of 1e-320 mm is 0 m) and results turn into inf/NaN.
MIN_LENGTH_MM = 1e-3
MIN_MODULUS_GPa = 1e-3
MIN_MOTION_DEG = 0.01  # a rise or fall over less than this: V, A, J (~ h / beta^1,2,3) overflow


NAME_MAX: Final = 200  # characters of a design's name
# Unicode categories a name may not hold: control, format, line and paragraph separators;
# but the zero-width (non-)joiner, which Persian words and emoji sequences need
NAME_REFUSED: Final = frozenset({"Cc", "Cf", "Zl", "Zp"})
NAME_JOINERS: Final = frozenset({"\u200c", "\u200d"})


class FollowerKind(StrEnum):
    """Translating followers: the four of the paper's Fig. 9, and the two classics.

    ``flat_face`` is the limit r_f -> infinity of the face (a flat-faced tappet, its
    face perpendicular to the stem); ``knife_edge`` is the limit r_c -> 0 of the roller.
    """

    single_roller = "single_roller"
    double_roller = "double_roller"
    single_concave = "single_concave"
    double_concave = "double_concave"
    flat_face = "flat_face"
    knife_edge = "knife_edge"

    @property
    def is_double(self) -> bool:
        return self in (FollowerKind.double_roller, FollowerKind.double_concave)

    @property
    def is_roller(self) -> bool:
        """A roller of radius r_c (single or double); not the knife edge."""
        return self in (FollowerKind.single_roller, FollowerKind.double_roller)

    @property
    def is_concave(self) -> bool:
        return self in (FollowerKind.single_concave, FollowerKind.double_concave)

    @property
    def label(self) -> str:
        return self.value.replace("_", " ")

    def uses(self, field: str) -> bool:
        """Whether the Follower field ``field`` ("offset_mm", ...) shapes a design with
        this follower: a double follower's offset e means nothing to a single one (which
        uses the axis offset e_s instead), a roller radius nothing to a face, a face
        radius nothing to a roller. Fields not named here shape every follower."""
        if field == "offset_mm":
            return self.is_double
        if field == "single_offset_mm":
            return not self.is_double
        if field == "roller_radius_mm":
            return self.is_roller
        if field == "face_radius_mm":
            return self.is_concave
        return True


# The paper's four followers (Fig. 9, Table 1): the default set of the comparison.
PAPER_FOLLOWERS = (
    FollowerKind.single_roller,
    FollowerKind.double_roller,
    FollowerKind.single_concave,
    FollowerKind.double_concave,
)


class MotionLaw(StrEnum):
    """Laws of a rise or fall (see camcore.motion). ``family`` names each after the
    motion tasks of the VDI 2143 guideline (R rest, G constant velocity)."""

    cycloidal = "cycloidal"
    simple_harmonic = "simple_harmonic"
    poly_345 = "poly_345"
    poly_4567 = "poly_4567"
    modified_trapezoid = "modified_trapezoid"
    modified_sine = "modified_sine"
    constant_velocity = "constant_velocity"
    polynomial = "polynomial"

    @property
    def family(self) -> str:
        if self is MotionLaw.constant_velocity:
            return "VDI 2143 G-G: constant velocity (a straight line S(theta))"
        if self is MotionLaw.polynomial:
            return (
                "VDI 2143 polynomial of degree 5 fitted to the end conditions "
                "(S, V, A of the neighbouring segments): R-G, G-R, G-G or R-R"
            )
        return "VDI 2143 R-R: rest to rest (zero velocity at both ends)"


class _Part(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _no_bool_as_number(cls, v, info):
        """true / false is not a number: pydantic's lax mode reads true as 1.0 (a file
        with "base_radius_mm": true made a 1 mm cam without a word)."""
        if isinstance(v, bool) and info.field_name in _number_fields(cls):
            # (its own type, not value_error: a sweep refuses it for every row, as a
            # string for a number, not as a value that depends on the other fields)
            raise _type_error("a number, not true or false")
        return v


def _type_error(message: str) -> PydanticCustomError:
    """A validation error that holds whatever the other fields are (a wrong type, a
    field the design does not have): its own error type, not value_error, so a sweep
    refuses the spec rather than making a row each (camcore.sweep)."""
    return PydanticCustomError("design_type", "{message}", {"message": message})


@functools.cache
def _number_fields(cls) -> frozenset[str]:
    """The fields of a model class whose annotation allows a number and not a bool
    (``float``, ``float | None``, ``int``)."""
    out = set()
    for name, field in cls.model_fields.items():
        types = set(get_args(field.annotation) or (field.annotation,))
        if types & {float, int} and bool not in types:
            out.add(name)
    return frozenset(out)


class ClassicMotion(_Part):
    """The paper's program: rise, high dwell, fall; the low dwell is the rest of 360 deg.

    This was the ``motion`` of format 1 files; it is still accepted wherever a motion
    is (the app's sliders edit it), and turned into segments (``to_segments``)."""

    lift_mm: float = Field(15.0, ge=MIN_LENGTH_MM, le=1000, description="total lift h [mm]")
    rise_deg: float = Field(100.0, ge=MIN_MOTION_DEG, lt=360, description="rise angle beta_r [deg]")
    high_dwell_deg: float = Field(70.0, ge=0, lt=360, description="high dwell beta_h [deg]")
    fall_deg: float = Field(130.0, ge=MIN_MOTION_DEG, lt=360, description="fall angle beta_f [deg]")
    rise_law: MotionLaw = MotionLaw.cycloidal
    fall_law: MotionLaw = MotionLaw.cycloidal

    @property
    def low_dwell_deg(self) -> float:
        """beta_l = 360 - beta_r - beta_h - beta_f [deg]."""
        return 360.0 - self.rise_deg - self.high_dwell_deg - self.fall_deg

    @model_validator(mode="after")
    def _fits_in_a_turn(self) -> ClassicMotion:
        if self.low_dwell_deg < -1e-9:
            raise ValueError(
                f"rise_deg + high_dwell_deg + fall_deg = "
                f"{360 - self.low_dwell_deg:g} deg exceeds 360 deg by "
                f"{-self.low_dwell_deg:g} deg (the low dwell beta_l must be >= 0, Eq. 27)"
            )
        return self

    def to_segments(self) -> list[dict]:
        low = max(0.0, self.low_dwell_deg)
        return [
            {
                "kind": "rise",
                "angle_deg": self.rise_deg,
                "lift_mm": self.lift_mm,
                "law": self.rise_law.value,
            },
            {"kind": "dwell", "angle_deg": self.high_dwell_deg},
            {
                "kind": "fall",
                "angle_deg": self.fall_deg,
                "lift_mm": self.lift_mm,
                "law": self.fall_law.value,
            },
            {"kind": "dwell", "angle_deg": low},
        ]


CLASSIC_KEYS = frozenset(ClassicMotion.model_fields)
MAX_SEGMENTS = 48  # a program of more pieces is not a cam a machine runs


class SegmentKind(StrEnum):
    rise = "rise"
    fall = "fall"
    dwell = "dwell"


class MotionSegment(_Part):
    """One piece of a motion program: a rise or fall of ``lift_mm`` over ``angle_deg``
    with a law, or a dwell (no lift, no law)."""

    kind: SegmentKind
    angle_deg: float = Field(ge=0, le=360, description="cam angle the segment spans [deg]")
    lift_mm: float | None = Field(
        None, ge=MIN_LENGTH_MM, le=1000, description="rise/fall: its lift [mm] (> 0)"
    )
    law: MotionLaw | None = Field(None, description="rise/fall: the law (default cycloidal)")

    @model_validator(mode="after")
    def _complete(self) -> MotionSegment:
        if self.kind is SegmentKind.dwell:
            if self.lift_mm is not None or self.law is not None:
                raise ValueError("a dwell has no lift_mm and no law")
            return self
        if self.lift_mm is None:
            raise ValueError(f"lift_mm: a {self.kind.value} needs its lift (> 0 mm)")
        if self.angle_deg < MIN_MOTION_DEG:
            raise ValueError(
                f"angle_deg: a {self.kind.value} spans at least "
                f"{MIN_MOTION_DEG} deg, got {self.angle_deg:g}"
            )
        if self.law is None:
            self.__dict__["law"] = MotionLaw.cycloidal
        return self

    @property
    def signed_lift_mm(self) -> float:
        return {"rise": 1.0, "fall": -1.0, "dwell": 0.0}[self.kind.value] * (self.lift_mm or 0.0)


def _paper_program() -> list[MotionSegment]:
    return [MotionSegment.model_validate(g) for g in ClassicMotion().to_segments()]


class Motion(_Part):
    """The motion program: segments (rise, fall, dwell) that fill 360 deg, in order from
    theta = 0, whose lifts close the cycle. The lowest displacement of the program is
    S = 0, on the base circle.

    The paper's program (rise, high dwell, fall, low dwell) may also be given in its
    classic form (lift_mm, rise_deg, high_dwell_deg, fall_deg, rise_law, fall_law: the
    format 1 ``motion``); those keys next to ``segments`` edit a classic program."""

    segments: list[MotionSegment] = Field(
        default_factory=_paper_program, min_length=1, max_length=MAX_SEGMENTS
    )

    @model_validator(mode="before")
    @classmethod
    def _classic_form(cls, data):
        if not isinstance(data, dict) or not (CLASSIC_KEYS & data.keys()):
            return data
        flat = {k: data[k] for k in CLASSIC_KEYS & data.keys()}
        for k, v in flat.items():  # as strict as the rest of a design file: no "15", true
            if k.endswith(("_mm", "_deg")) and (
                isinstance(v, bool) or not isinstance(v, int | float)
            ):
                raise _type_error(f"{k}: a number is required, got {printable(repr(v), 60)}")
        rest = {k: v for k, v in data.items() if k not in CLASSIC_KEYS}
        if "segments" in rest:  # edit the classic program the segments hold
            current = classic_of(rest["segments"])
            if current is None:
                raise _type_error(
                    f"{', '.join(sorted(flat))}: these edit a rise-dwell-fall-dwell "
                    "program; this one has other segments, so edit motion.segments"
                )
            flat = {**current, **flat}
        return {**rest, "segments": ClassicMotion.model_validate(flat).to_segments()}

    @model_validator(mode="after")
    def _closes(self) -> Motion:
        total = sum(g.angle_deg for g in self.segments)
        if abs(total - 360.0) > 1e-6:
            raise ValueError(
                f"segments: the angles sum to {total:g} deg, not 360 deg "
                f"({'over' if total > 360 else 'short'} by "
                f"{abs(total - 360):g} deg)"
            )
        net = sum(g.signed_lift_mm for g in self.segments)
        scale = sum(g.lift_mm or 0.0 for g in self.segments)
        if abs(net) > 1e-9 * max(scale, 1.0):
            raise ValueError(
                f"segments: the lifts do not close the cycle (rises minus "
                f"falls = {net:g} mm, must be 0)"
            )
        if scale == 0.0:
            raise ValueError("segments: a program needs at least one rise and one fall")
        return self

    @property
    def classic(self) -> ClassicMotion | None:
        """The program as the paper's rise-dwell-fall-dwell, or None if it is not one."""
        flat = classic_of(self.segments)
        return None if flat is None else ClassicMotion.model_validate(flat)

    def _classic(self, name: str):
        c = self.classic
        if c is None:
            raise ValueError(f"motion.{name}: this program is not rise-dwell-fall-dwell")
        return getattr(c, name)

    @property
    def lift_mm(self) -> float:
        """The largest displacement of the program [mm] (the paper's h)."""
        S = s_max = 0.0
        low = 0.0
        for g in self.segments:
            S += g.signed_lift_mm
            s_max, low = max(s_max, S), min(low, S)
        return s_max - low

    @property
    def rise_deg(self) -> float:
        return self._classic("rise_deg")

    @property
    def high_dwell_deg(self) -> float:
        return self._classic("high_dwell_deg")

    @property
    def fall_deg(self) -> float:
        return self._classic("fall_deg")

    @property
    def low_dwell_deg(self) -> float:
        return self._classic("low_dwell_deg")

    @property
    def rise_law(self) -> MotionLaw:
        return self._classic("rise_law")

    @property
    def fall_law(self) -> MotionLaw:
        return self._classic("fall_law")


def classic_of(segments) -> dict | None:
    """The classic keys of a rise-dwell-fall-dwell program (segments as models or
    dicts), or None. A program of rise, fall (no dwells) or with one dwell missing is
    classic too when it starts with the rise."""

    def get(g, k):
        return g.get(k) if isinstance(g, dict) else getattr(g, k)

    kinds = [str(get(g, "kind")).removeprefix("SegmentKind.") for g in segments]
    if not kinds or kinds[0] != "rise":
        return None
    motions = [i for i, k in enumerate(kinds) if k != "dwell"]
    if [kinds[i] for i in motions] != ["rise", "fall"] or len(segments) > 4:
        return None
    i_fall = motions[1]
    if i_fall > 2 or (len(segments) == 4 and i_fall != 2):
        return None
    rise, fall = segments[0], segments[i_fall]
    if get(rise, "lift_mm") != get(fall, "lift_mm"):
        return None
    high = sum(float(get(g, "angle_deg")) for g in segments[1:i_fall])

    def law(g):
        return get(g, "law") or MotionLaw.cycloidal

    return {
        "lift_mm": get(rise, "lift_mm"),
        "rise_deg": float(get(rise, "angle_deg")),
        "high_dwell_deg": high,
        "fall_deg": float(get(fall, "angle_deg")),
        "rise_law": MotionLaw(law(rise)),
        "fall_law": MotionLaw(law(fall)),
    }


class Follower(_Part):
    """Translating follower. Radii are signed as in the paper: r_f < 0 is concave."""

    kind: FollowerKind = FollowerKind.double_concave
    roller_radius_mm: float = Field(
        8.0, ge=MIN_LENGTH_MM, le=1000, description="roller radius r_c [mm]"
    )
    face_radius_mm: float = Field(
        -250.0, lt=0, ge=-100000, description="face radius r_f [mm], negative = concave"
    )
    offset_mm: float = Field(
        10.0,
        ge=0,
        le=1000,
        description="offset e of each face/roller of a double follower [mm]; "
        "single followers run on the stem centreline (e = 0), as in the paper",
    )

    single_offset_mm: float = Field(
        0.0,
        ge=-1000,
        le=1000,
        description="offset e_s of a single follower's axis from the cam centre [mm]: "
        "positive to the left (-X in Fig. 2), the side that lowers the rise's pressure "
        "angle for the clockwise cam (and raises the fall's) while e_s stays below "
        "about the rise's largest V (beyond, the resting follower's lean "
        "atan(e_s / Y_C) raises it again); 0 = on the centreline, as in the paper. "
        "Double followers use offset_mm",
    )

    @field_validator("offset_mm", "single_offset_mm")
    @classmethod
    def _no_negative_zero(cls, v: float) -> float:
        return v + 0.0  # -0.0 mm is 0 mm (it printed psi_h = -0.0)

    @property
    def radius_mm(self) -> float:
        """Signed radius of the active kind: r_c > 0 for rollers, r_f < 0 for concave
        faces, +inf for a flat face, 0 for a knife edge."""
        if self.kind.is_roller:
            return self.roller_radius_mm
        if self.kind.is_concave:
            return self.face_radius_mm
        return math.inf if self.kind is FollowerKind.flat_face else 0.0

    @property
    def stem_x_mm(self) -> float:
        """World X of a single follower's axis [mm] (-e_s); 0 for double followers."""
        return 0.0 if self.kind.is_double else -self.single_offset_mm + 0.0

    @property
    def effective_offset_mm(self) -> float:
        return self.offset_mm if self.kind.is_double else 0.0


FLAT_SHARE = (0.55, 0.98)  # a D flat's size across it: of the bore diameter


class Cam(_Part):
    """The disk cam. It turns clockwise, as in the paper."""

    base_radius_mm: float = Field(
        80.0, ge=MIN_LENGTH_MM, le=10000, description="base radius r_b [mm]"
    )
    width_mm: float = Field(
        15.0, ge=MIN_LENGTH_MM, le=10000, description="cam and contact width w [mm]"
    )
    speed_rpm: float = Field(1200.0, gt=0, le=100000, description="cam speed [rpm]")
    bore_diameter_mm: float = Field(
        0.0,
        ge=0,
        le=20000,
        description="shaft bore of the exported solid [mm]; 0 = a solid blank",
    )

    keyway_width_mm: float = Field(
        0.0,
        ge=0,
        le=5000,
        description="width b of a keyway in the bore [mm]; 0 = none. It is centred on "
        "the theta = 0 ray (the DXF's datum: where the follower sits at theta = 0)",
    )
    keyway_depth_mm: float = Field(
        0.0,
        ge=0,
        le=5000,
        description="depth t2 of the keyway into the hub, beyond the bore radius [mm]",
    )
    bore_flat_mm: float = Field(
        0.0,
        ge=0,
        le=20000,
        description="a D-shaped bore for a D shaft: the size across its flat [mm], 0.55 "
        "to 0.98 of the bore diameter (e.g. 4.5 for a 5 mm shaft), the flat facing the "
        "theta = 0 ray; 0 = a round bore",
    )
    cutter_diameter_mm: float = Field(
        10.0,
        gt=0,
        le=500,
        description="diameter D of the end mill for the toolpath export [mm]",
    )
    pass_depth_mm: float = Field(
        0.0,
        ge=0,
        le=10000,
        description="largest depth of cut per pass of the toolpath export [mm]; 0 = the "
        "whole depth in one pass. The passes are equal, as few as this allows",
    )
    breakthrough_mm: float = Field(
        0.0,
        ge=0,
        le=100,
        description="how far the toolpath's last pass goes below the blank's bottom face "
        "[mm]; 0 = to the cam width exactly (a thin skin may stay)",
    )
    feed_mm_per_min: float = Field(
        200.0,
        ge=1,
        le=100000,
        description="the toolpath's cutting feed F along the contour [mm/min] (set it for "
        "your machine, cutter and material)",
    )
    plunge_mm_per_min: float = Field(
        50.0,
        ge=1,
        le=100000,
        description="the toolpath's plunge feed F down into the blank [mm/min]",
    )
    spindle_rpm: float = Field(
        0.0,
        ge=0,
        le=200000,
        description="the toolpath's spindle speed S [rpm]; 0 = none written (M3 without "
        "S: the operator sets it, and the G-code's header says so), else at least 1",
    )
    safe_height_mm: float = Field(
        5.0,
        ge=0.5,
        le=1000,
        description="the toolpath's rapid height above the blank's top face [mm]: above "
        "every clamp",
    )

    @property
    def cut_depth_mm(self) -> float:
        """How deep the toolpath cuts: the cam width and the breakthrough [mm]."""
        return self.width_mm + self.breakthrough_mm

    @property
    def passes(self) -> int:
        """The toolpath's passes: as few equal ones as pass_depth_mm allows (a ratio a
        rounding error above a whole number counts as that number)."""
        if self.pass_depth_mm == 0:
            return 1
        ratio = min(self.cut_depth_mm / self.pass_depth_mm, 1e9)  # (a tiny depth: inf)
        return max(1, math.ceil(ratio - 1e-9))

    @model_validator(mode="after")
    def _bore_inside_base_circle(self) -> Cam:
        if self.bore_diameter_mm >= 2 * self.base_radius_mm:
            raise ValueError(
                f"bore_diameter_mm = {self.bore_diameter_mm:g} mm must be below the base "
                f"circle's diameter 2 r_b = {2 * self.base_radius_mm:g} mm"
            )
        if 0 < self.spindle_rpm < 1:  # (it would be written as S0.5, or S5e-05)
            raise ValueError(
                f"spindle_rpm = {self.spindle_rpm:g}: 0 (none written) or at least 1 rpm"
            )
        if self.bore_flat_mm > 0:
            if self.bore_diameter_mm == 0:
                raise ValueError("bore_flat_mm: a flat needs a bore (bore_diameter_mm > 0)")
            if self.keyway_width_mm > 0:
                raise ValueError("bore_flat_mm: a flat or a keyway, not both")
            lo, hi = (f * self.bore_diameter_mm for f in FLAT_SHARE)
            if not lo <= self.bore_flat_mm <= hi:
                raise ValueError(  # (a review: 0.99999 D had made a DXF bulge of 7.5e7)
                    f"bore_flat_mm = {self.bore_flat_mm:g} mm must lie between "
                    f"{FLAT_SHARE[0]:g} and {FLAT_SHARE[1]:g} x the bore diameter "
                    f"({lo:g} to {hi:g} mm)"
                )
        if (self.keyway_width_mm > 0) != (self.keyway_depth_mm > 0):
            raise ValueError("keyway_width_mm and keyway_depth_mm: give both, or neither")
        if self.keyway_width_mm > 0:
            if self.bore_diameter_mm == 0:
                raise ValueError("keyway_width_mm: a keyway needs a bore (bore_diameter_mm > 0)")
            if self.keyway_width_mm >= self.bore_diameter_mm * 0.9:
                raise ValueError(
                    f"keyway_width_mm = {self.keyway_width_mm:g} mm must be below 0.9 x the "
                    f"bore diameter ({0.9 * self.bore_diameter_mm:g} mm)"
                )
            top = self.bore_diameter_mm / 2 + self.keyway_depth_mm
            if math.hypot(top, self.keyway_width_mm / 2) >= self.base_radius_mm:
                raise ValueError(
                    f"keyway_depth_mm: the keyway's corners reach "
                    f"{math.hypot(top, self.keyway_width_mm / 2):g} mm from the axis, "
                    f"past the base radius r_b = {self.base_radius_mm:g} mm"
                )
        return self


class Dynamics(_Part):
    """Spring, mass and guide of the follower (Section 5, Eqs. 29-41)."""

    mass_g: float = Field(108.0, gt=0, le=1e7, description="effective follower mass M [g]")
    spring_rate_N_per_m: float = Field(6772.5, ge=0, le=1e9, description="spring rate k [N/m]")
    preload_mm: float = Field(5.0, ge=0, le=1e4, description="initial compression s_p [mm]")
    guide_friction: float = Field(0.1, ge=0, le=1.0, description="guide friction mu [-]")
    guide_width_mm: float = Field(
        8.0, ge=MIN_LENGTH_MM, le=1e4, description="stem/guide width d [mm]"
    )
    guide_length_mm: float = Field(
        80.0, ge=MIN_LENGTH_MM, le=1e5, description="guide length l2 [mm]"
    )
    overhang_mm: float = Field(30.0, ge=0, le=1e5, description="initial overhang l1 [mm]")
    gravity_m_s2: float = Field(
        9.81, ge=0, le=1000, description="g along the follower axis; 0 drops weight from Eq. 29"
    )
    external_load_N: float = Field(
        0.0,
        ge=-1e6,
        le=1e6,
        description="a constant load on the follower along its axis, toward the cam [N] "
        "(a process force, a cylinder; negative: pulling it off the cam); it adds to F_t "
        "of Eq. 29 as the weight does (0 as in the paper)",
    )
    overhang_shrinks: bool = Field(
        True, description="l1 = l1_0 - S (the stem slides further into the guide as it rises)"
    )
    contact_friction: float = Field(
        0.0,
        ge=0,
        le=1.0,
        description="sliding friction mu_c at the cam-face contact (0 as in the paper; "
        "rollers roll and ignore it)",
    )
    train_stiffness_N_per_m: float | None = Field(
        None,
        gt=0,
        le=1e12,
        description="stiffness k_1 of the follower train between the cam contact and the "
        "follower mass [N/m]; empty = rigid follower (the paper's model)",
    )
    damping_ratio: float = Field(
        0.05, ge=0, le=2.0, description="damping ratio zeta of the follower train"
    )
    spring_mass_g: float = Field(
        0.0,
        ge=0,
        le=1e7,
        description="return spring's own mass [g]; a third of it moves with the follower "
        "(in every model: the forces of Eq. 29, the jump speed, the elastic train)",
    )
    spring_safety_factor: float = Field(
        1.5,
        ge=1.0,
        le=100.0,
        description="proposed spring: its force is this many times the force that just "
        "keeps contact, at every angle (1 = on the edge of jump)",
    )
    speed_fluctuation: float = Field(
        0.02,
        gt=0,
        le=1.0,
        description="allowed speed fluctuation C_s = (w_max - w_min)/w of the shaft, "
        "for the flywheel inertia",
    )


class MaterialGrade(StrEnum):
    """The cam's surface material: it sets the default allowable contact stress."""

    case_hardened_steel = "case_hardened_steel"
    through_hardened_steel = "through_hardened_steel"
    mild_steel = "mild_steel"
    cast_iron = "cast_iron"
    bronze = "bronze"


# Allowable Hertz contact stress [MPa] for ~1e8 cycles of a lubricated cam/follower
# line contact, by the cam's surface. Order-of-magnitude design values of the cam
# literature (surface-fatigue strengths of the common cam materials, e.g. Rothbart,
# Cam Design Handbook, ch. on cam materials; Norton, Cam Design and Manufacturing
# Handbook, ch. 12): a default to start from, to be replaced by the supplier's figure
# (limits.allowable_contact_stress_MPa).
ALLOWABLE_CONTACT_STRESS_MPa = {
    MaterialGrade.case_hardened_steel: 1500.0,  # 58-62 HRC
    MaterialGrade.through_hardened_steel: 1000.0,  # ~300 HB
    MaterialGrade.mild_steel: 550.0,  # ~150 HB
    MaterialGrade.cast_iron: 500.0,  # grey iron ~200 HB
    MaterialGrade.bronze: 350.0,
}


class Material(_Part):
    """Elastic constants for the Hertz stress (Eq. 42), and the cam's surface grade."""

    grade: MaterialGrade = Field(
        MaterialGrade.through_hardened_steel,
        description="cam surface; sets the default allowable contact stress (not E or nu: "
        "set cam_E_GPa and cam_nu for the material)",
    )

    cam_E_GPa: float = Field(
        210.0, ge=MIN_MODULUS_GPa, le=2000, description="Young's modulus E1 of the cam"
    )
    cam_nu: float = Field(0.29, ge=0, lt=0.5, description="Poisson's ratio nu1 of the cam")
    follower_E_GPa: float = Field(
        210.0, ge=MIN_MODULUS_GPa, le=2000, description="E2 of the follower"
    )
    follower_nu: float = Field(0.29, ge=0, lt=0.5, description="nu2 of the follower")


class Wear(_Part):
    """Constants of the wear and surface-fatigue estimates (camcore.wear; not from the
    paper). Order-of-magnitude defaults for lubricated hardened steel: replace them with
    measured values for a real pair."""

    coefficient_mm3_per_N_m: float = Field(
        1e-8,
        ge=0,
        le=1.0,
        description="Archard specific wear rate k of the cam surface [mm^3/(N m)] "
        "(lubricated hardened steel ~1e-9 to 1e-7, dry steel ~1e-5)",
    )
    pitting_reference_cycles: float = Field(
        1e8,
        gt=0,
        le=1e15,
        description="cycles at which the allowable contact stress is the surface-fatigue strength",
    )
    pitting_exponent: float = Field(
        13.2,
        gt=1,
        le=100,
        description="slope m of the contact-stress life curve N = N_ref (sigma_allow / "
        "sigma)^m (13.2: ISO 6336-2 for case-hardened steel)",
    )


class Limits(_Part):
    """User-set design limits (not from the paper)."""

    max_pressure_angle_deg: float = Field(30.0, gt=0, lt=90, description="max |phi| [deg]")
    resolution_deg: float = Field(
        0.1, ge=0.01, le=5.0, description="cam-angle step of the analysis [deg]"
    )
    export_tolerance_mm: float = Field(
        0.001,
        ge=1e-5,
        le=1.0,
        description="largest deviation of the exported profile's chords from the exact "
        "cam [mm] (default 1 um)",
    )
    allowable_contact_stress_MPa: float | None = Field(
        None,
        gt=0,
        le=1e5,
        description="allowable Hertz stress [MPa]; empty = the default of material.grade",
    )
    require_continuous_acceleration: bool = Field(
        True,
        description="report a jump in acceleration (an infinite jerk) where "
        "segments meet as a broken limit; off accepts it (e.g. simple harmonic laws)",
    )
    contact_stress_safety_factor: float = Field(
        1.25,
        ge=1.0,
        le=10.0,
        description="the maximum Hertz stress times this must stay within the allowable",
    )
    min_jump_speed_ratio: float | None = Field(
        None,
        ge=1.0,
        le=100.0,
        description="the rigid follower must keep contact up to this many times the "
        "cam speed (its jump speed, Eq. 29, / the speed; the elastic train is checked at "
        "the speed itself); empty = only at the speed itself",
    )
    max_outer_diameter_mm: float | None = Field(
        None,
        gt=0,
        le=1e5,
        description="the largest the cam may be across (its envelope, or the stock it is "
        "cut from) [mm]; empty = not checked",
    )
    min_hub_wall_mm: float = Field(
        2.0,
        ge=0.0,
        le=1000.0,
        description="thinnest material allowed between the shaft bore (and keyway) and "
        "the profile [mm]; checked when there is a bore",
    )


class Design(_Part):
    """A complete disk-cam design. Save with :func:`save_design`, load with :func:`load_design`."""

    schema_version: Literal[2] = SCHEMA_VERSION
    name: str = Field("untitled", max_length=NAME_MAX)
    motion: Motion = Motion()
    follower: Follower = Follower()
    cam: Cam = Cam()
    dynamics: Dynamics = Dynamics()
    material: Material = Material()
    wear: Wear = Wear()
    limits: Limits = Limits()

    @field_validator("name")
    @classmethod
    def _printable_name(cls, v: str) -> str:
        """A name prints in files, terminals and the app: its control and format
        characters are dropped, a line break or tab made a space (a review: a pasted
        U+FEFF broke the PDF, and ESC sequences in a name could rewrite a terminal's
        report, e.g. hide its violations). Dropped, not refused: a design kept in a
        browser or a file under such a name still opens (nothing a user made is lost)."""
        return "".join(
            (" " if ch.isspace() else "")
            if unicodedata.category(ch) in NAME_REFUSED and ch not in NAME_JOINERS
            else ch
            for ch in v
        )

    @model_validator(mode="after")
    def _equations_can_be_evaluated(self) -> Design:
        """Geometry for which Eqs. 3 and 20 have no real answer is not a design."""
        f, rb, h = self.follower, self.cam.base_radius_mm, self.motion.lift_mm
        if f.kind is FollowerKind.flat_face:
            return self  # the face is a line at r_b + S: any offset, any lift
        r = f.radius_mm
        e, field = (
            (f.offset_mm, "offset_mm")
            if f.kind.is_double
            else (abs(f.single_offset_mm), "single_offset_mm")
        )
        if f.kind.is_concave and -r <= rb:
            raise ValueError(
                f"follower.face_radius_mm: |r_f| = {-r:g} mm must exceed the base radius "
                f"r_b = {rb:g} mm (a concave face must wrap the cam, Eq. 3)"
            )
        reach = abs(r + rb)
        if e >= reach * (1.0 - 1e-9):  # margin: e == |r + r_b| to round-off puts C on O's level
            # (a teacher's review read "|r + r_b|" blamed on the offset for r_f = -90 mm)
            what, fix = (
                ("|r_f| - r_b", "a smaller offset, or a flatter face (a larger |r_f|)")
                if f.kind.is_concave
                else ("r_c + r_b" if r > 0 else "r_b", "a smaller offset, or a larger r_b")
            )
            raise ValueError(
                f"follower.{field}: {'e' if f.kind.is_double else '|e_s|'} = {e:g} mm "
                f"must be below {what} = {reach:g} mm "
                f"(the square root in Eq. 3 needs (r + r_b)^2 - e^2 > 0): {fix}"
            )
        if f.kind.is_concave:
            l0 = math.sqrt(reach**2 - e**2)
            if h >= l0 * (1.0 - 1e-9):  # margin: h == L(0) to round-off in SI is L = 0
                raise ValueError(
                    f"motion.lift_mm: h = {h:g} mm must stay below L(0) = {l0:.3f} mm, the "
                    f"distance of the face centre below the cam axis (Eq. 3 needs L > 0)"
                )
        return self

    @model_validator(mode="before")
    @classmethod
    def _known_schema(cls, data):
        """Upgrade an older file through MIGRATIONS, or say exactly why it cannot load."""
        if not isinstance(data, dict) or "schema_version" not in data:
            return data
        v = data["schema_version"]
        if type(v) is not int:
            raise ValueError(
                f"schema_version: must be an integer, the file says {printable(repr(v), 60)}"
            )
        while v < SCHEMA_VERSION and v in MIGRATIONS:
            data = MIGRATIONS[v](dict(data))
            v = data["schema_version"] = v + 1
        if v < SCHEMA_VERSION:
            raise ValueError(
                f"schema_version: the file is format {v}, older than any this program "
                f"can upgrade (it reads format {SCHEMA_VERSION}"
                + (
                    f" and upgrades {sorted(MIGRATIONS)})"
                    if MIGRATIONS
                    else "; format 1 is the first published one)"
                )
            )
        if v > SCHEMA_VERSION:
            raise ValueError(
                f"schema_version: the file is format {v}, written by a newer program; "
                f"this one reads format {SCHEMA_VERSION}"
            )
        return data

    def with_kind(self, kind: FollowerKind | str) -> Design:
        """The same design with another follower kind (the comparison of Table 1).

        Re-validated: an offset that suits a roller may not suit a concave face.
        """
        data = self.model_dump()
        data["follower"]["kind"] = FollowerKind(kind)
        return name_follows_kind(Design.model_validate(data), self.follower.kind, self.name)


# how a design's name says its follower: what with_kind writes in place of the old one
KIND_PHRASES: Final = {
    FollowerKind.single_roller: "single roller",
    FollowerKind.double_roller: "double rollers",
    FollowerKind.single_concave: "single concave face",
    FollowerKind.double_concave: "double concave faces",
    FollowerKind.flat_face: "flat face",
    FollowerKind.knife_edge: "knife edge",
}


def _kind_mention(kind: FollowerKind) -> re.Pattern[str]:
    """How a name mentions ``kind``: its words ("double concave", "single_roller"),
    a plural or "face(s)" after them, as whole words (not "single concave-faced")."""
    words = r"[\s_-]+".join(map(re.escape, kind.value.split("_")))
    return re.compile(rf"\b{words}(?:s|\s+faces?)?(?![\w-])", re.IGNORECASE)


def renamed_for_kind(name: str, old: FollowerKind, new: FollowerKind) -> str:
    """``name`` with its mention of the ``old`` follower ("double concave", "double
    concave faces", "Single roller", ...) replaced by the ``new`` one's phrase (in the
    mention's case), so a header does not name one follower over another's part.
    Unchanged if it names no follower (a user's own name) or more than one kind (a
    comparison), if the kind is the same, or if the new name would pass NAME_MAX."""
    if old == new or not _kind_mention(old).search(name):
        return name
    if any(_kind_mention(k).search(name) for k in FollowerKind if k != old):
        return name
    phrase = KIND_PHRASES[new]

    def keep_case(m: re.Match[str]) -> str:
        said = m.group(0)
        if said.isupper():
            return phrase.upper()
        return phrase[0].upper() + phrase[1:] if said[0].isupper() else phrase

    out = _kind_mention(old).sub(keep_case, name, count=1)
    return out if len(out) <= NAME_MAX else name


def name_follows_kind(design: Design, old_kind: FollowerKind | str, old_name: str) -> Design:
    """``design``, made from a design of ``old_kind`` named ``old_name``, with its name's
    follower renamed (renamed_for_kind) if its kind changed and its name did not: the
    one rule of with_kind, the CLI's --set, a sweep's grid and the app."""
    old = FollowerKind(old_kind)
    if design.follower.kind == old or design.name != old_name:
        return design
    name = renamed_for_kind(design.name, old, design.follower.kind)
    return design if name == design.name else design.model_copy(update={"name": name})


class DesignError(ValueError):
    """A design file or value that cannot be used; the message says why, in one line."""


MAX_JSON_DEPTH = 8  # a design nests three deep; deeper documents are not designs


class _JsonObject(dict):
    """A JSON object that remembers the keys it saw twice (json.loads keeps the last)."""

    duplicates: list[str]


def _object_pairs(pairs: list[tuple[str, object]]) -> _JsonObject:
    obj = _JsonObject(pairs)
    seen: set[str] = set()
    obj.duplicates = []
    for k, _ in pairs:
        if k in seen:
            obj.duplicates.append(k)
        seen.add(k)
    return obj


class _NonFinite(str):
    """Marks a NaN/Infinity literal so that _check_tree can name its field."""


def _non_finite(name: str) -> _NonFinite:
    return _NonFinite(name)


def _check_tree(node, path: str = "", depth: int = 1) -> None:
    """Refuse duplicate keys (naming the field) and nesting deeper than MAX_JSON_DEPTH."""
    if depth > MAX_JSON_DEPTH:
        raise DesignError(f"{path or 'the document'}: nested deeper than {MAX_JSON_DEPTH} levels")
    if isinstance(node, _NonFinite):
        raise DesignError(
            f"{path or 'the document'}: {node} is not a number a design may hold "
            "(it must be finite)"
        )
    if isinstance(node, dict):
        duplicates = getattr(node, "duplicates", None)
        if duplicates:
            key = duplicates[0]
            raise DesignError(f"{path + '.' if path else ''}{key}: the key appears twice")
        for key, value in node.items():
            _check_tree(value, f"{path}.{key}" if path else str(key), depth + 1)
    elif isinstance(node, list):
        for i, value in enumerate(node):
            _check_tree(value, f"{path}.{i}", depth + 1)


def json_document(text: str | bytes):
    """``text`` parsed as JSON, strictly (a key twice, NaN and Infinity refused), or a
    DesignError that says where and why in words, never Python's own advice."""
    try:
        return json.loads(text, object_pairs_hook=_object_pairs, parse_constant=_non_finite)
    except json.JSONDecodeError as exc:  # where the file stops being JSON, in words
        what = exc.msg.lower().removesuffix(" at")  # ("unterminated string starting at")
        raise DesignError(
            f"not a JSON document: {what} at line {exc.lineno}, column {exc.colno}"
        ) from None
    except (ValueError, RecursionError) as exc:
        if "integer string conversion" in str(exc):  # (Python's advice, not the user's:
            raise DesignError(  # a CLI review)
                "a JSON number of more than 4300 digits (no field takes one)"
            ) from None
        raise DesignError(f"not a JSON document: {str(exc)[:200]}") from None


def design_from_json(text: str | bytes) -> Design:
    """Parse a design JSON document strictly, turning every failure into a one-line DesignError.

    Strict means: a key given twice, a number written as a string ("15") or a
    boolean, NaN/Infinity, and nesting deeper than MAX_JSON_DEPTH are refused
    with the field's dotted path, never silently coerced or overwritten.
    """
    from pydantic import ValidationError

    if len(text) > MAX_DESIGN_BYTES:
        raise DesignError(f"design file is {len(text)} bytes; the limit is {MAX_DESIGN_BYTES}")
    if isinstance(text, bytes):  # (a review: an STL said "'utf-8' codec can't decode")
        try:
            text = text.decode(json.detect_encoding(text))  # (as json.loads: a BOM too)
        except UnicodeDecodeError:
            raise DesignError(
                "not a text file: a design is a JSON text file (this one looks like a "
                "binary file, such as an STL or an image)"
            ) from None
    if not text.strip():
        raise DesignError("the file is empty: a design is a JSON text file")
    data = json_document(text)
    if not isinstance(data, dict):
        raise DesignError(f"a design is a JSON object, got {type(data).__name__}")
    _check_tree(data)
    try:
        # JSON-mode strict validation: no str->number or bool->number coercion,
        # while enum fields still take their string values.
        return Design.model_validate_json(json.dumps(data), strict=True)
    except ValidationError as exc:
        raise DesignError(format_validation_error(exc)) from None


def format_validation_error(exc) -> str:
    """One line per problem: 'field.path: message'."""
    parts = []
    for err in exc.errors()[:8]:
        loc = ".".join(printable(str(p), 60) for p in err["loc"])  # (a file's own keys)
        msg = err["msg"].removeprefix("Value error, ")
        head, sep, tail = msg.partition(": ")
        if loc and sep and head.replace(".", "").replace("_", "").isalnum():
            loc, msg = f"{loc}.{head}", tail  # a validator naming a field inside loc
        elif loc and (shown := _shown_value(err.get("input"))) is not None:
            if loc in BOUND_MEANS and err["type"] in ("less_than", "greater_than"):
                msg = f"{msg}, {BOUND_MEANS[loc]}"
            msg = f"{msg} (got {shown})"  # the value refused, as the user wrote it
        parts.append(f"{loc}: {msg}" if loc else msg)
    return "; ".join(parts)


# what a bound on a field means, said after pydantic's own words (a teacher's review:
# "Input should be less than 0" for a positive face radius)
BOUND_MEANS = {
    "follower.face_radius_mm": "a concave face's radius is negative, r_f < 0 (Eq. 3)",
}


def _shown_value(x) -> str | None:
    """A refused value as the error quotes it: a number or a short plain word; None for
    anything else (the app splits the errors at '; ' and the field at ': ')."""
    if isinstance(x, bool):
        return json.dumps(x)
    if isinstance(x, int) and abs(x) > 1e300:  # (a 400-digit integer: float() fails)
        return None
    if isinstance(x, int | float):  # (a 50-digit integer as a number, not cut short)
        return json.dumps(x) if len(json.dumps(x)) <= 24 else f"{float(x):.6g}"
    if isinstance(x, str) and re.fullmatch(r"[A-Za-z0-9_. +-]{1,40}", x):
        return json.dumps(x)
    return None


GROUPS = ("cam", "follower", "dynamics", "material", "wear", "limits")  # of fields (motion's
# own: its classic form or its segments)


def field_table() -> list[dict]:
    """Every field a design file or ``--set`` can give, as rows {"path", "default",
    "range", "description", "followers"} (a designer's review: only a misspelled
    ``--set`` had listed a group's fields). The motion's are its classic form's
    (motion.lift_mm, ...) and a program segment's (motion.segments.N.kind, ...);
    "followers": the kinds that use a follower field (FollowerKind.uses), else None."""
    defaults = Design()
    rows = []

    def add(path: str, field, default, group: str = "") -> None:
        bounds = []
        for t in (field.annotation, *get_args(field.annotation)):  # (an Enum | None too)
            if isinstance(t, type) and issubclass(t, Enum):
                bounds.append("one of " + ", ".join(m.value for m in t))
        for m in field.metadata:
            for op, sign in (("ge", ">="), ("gt", ">"), ("le", "<="), ("lt", "<")):
                if getattr(m, op, None) is not None:
                    bounds.append(f"{sign} {getattr(m, op):g}")
        kinds = None
        if group == "follower" and path != "follower.kind":
            kinds = [k.value for k in FollowerKind if k.uses(path.rpartition(".")[2])]
        rows.append(
            {
                "path": path,
                "default": default.value if isinstance(default, Enum) else default,
                "range": ", ".join(bounds),
                "description": field.description or "",
                "followers": kinds,
            }
        )

    for group in GROUPS:
        part = getattr(defaults, group)
        for name, field in type(part).model_fields.items():
            add(f"{group}.{name}", field, getattr(part, name), group)
    classic = classic_of(defaults.motion.segments) or {}
    for name, field in ClassicMotion.model_fields.items():
        add(f"motion.{name}", field, classic.get(name))
    first = defaults.motion.segments[0]
    for name, field in MotionSegment.model_fields.items():
        add(f"motion.segments.N.{name}", field, getattr(first, name))
    rows.append(
        {
            "path": "name",
            "default": defaults.name,
            "range": f"at most {NAME_MAX} characters (control and format characters dropped)",
            "description": "the design's name (files, headers, the app's title)",
            "followers": None,
        }
    )
    return rows


def with_given(text: str | bytes, paths: list[str]) -> str:
    """The design document ``text`` with the fields at ``paths`` (dotted, as --set and
    a sweep grid give them) marked present, their values unchanged elsewhere: for
    defaulted_fields, none of them is a default. A whole group's path marks all its
    fields."""
    data = json.loads(text)
    groups = {g: type(getattr(Design(), g)) for g in GROUPS}
    for path in paths:
        group, _, name = path.partition(".")
        node = data.setdefault(group, {})
        if not isinstance(node, dict):
            continue
        if not name and group in groups:
            for field in groups[group].model_fields:
                node.setdefault(field, None)
        elif name and "." not in name:
            node.setdefault(name, None)
    return json.dumps(data)


def defaulted_fields(
    text: str | bytes, design: Design, kinds: tuple[FollowerKind, ...] = ()
) -> list[str]:
    """The inputs a design document leaves out, which took their default values (the
    paper example's where the paper gives one), as "path = value" ("dynamics (the
    whole group)" for a group left out). A hand-written file without a base radius is
    analysed at 80 mm, and the CLI and the app say so (a review: ``{}`` reported the
    paper example, "valid yes", without a word). ``design``: the design analysed.
    Not listed: the name, fields whose default is "unset" (None), follower fields the
    design's kind does not use (FollowerKind.uses), and a program of segments, which is
    whole or refused (a classic motion's keys left out are listed, _defaulted_classic).
    ``kinds``: the followers analysed, if more than the design's own (compare:
    a concave face's radius left out is its default there too, a designer's review)."""
    kinds = kinds or (design.follower.kind,)
    data = json.loads(text)
    out = []
    for group in type(design).model_fields:
        part = getattr(design, group)
        if not isinstance(part, BaseModel):
            continue  # schema_version, name
        if group not in data:
            out.append(f"{group} (the whole group)")
            continue
        if group == "motion":
            out += _defaulted_classic(data[group], design)
            continue
        if not isinstance(data[group], dict):
            continue
        for name, field in type(part).model_fields.items():
            if name in data[group] or field.default is None:
                continue
            if group == "follower" and not any(k.uses(name) for k in kinds):
                continue
            value = getattr(part, name)
            out.append(f"{group}.{name} = {value.value if isinstance(value, Enum) else value}")
    return out


def _defaulted_classic(motion, design: Design) -> list[str]:
    """defaulted_fields of a motion written in the classic form (no segments): the
    keys of the rise-dwell-fall-dwell it leaves out, as "motion.rise_deg = 100.0" (a
    review: ``{"motion": {"lift_mm": 16}}`` ran the paper's angles and laws unsaid)."""
    classic = design.motion.classic
    if not isinstance(motion, dict) or "segments" in motion or classic is None:
        return []
    out = []
    for name in ClassicMotion.model_fields:
        if name not in motion:
            value = getattr(classic, name)
            out.append(f"motion.{name} = {value.value if isinstance(value, Enum) else value}")
    return out


def read_design(path: str | Path) -> tuple[Design, str | bytes]:
    """A design file (a regular file of at most MAX_DESIGN_BYTES) read strictly, and
    its text (for defaulted_fields)."""
    from .files import FileError, read_capped

    try:
        text = read_capped(path, MAX_DESIGN_BYTES)
    except FileError as exc:
        raise DesignError(str(exc)) from None
    return design_from_json(text), text


def load_design(path: str | Path) -> Design:
    """Read a design file (a regular file of at most MAX_DESIGN_BYTES) strictly."""
    return read_design(path)[0]


def defaults_note(left_out: list[str], shown: int = 8, where: str = "the file") -> str:
    """One line saying which inputs took their defaults (defaulted_fields), or ""
    (``where``: the file that left them out)."""
    if not left_out:
        return ""
    more = f" (+{len(left_out) - shown} more)" if len(left_out) > shown else ""
    return f"not in {where}, so at their defaults: {'; '.join(left_out[:shown])}{more}"


def design_to_json(design: Design) -> str:
    """The design as JSON (format 2). Fields that are unset (a dwell's lift and law,
    an allowable stress left to the material's default) are left out."""
    return design.model_dump_json(indent=2, exclude_none=True)


def save_design(design: Design, path: str | Path) -> None:
    Path(path).write_text(design_to_json(design) + "\n")


PRESETS = "camcore.presets"  # package data: ships inside the wheel


def preset_names() -> list[str]:
    """The names of the presets shipped with the package, sorted."""
    from importlib.resources import files

    return sorted(p.name[:-5] for p in files(PRESETS).iterdir() if p.name.endswith(".json"))


def load_preset(name: str) -> Design:
    """The preset called *name*, looked up in the fixed set of shipped names.

    The name is compared against ``preset_names()`` and never joined onto a
    path, so a client-supplied value like ``../../x`` or ``/tmp/x`` cannot
    reach any other file.
    """
    from importlib.resources import files

    names = preset_names()
    if not isinstance(name, str) or name not in names:
        raise DesignError(f"no preset {str(name)[:40]!r}; presets: {', '.join(names)}")
    shipped = names[names.index(name)]  # the package's own string, not the client's
    return design_from_json(files(PRESETS).joinpath(shipped + ".json").read_bytes())


def _leaves(node, prefix: str = "") -> dict:
    """A design dump's values by dotted path, lists by index (set_field's paths:
    ``motion.segments.0.lift_mm``)."""
    if not isinstance(node, dict | list):
        return {prefix: node}
    items = node.items() if isinstance(node, dict) else enumerate(node)
    out: dict = {}
    for k, v in items:
        out.update(_leaves(v, f"{prefix}.{k}" if prefix else str(k)))
    return out


@functools.cache
def _shipped_leaves() -> dict[str, dict]:
    """Each preset's fields by dotted path (read once: the presets ship in the package)."""
    return {key: _leaves(load_preset(key).model_dump(mode="json")) for key in preset_names()}


def preset_edits(design: Design) -> tuple[str, list[str]] | None:
    """The shipped preset whose name ``design`` carries, and the fields it changes from
    that preset (dotted paths); None if it carries no preset's name, or is the preset.

    A name renamed for another follower (name_follows_kind: the comparison of Table 1)
    still names its preset, and then the kind is no edit: the name says it. Why: an
    edited preset keeps the preset's name, so a part cut from the paper example with
    another base radius was labelled as the paper's cam (edited_note says so).
    """
    ours = _leaves(design.model_dump(mode="json"))
    for key, theirs in _shipped_leaves().items():
        shipped, kind = theirs["name"], FollowerKind(theirs["follower.kind"])
        if design.name == shipped:
            skip = {"name"}
        elif design.name == renamed_for_kind(shipped, kind, design.follower.kind) != shipped:
            skip = {"name", "follower.kind"}
        else:
            continue
        paths = [*ours, *(p for p in theirs if p not in ours)]  # (a segment removed)
        changed = [p for p in paths if p not in skip and ours.get(p) != theirs.get(p)]
        return (key, changed) if changed else None
    return None


EDITS_NAMED = 3  # fields an edited preset's note names; more are counted


def edited_note(design: Design) -> str | None:
    """The note 'edited from preset KEY: field, ...' for a design that carries a shipped
    preset's name but is not that preset (preset_edits), else None: printed beside the
    name wherever a file names the design, so the part is not taken for the preset's."""
    edits = preset_edits(design)
    if edits is None:
        return None
    key, paths = edits
    # a program's segments are one edit: "motion.segments" (its fields' paths ran long)
    fields = list(
        dict.fromkeys(re.sub(r"^motion\.segments\..*", "motion.segments", p) for p in paths)
    )
    more = len(fields) - EDITS_NAMED
    named = ", ".join(fields[:EDITS_NAMED]) + (f" and {more} more" if more > 0 else "")
    return f"edited from preset {key}: {named}"


# --- SI conversion at the edge -------------------------------------------------------


def allowable_contact_stress_MPa(design: Design) -> float:
    """The allowable Hertz stress [MPa]: the user's figure, else the material grade's."""
    given = design.limits.allowable_contact_stress_MPa
    return given if given is not None else ALLOWABLE_CONTACT_STRESS_MPa[design.material.grade]


def contact_stress_limit_MPa(design: Design) -> float:
    """The largest contact stress the design may reach [MPa]: the allowable over the
    safety factor (the limit of checks' ``contact_stress``)."""
    return allowable_contact_stress_MPa(design) / design.limits.contact_stress_safety_factor


def omega_rad_s(design: Design) -> float:
    """Cam angular speed omega_2 [rad/s] (the magnitude; the cam turns clockwise)."""
    return design.cam.speed_rpm * RPM


def field_path(path: str) -> str:
    """A dotted field path with its list indexes as numbers ("segments.00" is
    "segments.0")."""
    return ".".join(  # (an index is 1-6 digits, as _child reads one)
        str(int(p)) if re.fullmatch(r"[0-9]{1,6}", p) else p for p in path.split(".")
    )


def is_classic_field(field: str) -> bool:
    """A classic program's field (motion.rise_deg, ...): Motion makes the segments of
    them, so it sets every part of motion.segments."""
    head, _, name = field.partition(".")
    return head == "motion" and name in CLASSIC_KEYS


PROGRAM_CLASH = "both set the motion program (its classic fields make its segments)"


def program_clash(a: str, b: str) -> bool:
    """Whether the field paths ``a`` and ``b`` (field_path) both set the motion
    program, one a classic field, the other a part of motion.segments: the classic
    one would make the segments and the other's edit be lost (a review: `--set
    motion.rise_deg=90 --set motion.segments.0.angle_deg=80` dropped the second)."""
    return (is_classic_field(a) and b.startswith("motion.segments")) or (
        is_classic_field(b) and a.startswith("motion.segments")
    )


def set_field(data: dict, path: str, value, what: str = "") -> None:
    """Write ``value`` at the dotted ``path`` of a design dict (``motion.segments.0.lift_mm``
    reaches into lists), refusing a path the design has no field at. ``what`` prefixes
    the messages (e.g. "--set "); the path is the user's (a spec's key), shown escaped
    and short."""
    keys = path.split(".")
    path = printable(path, 120)  # (for the messages only)
    if not all(keys):
        raise DesignError(f"{what}{path!r}: expected FIELD.PATH, e.g. cam.base_radius_mm")
    node = data
    for i, key in enumerate(keys[:-1]):
        node = _child(node, key, what, printable(".".join(keys[:i]), 120))
        if not isinstance(node, dict | list):
            head = printable(".".join(keys[: i + 1]), 120)
            raise DesignError(f"{what}{path}: {head} is not a group of fields")
    last = keys[-1]
    if isinstance(node, list):
        _child(node, last, what, printable(".".join(keys[:-1]), 120))  # the index must exist
        node[int(last)] = value
        return
    classic = keys[:-1] == ["motion"] and last in CLASSIC_KEYS  # edits a classic program
    if last not in node and not classic:
        raise DesignError(f"{what}{path}: no such field; fields here: {', '.join(node)}")
    node[last] = value


def _child(node, key: str, what: str = "", where: str = ""):
    """node[key] for a dict, node[int(key)] for a list; None if there is none. An
    index is ASCII digits, at most 6 of them (str.isdigit took "²", which int() then
    refused with a traceback, and 5,000 digits, which int() refuses too: a review)."""
    if isinstance(node, dict):
        return node.get(key)
    if isinstance(node, list) and re.fullmatch(r"[0-9]{1,6}", key) and int(key) < len(node):
        return node[int(key)]
    if isinstance(node, list):
        shown = key if len(key) <= 20 else key[:20] + "…"  # (a 5,000-digit one: a review)
        raise DesignError(  # (the list named: a CLI review)
            f"{what}{shown!r} is not an index of {where or 'the list'}, a list of {len(node)}"
        )
    return None
