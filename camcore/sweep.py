"""Design-space sweeps: many designs, one Parquet table (issue 12).

A SPEC names a base design and a grid of field values; the sweep analyses every
combination and writes one row per design: the grid values (columns ``grid.`` + the
field path, e.g. ``grid.cam.base_radius_mm``), ``valid``, ``error`` (why a combination is
not a design at all, else null) and the summary of ``camcore report --json``, flattened
with its keys joined by dots (``contact_force_max_N.cycle``; lists become JSON text).
A row equals the single report of that design.

    {"base": {...a design...} | {"preset": "paper_example"},
     "grid": {"cam.base_radius_mm": [60, 70, 80] | {"from": 60, "to": 110, "num": 51},
              "follower.kind": ["single_roller", "double_concave"]},
     "balance": "motion.segments.3.angle_deg"}

``balance`` (optional) names the segment angle that takes up the turn when the grid
varies other segments' angles: each point sets it to 360 deg less the others, so an
indexer's rise angle can be swept against its dwell (the program must fill 360 deg;
without it every such point is no design). A classic program's fields do this already
(the low dwell is the rest of the turn).

Work is cut into chunks of designs (batches, not single designs). Each finished chunk is
kept as a Parquet part beside the output (``OUT.parts/``) with the SPEC's fingerprint,
so an interrupted run resumes where it stopped; the parts are joined into OUT at the
end. Chunks run in this process by default, on a Dask ``LocalCluster`` with
``workers``, or on an existing Dask cluster at ``scheduler``: the same work either way.
"""

from __future__ import annotations

import contextlib
import hashlib
import itertools
import json
import math
import re
import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import code_fingerprint, package_version
from .files import (
    FileError,
    printable,
    read_capped,
    regular_file,
    write_atomic,
    write_target,
)
from .model import (
    PROGRAM_CLASH,
    Design,
    DesignError,
    FollowerKind,
    defaulted_fields,
    design_from_json,
    field_path,
    format_validation_error,
    is_classic_field,
    load_preset,
    name_follows_kind,
    program_clash,
    read_design,
    set_field,
    with_given,
)

MAX_SPEC_BYTES = 1_000_000
MAX_DESIGNS = 1_000_000  # designs per sweep
MAX_VALUES = 100_000  # values per grid axis
MAX_AXES = 300  # grid fields: more than a design has (63 and 4 a segment, 48 segments)
DEFAULT_CHUNK = 32
MAX_CHUNK = 512  # designs per chunk: the batched core holds ~2 MB a design (0.1 deg grid)
# grid samples the batched core takes at once (MAX_CHUNK designs at 0.1 deg, ~1 GB): a
# chunk of finer designs goes through it in parts (a review: 32 designs at 0.01 deg held
# 680 MB, ten times the designs' share at 0.1 deg)
BATCH_SAMPLES = MAX_CHUNK * 3601
SPEC_METADATA = "camcore.sweep"  # the table's key-value metadata: its SPEC (Spec.document)
VERSION_METADATA = "camcore.version"
CODE_METADATA = "camcore.code"  # camcore.code_fingerprint of the code that made the rows
MEMO_ROWS = 1024  # designs an in-process run remembers across its chunks (~10 kB a row)


@dataclass(frozen=True)
class Spec:
    """A parsed sweep: the base design as a dict and the grid axes (path, values)."""

    base: dict
    axes: tuple[tuple[str, tuple], ...]
    grid: object = field(default=None, compare=False)  # the grid as given (ranges kept)
    # a base design file's inputs left out, which took their defaults and no grid axis
    # gives (model.defaulted_fields): the command line says them, as report does
    defaulted: tuple[str, ...] = field(default=(), compare=False)
    # the base design file a {"file": NAME} base was read from (the command line
    # refuses to write its table over it)
    base_file: Path | None = field(default=None, compare=False)
    balance: str | None = None  # the segment angle that takes up the turn (see above)

    def document(self) -> str:
        """The spec as a SPEC document with its base resolved (a preset by its design):
        parse_spec reads it back to the same spec. Kept in the table it wrote, so the
        table says which design each row is (design_of_row)."""
        grid = self.grid if self.grid is not None else {p: list(v) for p, v in self.axes}
        balance = {} if self.balance is None else {"balance": self.balance}
        return json.dumps({"base": self.base, "grid": grid, **balance})

    @property
    def size(self) -> int:
        return math.prod(len(v) for _, v in self.axes)

    def fingerprint(self) -> str:
        balance = {} if self.balance is None else {"balance": self.balance}  # (a spec
        text = json.dumps(  # without one keeps its fingerprint)
            {"base": self.base, "axes": self.axes, **balance}, sort_keys=True
        )
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def points(self) -> Iterable[dict]:
        """Each combination as {path: value}, the last axis varying fastest."""
        names = [p for p, _ in self.axes]
        for combo in itertools.product(*(v for _, v in self.axes)):
            yield self._balanced(dict(zip(names, combo, strict=True)))

    def point(self, index: int) -> dict:
        """The combination number ``index`` of points(), without listing the others."""
        out = {}
        for path, values in reversed(self.axes):
            index, j = divmod(index, len(values))
            out[path] = values[j]
        return self._balanced(dict(reversed(out.items())))

    def _balanced(self, point: dict) -> dict:
        """``point`` with the balance segment's angle: 360 deg less the other segments'
        once the point is set (a value <= 0 makes the point no design, said in its
        row). A point that is no design to begin with is left as it is."""
        if self.balance is None:
            return point
        data = json.loads(json.dumps(self.base))
        try:
            for path, value in point.items():
                set_field(data, path, value, "grid.")
            segments = data["motion"]["segments"]
            i = int(self.balance.split(".")[2])
            others = sum(float(s["angle_deg"]) for k, s in enumerate(segments) if k != i)
        except (DesignError, KeyError, TypeError, ValueError, IndexError):
            return point
        return {**point, self.balance: 360.0 - others}

    def chunk(self, i: int, size: int) -> list[dict]:
        """Chunk ``i`` of ``size`` designs (the last one may be shorter)."""
        return [self.point(k) for k in range(i * size, min((i + 1) * size, self.size))]


def axis_values(path: str, raw) -> tuple:
    """A grid axis from a list of values or {"from", "to", "num"} (inclusive, linear)."""
    if isinstance(raw, dict):
        if set(raw) != {"from", "to", "num"}:
            raise DesignError(f'grid.{path}: a range is {{"from", "to", "num"}}')
        lo, hi, num = raw["from"], raw["to"], raw["num"]
        if not all(isinstance(x, int | float) and not isinstance(x, bool) for x in (lo, hi)):
            raise DesignError(f"grid.{path}: from and to must be numbers")
        if not all(_finite(x) for x in (lo, hi)):
            raise DesignError(f"grid.{path}: from and to must be finite numbers")
        if not math.isfinite(float(hi) - float(lo)):  # (linspace made NaN of it)
            raise DesignError(f"grid.{path}: from and to span more than a float holds")
        if not isinstance(num, int) or isinstance(num, bool) or not 1 <= num <= MAX_VALUES:
            raise DesignError(f"grid.{path}.num: an integer from 1 to {MAX_VALUES}")
        if num == 1 and lo != hi:  # (linspace gives "from" alone: "to" dropped unsaid)
            raise DesignError(
                f"grid.{path}: num 1 gives only from = {lo:g}, not to = {hi:g}; a range "
                f"needs num >= 2 (one value: a list [{lo:g}])"
            )
        values = tuple(float(x) for x in np.linspace(lo, hi, num))
        return _distinct(path, values, "; a range's from and to must differ")
    if not isinstance(raw, list) or not raw or len(raw) > MAX_VALUES:
        raise DesignError(f"grid.{path}: a list of 1 to {MAX_VALUES} values, or a range")
    return _distinct(path, _one_type(path, tuple(raw)))


def _distinct(path: str, values: tuple, hint: str = "") -> tuple:
    """``values`` unless one repeats: each would be a design computed and listed twice
    (a review: from = to with num 3, or a list [60, 60], ran identical rows unsaid)."""
    seen: set = set()
    for v in values:
        key = json.dumps(v, sort_keys=True) if isinstance(v, list | dict) else v
        if key in seen:
            shown = printable(repr(v), 60)
            raise DesignError(f"grid.{path}: the value {shown} comes twice; each value once{hint}")
        seen.add(key)
    return values


def _defaulted(text, design: Design, axes) -> tuple[str, ...]:
    """defaulted_fields of a base design file, less those a grid axis gives, for every
    follower kind the grid runs (model.with_given, as the command line's --set)."""
    kinds = {design.follower.kind}
    for path, values in axes:
        if path == "follower.kind":  # the grid's kinds replace the base's own
            kinds = {FollowerKind(v) for v in values if v in set(FollowerKind)} or kinds
    given = with_given(text, [path for path, _ in axes])
    return tuple(defaulted_fields(given, design, tuple(kinds)))


def _axis_size(raw) -> int:
    """How many values an axis as written would give (1 where it is malformed: axis_values
    then says what is wrong with it)."""
    if isinstance(raw, list):
        return max(len(raw), 1)
    num = raw.get("num") if isinstance(raw, dict) else None
    if not isinstance(num, int) or isinstance(num, bool) or num < 1:
        return 1
    return min(num, 10**15)  # (a 4,000-digit num: no 4,000-digit product to print)


def _kind(value) -> str:
    """A grid value's column type in the table (a list or object becomes JSON text)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, int | float):
        return "number"
    return "text" if isinstance(value, str) else "list or object"


def _finite(x: int | float) -> bool:
    """Finite, and within a float's range (an integer of 400 digits is not)."""
    return abs(x) <= sys.float_info.max if isinstance(x, int) else math.isfinite(x)


def _one_type(path: str, values: tuple) -> tuple:
    """An axis' values, all of one type (nulls aside: one column of the table), its
    numbers finite; integers mixed with floats, or too large for a 64-bit column,
    become floats."""
    kinds = {_kind(v) for v in values} - {"null"}
    if len(kinds) > 1:
        raise DesignError(
            f"grid.{path}: values of one type (one column of the table), got "
            f"{' and '.join(sorted(kinds))}"
        )
    numbers = [v for v in values if _kind(v) == "number"]
    if not all(_finite(v) for v in numbers):
        raise DesignError(f"grid.{path}: numbers must be finite (and within a float's range)")
    if any(isinstance(v, float) or abs(v) >= 2**63 for v in numbers):
        return tuple(v if v is None else float(v) for v in values)
    return values


def parse_spec(text: str | bytes, base_dir: str | Path | None = None) -> Spec:
    """A SPEC document, strictly: unknown keys, a key twice, bad ranges and grids of more
    than MAX_DESIGNS designs are refused with the offending key named. ``base_dir``: the
    folder of the spec's file, where a base ``{"file": NAME}`` is read from (the command
    line's; a spec from anywhere else names no file: a designer's review had pasted a
    whole design into the spec)."""
    from .model import _check_tree, json_document

    try:
        data = json_document(text)
    except DesignError as exc:
        raise DesignError(f"sweep spec: {exc}") from None
    if not isinstance(data, dict) or set(data) - {"base", "grid", "balance"} or "grid" not in data:
        raise DesignError('sweep spec: an object with "grid" and optionally "base", "balance"')
    _check_tree(data)
    base = data.get("base", {"preset": "paper_example"})
    base_text = None  # a base design file's text
    base_file = None
    if isinstance(base, dict) and set(base) == {"preset"}:
        design = load_preset(str(base["preset"]))
    elif isinstance(base, dict) and set(base) == {"file"}:
        if base_dir is None or not isinstance(base["file"], str) or not base["file"]:
            raise DesignError('base: {"file": NAME} names a design file beside the spec file')
        base_file = _beside(Path(base_dir), base["file"])
        design, base_text = read_design(base_file)
    elif isinstance(base, dict):
        try:
            design = design_from_json(json.dumps(base))
        except DesignError as exc:  # (its keys are the base's: "preset: ..." misled)
            raise DesignError(f"base: {exc}") from None
    else:
        raise DesignError('base: a design object or {"preset": NAME}')
    grid = data["grid"]
    if not isinstance(grid, dict) or not grid:
        raise DesignError("grid: an object of field paths to values")
    if len(grid) > MAX_AXES:  # (a review: 12,000 keys took 35 s to be compared pairwise)
        raise DesignError(f"grid: {len(grid)} fields; at most {MAX_AXES}")
    # the grid's size before its values are made (30 ranges of 100,000 values each had
    # built 3 million floats, 118 MB, before the size was refused: a review)
    size = math.prod(_axis_size(raw) for raw in grid.values())
    if size > MAX_DESIGNS:
        many = f"{size}" if size < 10**15 else "over 10^15"
        raise DesignError(f"grid: {many} designs; at most {MAX_DESIGNS} per sweep")
    if "schema_version" in grid:  # (a review's range of it gave a table of non-designs)
        raise DesignError("grid.schema_version: the design file's format, not a parameter")
    axes = tuple((str(path), axis_values(path, raw)) for path, raw in grid.items())
    _one_field_each([p for p, _ in axes])
    base_dict = json.loads(design.model_dump_json())
    for path, values in axes:
        _check_values(base_dict, path, values)
    left_out = () if base_text is None else _defaulted(base_text, design, axes)
    balance = _balance_path(data.get("balance"), base_dict, [p for p, _ in axes])
    spec = Spec(base_dict, axes, grid, left_out, base_file, balance)
    if spec.size > MAX_DESIGNS:
        raise DesignError(f"grid: {spec.size} designs; at most {MAX_DESIGNS} per sweep")
    return spec


def _balance_path(raw, base: dict, paths: list[str]) -> str | None:
    """The SPEC's ``balance``: "motion.segments.N.angle_deg" of a segment of the base
    design that no grid path sets, in a grid that sets no classic field (those keep
    the turn already); None if the SPEC has none. DesignError naming what is wrong."""
    if raw is None:
        return None
    m = (
        re.fullmatch(r"motion\.segments\.([0-9]{1,6})\.angle_deg", raw)
        if isinstance(raw, str)
        else None
    )
    if m is None:
        raise DesignError('balance: a segment angle, "motion.segments.N.angle_deg"')
    path = f"motion.segments.{int(m[1])}.angle_deg"
    if int(m[1]) >= len(base["motion"]["segments"]):
        raise DesignError(f"balance: the base design has no segment {int(m[1])}")
    fields = [field_path(p) for p in paths]
    if any(f == path or path.startswith(f + ".") for f in fields):
        raise DesignError(f"balance: {path} is set by the grid itself")
    if any(is_classic_field(f) for f in fields):
        raise DesignError(
            "balance: the grid sets a classic program's field, whose low dwell takes up "
            "the turn already"
        )
    return path


def _one_field_each(paths: list[str]) -> None:
    """Refuse two grid paths that set one field, or one a part of the other (a review:
    "motion.segments.0.law" beside "motion.rise_law" ran the second's law while the
    table's column said the first's)."""
    fields = [field_path(p) for p in paths]
    for i, (a, fa) in enumerate(zip(paths, fields, strict=True)):
        for b, fb in zip(paths[i + 1 :], fields[i + 1 :], strict=True):
            if program_clash(fa, fb):
                why = PROGRAM_CLASH
            elif fa == fb:
                why = "both set one field"
            elif fb.startswith(fa + ".") or fa.startswith(fb + "."):
                why = "one sets a part of the other"
                a, b = (a, b) if len(fa) < len(fb) else (b, a)  # the whole first
            else:
                continue
            raise DesignError(f"grid.{a} and grid.{b}: {why}")


# Validation errors that depend on the other fields' values (a limit, a check across
# fields): a grid value meeting one of them makes an error row; any other error (a
# wrong type, an unknown enum member, a missing or extra key) holds for every row, and
# the spec is refused.
_COMBINATION_ERRORS = frozenset(
    {
        "value_error",
        "assertion_error",
        "greater_than",
        "greater_than_equal",
        "less_than",
        "less_than_equal",
    }
)


def _check_values(base: dict, path: str, values: tuple) -> None:
    """Refuse a grid path the design has no field at, and a value no design can take
    there (e.g. "80" for a number, a misspelt follower kind), naming it. Each distinct
    text, list or object is tried on the base design, and one value of each number
    type (every int or every float behaves alike)."""
    from pydantic import ValidationError

    tried: dict[str, object] = {}
    for v in values:
        kind = _kind(v)
        tag = f"{kind}:{type(v).__name__}" if kind == "number" else json.dumps(v, sort_keys=True)
        tried.setdefault(tag, v)
    for v in tried.values():
        data = json.loads(json.dumps(base))
        set_field(data, path, v, "grid.")  # every path must be a field of the design
        try:
            Design.model_validate_json(json.dumps(data), strict=True)
        except ValidationError as exc:
            if any(e["type"] not in _COMBINATION_ERRORS for e in exc.errors()):
                shown = json.dumps(v)
                shown = shown if len(shown) <= 60 else shown[:57] + "..."
                raise DesignError(
                    f"grid.{path}: {shown} is not a value of this field: "
                    f"{format_validation_error(exc)}"
                ) from None


def flatten(node, prefix: str = "", out: dict | None = None) -> dict:
    """Nested dicts to one level with dotted keys; lists become JSON text."""
    out = {} if out is None else out
    if isinstance(node, dict):
        for k, v in node.items():
            flatten(v, f"{prefix}.{k}" if prefix else str(k), out)
    elif isinstance(node, list):
        out[prefix] = json.dumps(node)
    else:
        out[prefix] = node
    return out


def _beside(folder: Path, name: str) -> Path:
    """The design file ``name`` in the spec file's ``folder`` or below it, nowhere else
    (a review: "/home/me/secret.json" or "../x" was read, and its keys quoted in the
    error: a spec handed round must not read the user's other files)."""
    root = folder.resolve()
    try:
        path = (root / name).resolve()
    except (ValueError, OSError):  # an embedded NUL, a loop of links: no file to read
        path = root
    if root not in path.parents:
        raise DesignError(
            f'base: {{"file": ...}} names a design file in the spec file\'s folder or '
            f"below it, not {name[:80]!r}"
        )
    return path


def design_at(base: dict, point: dict) -> Design:
    """The base design with the point's field values, validated strictly; a point that
    changes the follower's kind renames the follower the name mentions (as
    Design.with_kind does: Explore's 'Load this design' brings the name along)."""
    data = json.loads(json.dumps(base))
    for path, value in point.items():
        set_field(data, path, value, "grid.")
    design = design_from_json(json.dumps(data))
    old = base.get("follower", {}).get("kind")
    if old in FollowerKind.__members__:
        design = name_follows_kind(design, old, base.get("name", design.name))
    return design


def _grid_values(point: dict) -> dict:
    """The row's ``grid.`` columns: the point's values (a list or object as JSON text)."""
    return {
        f"grid.{k}": v if isinstance(v, int | float | str | bool) or v is None else json.dumps(v)
        for k, v in point.items()
    }


def _made(base: dict, points: list[dict]) -> list[Design | str]:
    """Each point's design, or why it is none (the DesignError's text)."""
    out: list[Design | str] = []
    for p in points:
        try:
            out.append(design_at(base, p))
        except DesignError as exc:
            out.append(str(exc))
    return out


def design_key(design: Design) -> str:
    """Designs with the same key are analysed alike: they differ at most in follower
    fields their kind does not use (FollowerKind.uses), e.g. a roller radius swept for
    a concave face."""
    data = design.model_dump(mode="json")
    kind = design.follower.kind
    data["follower"] = {k: v for k, v in data["follower"].items() if kind.uses(k)}
    return json.dumps(data, sort_keys=True)


def _keys(made: list[Design | str]) -> list[str | None]:
    return [None if isinstance(d, str) else design_key(d) for d in made]


def _same(keys: list[str | None]) -> list[int]:
    first: dict[str, int] = {}
    return [i if k is None else first.setdefault(k, i) for i, k in enumerate(keys)]


def same_designs(base: dict, points: list[dict]) -> list[int]:
    """For each point, the first point that makes the same design (design_key): its
    own index if none before it does, or if the point makes no design at all (its row
    says why)."""
    return _same(_keys(_made(base, points)))


def with_point(row: dict, point: dict) -> dict:
    """The row of a design, for another point that makes the same design."""
    return {**_grid_values(point), **{k: v for k, v in row.items() if not k.startswith("grid.")}}


def _row(point: dict, design: Design | str, verify: bool) -> dict:
    from .report import analyze_summary, summary

    if isinstance(design, str):
        return {**_grid_values(point), "valid": False, "error": design}
    if verify:
        s = analyze_summary(design)
    else:
        from .analysis import analyze

        s = summary(analyze(design, verify=False))
    return {**_grid_values(point), **flatten(s), "valid": s["valid"], "error": None}


def row(base: dict, point: dict, verify: bool = True) -> dict:
    """One design's row: the grid values, valid, error and the flattened summary."""
    return _row(point, _made(base, [point])[0], verify)


def run_chunk(
    base: dict,
    points: list[dict],
    verify: bool = True,
    fast: bool = False,
    memo: dict[str, dict] | None = None,
) -> list[dict]:
    """Rows of a batch of designs (the unit of work sent to a worker). Points that make
    the same design (same_designs) are analysed once and share its figures, each with
    its own grid values. ``fast``: the batched core (fast_rows), else one full
    analysis per design (row). ``memo`` (design_key -> row, added to here): the rows
    of designs earlier chunks of the same run analysed, to be reused; ``run`` passes
    one, bounded to MEMO_ROWS, when the chunks run in this process."""
    made = _made(base, points)
    keys = _keys(made)
    memo = {} if memo is None else memo
    todo = [
        i for i, j in enumerate(_same(keys)) if i == j and (keys[i] is None or keys[i] not in memo)
    ]
    if fast:
        done = _fast_rows([points[i] for i in todo], [made[i] for i in todo])
    else:
        done = [_row(points[i], made[i], verify) for i in todo]
    refused = {}  # the rows of points that make no design
    for i, r in zip(todo, done, strict=True):
        key = keys[i]
        if key is None:
            refused[i] = r
        else:
            memo[key] = r
    rows = [
        refused[i] if k is None else with_point(memo[k], p)
        for i, (k, p) in enumerate(zip(keys, points, strict=True))
    ]
    while len(memo) > MEMO_ROWS:  # the oldest first
        memo.pop(next(iter(memo)))
    return rows


def fast_rows(base: dict, points: list[dict]) -> list[dict]:
    """Rows of the batched core (camcore.batch): the designs that differ only in their
    geometry are analysed together. Their rows hold the report's fixed-size figures
    (a subset of the keys of ``row``, with the same values), ``violations`` as
    [{"code": ...}] and ``profile_checked`` = False: the profile's own figures and
    checks (area, vertices, chord error, star shape, wear, geometric check) are not
    computed. Designs the batch cannot take (contact friction on a sliding face, a
    bore or a diameter limit: batch.batchable) get the full analysis, with
    ``profile_checked`` = True."""
    return _fast_rows(points, _made(base, points))


def _fast_rows(points: list[dict], made: list[Design | str]) -> list[dict]:
    from . import batch, profile
    from .analysis import analyze
    from .report import summary

    rows = [_grid_values(p) for p in points]
    groups: dict[tuple, list[tuple[int, Design]]] = {}
    for i, design in enumerate(made):
        if isinstance(design, str):
            rows[i] = {**rows[i], "valid": False, "error": design}
            continue
        key = (batch.group_key(design), len(profile.geometry(design).faces))
        groups.setdefault((*key, batch.batchable(design)), []).append((i, design))
    for (*_, ok), members in groups.items():
        designs = [d for _, d in members]
        if ok:
            sums = [s for part in _parts_of(designs) for s in batch.summaries(part)]
        else:
            sums = [{**summary(analyze(d, verify=False)), "profile_checked": True} for d in designs]
        for (i, _), s in zip(members, sums, strict=True):
            rows[i] = {**rows[i], **flatten(s), "valid": s["valid"], "error": None}
    return rows


def _parts_of(designs: list[Design]) -> list[list[Design]]:
    """``designs`` in order, in parts of at most BATCH_SAMPLES grid samples (each
    design's grid without its stations, a few samples fewer; at least one design a
    part). Not 360 / resolution: a short rise has MIN_MOTION_STEPS samples whatever
    the resolution (a review: 48 rises of 7.5 deg at 0.1 deg have 5,760)."""
    from . import motion

    parts: list[list[Design]] = [[]]
    held = 0
    for d in designs:
        n = motion.theta_grid(d).size
        if parts[-1] and held + n > BATCH_SAMPLES:
            parts.append([])
            held = 0
        parts[-1].append(d)
        held += n
    return parts


def _table(rows: list[dict]):
    import pyarrow as pa

    cols: dict[str, list] = {}
    for i, r in enumerate(rows):
        for k in r:
            cols.setdefault(k, [None] * i)
        for k in cols:
            cols[k].append(r.get(k))
    return pa.table(cols)


FORMULA_START = ("=", "+", "-", "@", "\t", "\r")  # a spreadsheet runs such a text cell


def csv_text(rows: list[dict]) -> str:
    """The rows as CSV: the columns of the Parquet table (``_table``: each key where it
    first appears), a float at full precision (repr), None as an empty cell. A text
    cell that a spreadsheet would run as a formula (a design's name "=HYPERLINK(...)")
    starts with an apostrophe, as OWASP advises against CSV injection."""
    import csv
    import io

    names: dict[str, None] = {}
    for r in rows:
        names.update(dict.fromkeys(r))
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(names)
    for r in rows:
        writer.writerow(_cell(r.get(k)) for k in names)
    return out.getvalue()


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    text = str(v)
    return "'" + text if isinstance(v, str) and text.startswith(FORMULA_START) else text


def _progress(done: int, total: int, rate: float, stream=sys.stderr) -> None:
    width = 30
    fill = int(width * done / max(total, 1))
    left = f", ~{_duration((total - done) / rate)} left" if rate > 0 and done < total else ""
    stream.write(
        f"\r[{'#' * fill}{'.' * (width - fill)}] {done}/{total} designs, {rate:.1f}/s{left}   "
    )
    stream.flush()


def _duration(seconds: float) -> str:
    """A time to go, as a person reads it: 40 s, 12 min, 3.5 h."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


PART_METADATA = "camcore.sweep.part"  # a kept chunk's stamp: its run's, and its number
# the sweep's own files: its chunks, its label, and write_atomic's temporary files of them
PART_NAME = re.compile(
    r"(chunk-\d{6}\.parquet|sweep\.json)|\.(chunk-\d{6}\.parquet|sweep\.json)\.[0-9a-f]{12}\.tmp(\.old)?"
)


def _parts_dir(out: Path, stamp: dict) -> Path:
    """``OUT.parts/``, holding the finished chunks of this very run: same spec, mode,
    chunk size, camcore version and code (its ``stamp``). Parts of another run are refused
    with what differs; a parts directory with no chunk in it yet is taken over. A folder
    of that name holding anything but a sweep's own files, or a link, is refused: the
    run deletes the folder when it is done (a review: a user's notes kept there went
    with it)."""
    if out.is_dir():
        raise FileError(f"--out {out}: that is a directory; give a file name")
    if not out.parent.is_dir():
        raise FileError(f"--out {out}: no directory {out.parent}")
    target = write_target(out)  # (a FIFO, a device, a stream: before any work)
    if not target.parent.is_dir():  # (a link to a missing directory)
        raise FileError(f"--out {out}: no directory {target.parent}")
    parts = out.with_name(out.name + ".parts")
    label = parts / "sweep.json"
    if parts.is_symlink() or (parts.exists() and not parts.is_dir()):
        raise FileError(f"{parts}: not a folder of this sweep's (a link or a file); move it away")
    if parts.exists():  # (a link in it, even of our name, would be written through)
        other = sorted(
            f.name
            for f in parts.iterdir()
            if not PART_NAME.fullmatch(f.name) or f.is_symlink() or not f.is_file()
        )
        if other:
            raise FileError(
                f"{parts} holds files that are not a sweep's ({', '.join(other[:3])}"
                f"{', ...' if len(other) > 3 else ''}); the sweep keeps its chunks there and "
                "removes the folder when done: move them away or choose another --out"
            )
    if parts.exists() and any(parts.glob("chunk-*.parquet")):
        try:
            theirs = json.loads(label.read_text())
        except (OSError, ValueError):
            theirs = {}
        differ = [
            f"{k} {theirs.get(k)!r} (this run: {v!r})"
            for k, v in stamp.items()
            if theirs.get(k) != v
        ]
        if differ:
            raise DesignError(
                f"{parts} holds the finished chunks of another sweep: {'; '.join(differ)}. "
                "Rerun that sweep to finish it, or remove the directory to start over"
            )
    try:
        parts.mkdir(exist_ok=True)
    except OSError as exc:
        raise FileError(f"cannot write {parts}: {exc.strerror}") from None
    write_atomic(label, json.dumps(stamp).encode())
    return parts


def _remove_parts(parts: Path) -> None:
    """Remove the parts folder: only its own files (PART_NAME), then the folder if
    that empties it."""
    for f in parts.iterdir():
        if PART_NAME.fullmatch(f.name) and f.is_file() and not f.is_symlink():
            f.unlink()
    with contextlib.suppress(OSError):
        parts.rmdir()


def run(
    spec: Spec,
    out: str | Path,
    *,
    chunk: int = DEFAULT_CHUNK,
    verify: bool = True,
    fast: bool = False,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int, int, float], None] | None = _progress,
) -> int:
    """Run the sweep into the Parquet file ``out``; returns the number of rows.

    Finished chunks are kept in ``out.parts/`` (with the spec's fingerprint, the mode,
    the chunk size and the version) until the whole table is written, so a run
    interrupted and started again the same way computes only the missing chunks.
    ``fast``: the batched core (``fast_rows``; the geometric check is not run either
    way). ``progress(done, total, rate)``: designs done of all, and designs per second
    computed by this run (not the chunks it found done)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    out = Path(out)
    mode = "fast" if fast else "verify" if verify else "no-verify"
    stamp = {
        "spec": spec.fingerprint(),
        "mode": mode,
        "chunk": chunk,
        "camcore": package_version(),
        "code": code_fingerprint(),  # (two checkouts of one version differ here)
    }
    total = spec.size
    n_chunks = -(-total // chunk)
    parts = _parts_dir(out, stamp)  # a bad output fails before any work or cluster
    size = [min((i + 1) * chunk, total) - i * chunk for i in range(n_chunks)]
    todo = [i for i in range(n_chunks) if _kept(parts, i, stamp, size[i]) is None]
    try:
        _compute(spec, chunk, todo, (verify, fast), (workers, scheduler), (parts, stamp), progress)
    except BaseException:  # a bad scheduler, Ctrl-C before a chunk was kept: no litter
        if not any(parts.glob("chunk-*.parquet")):
            _remove_parts(parts)
        raise
    if progress:
        sys.stderr.write("\n")
    tables = [_kept(parts, i, stamp, size[i]) for i in range(n_chunks)]
    lost = [i for i, t in enumerate(tables) if t is None]
    if lost:  # (damaged since it was written, or removed meanwhile)
        raise FileError(
            f"{parts}: chunk {lost[0]} no longer reads back; the same command computes it again"
        )
    table = pa.concat_tables(tables, promote_options="permissive")  # e.g. int with float
    table = table.replace_schema_metadata(
        {
            SPEC_METADATA: spec.document(),
            VERSION_METADATA: package_version(),
            CODE_METADATA: code_fingerprint(),
        }
    )
    buf = pa.BufferOutputStream()
    pq.write_table(table, buf)
    write_atomic(out, buf.getvalue().to_pybytes())
    _remove_parts(parts)
    return table.num_rows


def _compute(
    spec: Spec,
    chunk: int,
    todo: list[int],
    how: tuple[bool, bool],
    where: tuple[int | None, str | None],
    into: tuple[Path, dict],
    progress: Callable[[int, int, float], None] | None,
) -> None:
    """Compute the chunks ``todo`` into ``into`` = (the parts folder, the run's stamp),
    with ``how`` = (verify, fast), in this process or on the cluster ``where`` =
    (workers, scheduler), each kept as soon as it is done, stamped with the run's stamp
    and its number (``_kept``). On Ctrl-C the terminal hears how much is kept and that
    the same command resumes."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    total = spec.size
    found = total - sum(min((i + 1) * chunk, total) - i * chunk for i in todo)
    done = found
    workers, scheduler = where
    parts, stamp = into
    with _cluster(workers if todo else None, scheduler if todo else None) as client:
        t0 = time.perf_counter()  # the rate: of this run's work, from when it can start

        def keep(i: int, rows: list[dict]) -> None:
            nonlocal done
            buf = pa.BufferOutputStream()
            mark = {PART_METADATA: json.dumps({**stamp, "part": i})}
            pq.write_table(
                _table(rows).replace_schema_metadata(mark), buf, write_page_checksum=True
            )
            write_atomic(parts / f"chunk-{i:06d}.parquet", buf.getvalue().to_pybytes())
            done += len(rows)
            if progress:
                progress(done, total, (done - found) / max(time.perf_counter() - t0, 1e-9))

        try:
            if client is None:
                memo: dict[str, dict] = {}  # a design repeated in a later chunk is not redone
                for i in todo:
                    keep(i, run_chunk(spec.base, spec.chunk(i, chunk), how[0], how[1], memo))
            else:
                _run_dask(client, spec, chunk, todo, how, keep)
        except ClusterLost as exc:
            raise ClusterLost(
                f"{exc}; {done} of {total} designs are kept in {parts}: the same command resumes"
            ) from None
        except KeyboardInterrupt:
            if progress and done:
                sys.stderr.write(
                    f"\ninterrupted: {done} of {total} designs are kept in {parts}; "
                    "the same command resumes\n"
                )
            elif progress:
                sys.stderr.write("\ninterrupted before a chunk was finished: nothing kept\n")
            raise


def _kept(parts: Path, i: int, stamp: dict, rows: int):
    """Chunk ``i`` as kept in ``parts`` (a pyarrow Table), or None where it must be
    computed (again): missing, not reading back whole with its pages' checksums
    (damaged outside this program, e.g. a disk that filled), not stamped by this very
    run as chunk ``i``, or not of its ``rows`` rows. A review: another sweep's chunk
    put there was joined in, and a damaged one whose footer still read failed the join
    on every run."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        table = pq.read_table(parts / f"chunk-{i:06d}.parquet", page_checksum_verification=True)
        mark = json.loads((table.schema.metadata or {}).get(PART_METADATA.encode(), b"{}"))
    except (OSError, ValueError, pa.ArrowException):
        return None
    if mark != {**stamp, "part": i} or table.num_rows != rows:
        return None
    return table.replace_schema_metadata(None)


@contextlib.contextmanager
def _cluster(workers: int | None, scheduler: str | None):
    """A Dask client: of a LocalCluster of ``workers`` processes, or of the scheduler at
    ``scheduler`` (refused, with the reason, if it cannot be reached in 10 s); None
    for neither (the chunks run in this process)."""
    if workers is None and scheduler is None:
        yield None
        return
    from dask.distributed import Client, LocalCluster

    cluster = None
    if scheduler is None:
        with _sigint_ignored():
            cluster = LocalCluster(
                n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
            )
        client = Client(cluster)
        client.run(_quiet_cancellations)
    else:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, ValueError, TypeError) as exc:  # no cluster there, or no address
            raise DesignError(f"--scheduler {scheduler}: cannot connect ({exc})") from None
    try:
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


@contextlib.contextmanager
def _sigint_ignored():
    """SIGINT ignored while our LocalCluster starts its worker processes: they inherit
    the ignore (it survives their exec), so Ctrl-C at the terminal (sent to the whole
    process group) reaches this process alone, which cancels the chunks and closes the
    cluster. Otherwise each worker printed a KeyboardInterrupt traceback after the clean
    "interrupted" line (a review). A Ctrl-C in the second or two of the start is lost:
    press it again."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield  # (only the main thread may set a handler; the app's runs are not ours)
        return
    old = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old)


def _quiet_cancellations() -> None:
    """On a worker of our own LocalCluster: do not log the chunks that Ctrl-C cancels
    (a CancelledError warning per running chunk, printed after the terminal has been
    told what is kept). A user's own cluster keeps its logging as it is."""
    import logging

    logging.getLogger("distributed.worker.state_machine").setLevel(logging.ERROR)


def same_code_on_workers(client) -> None:
    """Refuse a cluster whose workers run another camcore (an existing cluster started
    from another install or checkout): its rows would silently be another code's.
    DesignError naming the workers that differ, or saying that they cannot run this
    camcore's check at all. (A worker that joins later is checked by each chunk it
    runs: ``checked_chunk``.)"""
    try:
        theirs = client.run(code_fingerprint)
    except Exception as exc:  # e.g. a worker whose camcore has no code_fingerprint
        raise DesignError(
            f"the Dask workers cannot run this camcore ({type(exc).__name__}: {exc}); "
            "install this camdesigner on them"
        ) from None
    mine = code_fingerprint()
    other = sorted(w for w, fp in theirs.items() if fp != mine)
    if other:
        raise DesignError(
            f"{len(other)} of {len(theirs)} Dask workers run another camcore "
            f"({', '.join(other[:3])}{', ...' if len(other) > 3 else ''}: code "
            f"{theirs[other[0]]}, this one {mine}): their rows would be another code's. "
            "Install this camdesigner on them (or run with --workers N here)"
        )


def checked_chunk(code: str, base: dict, points: list[dict], *how) -> list[dict]:
    """``run_chunk`` on a Dask worker, refused (DesignError) where the worker's camcore
    is not the code of the run (``code``: the caller's code_fingerprint): a worker that
    joined the cluster after the run's check would otherwise add another code's rows."""
    if code_fingerprint() != code:
        raise DesignError(
            f"a Dask worker runs another camcore (code {code_fingerprint()}, this run "
            f"{code}): its rows would be another code's. Install this camdesigner on it"
        )
    return run_chunk(base, points, *how)


def _run_dask(client, spec, chunk, todo, how, keep) -> None:
    """The chunks on a Dask cluster; each finished chunk is kept as it arrives."""
    from dask.distributed import as_completed

    same_code_on_workers(client)
    # The base design (a few kB) goes inside each task, not scattered: a scattered value
    # lives only on workers, and two workers killed 0.2 s apart lost every copy, which
    # ended the run as an internal error (a review). A task's own arguments survive on
    # the scheduler, so Dask reruns a lost worker's chunks elsewhere.
    code = code_fingerprint()
    futures = {
        client.submit(checked_chunk, code, spec.base, spec.chunk(i, chunk), *how, pure=False): i
        for i in todo
    }
    for fut in as_completed(futures):
        keep(futures[fut], chunk_result(fut, futures[fut]))


class ClusterLost(RuntimeError):
    """The Dask cluster lost a chunk for good (its workers kept dying, or the scheduler
    went away): the chunks already kept stay, and the same command resumes."""


def chunk_result(fut, i: int) -> list[dict]:
    """The rows of chunk ``i``'s Dask future; ClusterLost where the cluster, not our
    code, failed it: a KilledWorker (Dask gave up after its workers died running it
    again and again), a cancelled future (the scheduler restarted or left) or a closed
    connection to it."""
    from concurrent.futures import CancelledError

    from dask.distributed import KilledWorker
    from distributed.comm.core import CommClosedError

    try:
        return fut.result()
    # (not any OSError: one our code raises on a worker is ours, not the cluster's)
    except (KilledWorker, CancelledError, CommClosedError) as exc:
        raise ClusterLost(
            f"the Dask cluster lost chunk {i} ({type(exc).__name__}: {str(exc)[:160]})"
        ) from None


def design_of_row(path: str | Path, row: int) -> Design:
    """The design of row ``row`` (0-based) of the sweep table at ``path``: the table
    keeps its SPEC and its rows are the SPEC's points in order. FileError for a table
    without one (written before camcore kept it) or whose rows do not match it."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    try:
        meta = pq.read_schema(regular_file(path)).metadata or {}
        rows = pq.ParquetFile(path).metadata.num_rows
    except (OSError, pa.ArrowException) as exc:
        raise FileError(f"{path}: not a readable Parquet table ({exc})") from None
    text = meta.get(SPEC_METADATA.encode())
    if text is None:
        raise FileError(f"{path} does not keep its sweep spec (an older camcore wrote it)")
    if len(text) > MAX_SPEC_BYTES:  # (as a spec file is: a table is a file from anywhere)
        raise FileError(f"{path}: its sweep spec is {len(text)} bytes; at most {MAX_SPEC_BYTES}")
    spec = parse_spec(text)
    if spec.size != rows or not 0 <= row < rows:
        raise FileError(f"{path}: {rows} rows, its spec {spec.size} designs (row {row})")
    point = spec.point(row)
    want = _grid_values(point)
    try:
        got = pq.read_table(path, columns=list(want)).slice(row, 1).to_pylist()[0]
    except (OSError, KeyError, pa.ArrowException) as exc:
        raise FileError(f"{path}: its grid columns do not read ({exc})") from None
    if got != want:  # a table whose rows are not its spec's points, in order
        raise FileError(
            f"{path}: row {row} holds {printable(repr(got), 200)}, its spec's point "
            f"{printable(repr(want), 200)}: the rows are not the spec's"
        )
    return design_at(spec.base, point)


def tally(path: str | Path) -> str:
    """How the rows of a sweep's table came out: valid, breaking a limit, no design."""
    import pyarrow.parquet as pq

    t = pq.read_table(path, columns=["valid", "error"]).to_pydict()
    refused = sum(e is not None for e in t["error"])
    valid = sum(bool(v) for v in t["valid"])
    return (
        f"{valid} valid, {len(t['valid']) - valid - refused} break a limit, {refused} not designs"
    )


def load_spec(path: str | Path) -> Spec:
    """The SPEC file at ``path`` (a base {"file": NAME} read beside it)."""
    return parse_spec(read_capped(path, MAX_SPEC_BYTES), base_dir=Path(path).parent)


SAME_DIGITS = 12  # significant digits two figures must share to count as equal


def _significant(x: np.ndarray, digits: int) -> np.ndarray:
    """``x`` rounded to ``digits`` significant digits (0, inf and NaN as they are)."""
    with np.errstate(all="ignore"):
        exp = np.floor(np.log10(np.abs(x)))
        scale = 10.0 ** (digits - 1 - exp)
        rounded = np.round(x * scale) / scale
        return np.where(np.isfinite(rounded), rounded, x)  # (beyond 1e±290: as it is)


def front_order(values: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """The rows ``idx`` of a front in its one order: by the first figure, then the next
    (each equal to SAME_DIGITS significant digits counts as equal), then by row, so
    the app's list and `camcore pareto` number one front alike (a review: designs with
    a stress 5e-14 apart came in two orders)."""
    v = _significant(np.asarray(values, dtype=float)[idx], SAME_DIGITS)
    return idx[np.lexsort((idx, *v.T[::-1]))]


def pareto_mask(values: np.ndarray) -> np.ndarray:
    """Which rows of ``values`` (n designs x k figures, all to be minimized) are on the
    Pareto front: no other row is at least as good in every figure and better in one.
    Rows with a NaN or an infinite figure are never on it (a sweep's figures are
    finite where a design has them); equal rows are both on it or both off.

    Equal rows are merged first; sorted lexicographically, a point can then only be
    dominated by one before it. Two figures: by the running minimum of the second
    (O(n log n)). More: blocks of points are tested against the front found so far and
    against each other (O(n |front| k)), so a million-row sweep with a front of a few
    thousand takes about a second; a front of n points would take O(n^2).

    Figures equal to SAME_DIGITS significant digits count as equal (a review: a
    single roller stayed on the front beside a face whose R was 95.00000000000003 mm
    against its 95.0: round-off, not a better cam)."""
    v = _significant(np.asarray(values, dtype=float), SAME_DIGITS)
    ok = np.isfinite(v).all(axis=1)
    front = np.zeros(len(v), dtype=bool)
    if not ok.any():
        return front
    points, inverse = np.unique(v[ok], axis=0, return_inverse=True)  # lexicographic
    if points.shape[1] == 1:
        on = np.arange(len(points)) == 0
    elif points.shape[1] == 2:  # an earlier point with a second figure <= dominates
        before = np.minimum.accumulate(np.concatenate([[np.inf], points[:-1, 1]]))
        on = points[:, 1] < before
    else:
        on = _front_by_blocks(points)
    front[np.flatnonzero(ok)] = on[inverse.reshape(-1)]
    return front


def _front_by_blocks(points: np.ndarray, block: int = 512) -> np.ndarray:
    """pareto_mask of distinct, lexicographically sorted points (n x k, k >= 3).

    First every point is tested against the front of a few hundred promising ones
    (least sum of ranks): that removes most of a large sweep at once. The rest go in
    blocks, each tested against the front found so far and then within itself."""
    keep = np.ones(len(points), dtype=bool)
    if len(points) > 4 * block:
        ranks = np.argsort(np.argsort(points, axis=0), axis=0).sum(axis=1)
        seed = np.sort(np.argpartition(ranks, block)[:block])
        seed = seed[_front_by_blocks(points[seed], block)]
        keep = ~_beaten_by(points[seed], points)
        keep[seed] = True  # a point is <= itself: the seeds' front stays
    on = np.zeros(len(points), dtype=bool)
    rest = np.flatnonzero(keep)
    kept = points[:0]
    for start in range(0, len(rest), block):
        idx = rest[start : start + block]
        cand = points[idx]
        if len(kept):
            ahead = _beaten_by(kept, cand)
            cand, idx = cand[~ahead], idx[~ahead]
        # within the block (sorted), only an earlier point can dominate a later one
        le = _all_le(cand, cand)  # [i, j]: cand[j] <= cand[i] in every figure
        inside = np.tril(le, k=-1).any(axis=1)
        on[idx[~inside]] = True
        kept = np.concatenate([kept, cand[~inside]])
    return on


def _all_le(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """[i, j]: a[j] <= b[i] in every column (one 2-D comparison per column)."""
    out = a[None, :, 0] <= b[:, None, 0]
    for c in range(1, a.shape[1]):
        out &= a[None, :, c] <= b[:, None, c]
    return out


def _beaten_by(front: np.ndarray, points: np.ndarray, size: int = 2_000_000) -> np.ndarray:
    """Which ``points`` a row of ``front`` is <= in every column (distinct points: so
    dominates), in pieces of at most ``size`` comparisons."""
    out = np.zeros(len(points), dtype=bool)
    step = max(1, size // max(1, len(front)))
    for s in range(0, len(points), step):
        out[s : s + step] = _all_le(front, points[s : s + step]).any(axis=1)
    return out


def first_violation(row: dict) -> str | None:
    """The first limit a row's design breaks (its violation code), None if it is
    valid, "not a design" if the combination was refused before any analysis."""
    if row.get("error"):
        return "not a design"
    if row.get("valid"):
        return None
    codes = [v["code"] for v in json.loads(row.get("violations") or "[]")]
    return codes[0] if codes else "invalid"
