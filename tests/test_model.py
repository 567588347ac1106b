"""The design model: lossless JSON, schema versions and migrations, re-validation."""

import importlib.resources
import json

import pytest
from pydantic import ValidationError

from camcore import model
from camcore.model import Design, DesignError, FollowerKind, design_from_json, load_preset


def test_json_roundtrip_is_lossless():
    d = load_preset("indexer_345")
    again = design_from_json(model.design_to_json(d))
    assert again == d
    assert json.loads(model.design_to_json(again)) == json.loads(model.design_to_json(d))


def test_an_older_format_is_upgraded_through_migrations(monkeypatch):
    """A format-0 file whose lift was called 'h_mm' loads once a migration exists, and
    goes on through 1 -> 2 (motion as segments)."""

    def v0_to_v1(data):
        data["motion"] = dict(data["motion"])
        data["motion"]["lift_mm"] = data["motion"].pop("h_mm")
        return data

    old = json.loads(
        importlib.resources.files("camcore.presets").joinpath("paper_example.json").read_text()
    )
    assert old["schema_version"] == 1
    old["schema_version"] = 0
    old["motion"]["h_mm"] = old["motion"].pop("lift_mm") + 1.0
    with pytest.raises(DesignError, match="format 0, older than any this program can upgrade"):
        design_from_json(json.dumps(old))
    monkeypatch.setitem(model.MIGRATIONS, 0, v0_to_v1)
    d = design_from_json(json.dumps(old))
    assert d.schema_version == 2 and d.motion.lift_mm == 16.0
    assert [g.kind.value for g in d.motion.segments] == ["rise", "dwell", "fall", "dwell"]


def test_format_1_files_load_and_save_as_format_2():
    """Every shipped preset is a format 1 file: it loads, saves as format 2 with
    segments, and the saved file loads back to the same design."""
    from camcore.model import design_to_json, preset_names

    for name in preset_names():
        d = load_preset(name)
        text = design_to_json(d)
        saved = json.loads(text)
        assert saved["schema_version"] == 2 and "segments" in saved["motion"]
        assert "lift_mm" not in saved["motion"]
        assert design_from_json(text) == d


@pytest.mark.parametrize(
    "version, message",
    [
        (3, "written by a newer program"),
        (True, "must be an integer"),
        ("1", "must be an integer"),
    ],
)
def test_unreadable_versions_say_why(version, message):
    data = {"schema_version": version}
    with pytest.raises(DesignError, match=message):
        design_from_json(json.dumps(data))


def test_with_kind_revalidates():
    """e = 100 mm fits the concave faces (|r_f + r_b| = 170) but not rollers (88 mm)."""
    data = load_preset("paper_example").model_dump()
    data["follower"]["offset_mm"] = 100.0
    d = Design.model_validate(data)
    with pytest.raises(ValidationError, match="offset_mm"):
        d.with_kind(FollowerKind.double_roller)


def test_with_kind_renames_the_follower_a_name_mentions():
    """`--follower` on the paper's preset must not leave '(double concave faces)' in the
    headers of a single roller's files; a name that names no follower is the user's."""
    paper = load_preset("paper_example")
    roller = paper.with_kind("single_roller")
    assert roller.name == "Chuang, Hsu & Chang, Section 6 example (single roller)"
    assert roller.with_kind("double_concave").name == paper.name  # and back
    shop = load_preset("valve_lift_roller")  # "Single roller, modified sine, ..."
    assert shop.with_kind("knife_edge").name.startswith("Knife edge, modified sine")
    own = paper.model_copy(update={"name": "Line 3 feeder"})
    assert own.with_kind("flat_face").name == "Line 3 feeder"
    knife = paper.with_kind("knife_edge").model_copy(update={"name": "x" * 188 + " knife edge"})
    assert knife.with_kind("double_concave").name == knife.name  # 209 chars: kept


@pytest.mark.parametrize(
    "name, old, new, expected",
    [
        ("A single roller follower", "single_roller", "knife_edge", "A knife edge follower"),
        ("double concave faces vs single roller", "single_roller", "double_concave", None),
        ("single concave-faced", "single_concave", "single_roller", None),
        ("SINGLE ROLLER cam", "single_roller", "flat_face", "FLAT FACE cam"),
        ("double rollers, test", "double_roller", "single_roller", "single roller, test"),
    ],
)
def test_a_rename_keeps_the_rest_of_the_name(name, old, new, expected):
    """A review's names: the word after the follower stays, a name that compares two
    followers or says 'single concave-faced' is left alone (None), capitals stay."""
    out = model.renamed_for_kind(name, FollowerKind(old), FollowerKind(new))
    assert out == (name if expected is None else expected)


@pytest.mark.parametrize(
    "path",
    [
        ("cam", "base_radius_mm"),
        ("dynamics", "spring_rate_N_per_m"),
        ("limits", "allowable_contact_stress_MPa"),  # (a number or null)
        ("motion", "segments", 0, "angle_deg"),
    ],
)
def test_true_or_false_is_not_a_number(path):
    """pydantic's lax mode reads true as 1.0: a file with "base_radius_mm": true had
    made a 1 mm cam without a word. A number field refuses a boolean, naming it; a
    boolean field still takes one."""
    data = Design().model_dump(mode="json")
    *parents, key = path
    node = data
    for p in parents:
        node = node[p]
    for flag in (True, False):
        node[key] = flag
        with pytest.raises(ValidationError, match="a number, not true or false"):
            Design.model_validate(data)
    data = Design().model_dump(mode="json")
    data["limits"]["require_continuous_acceleration"] = False
    assert Design.model_validate(data).limits.require_continuous_acceleration is False


def test_geometry_errors_name_the_quantities_and_the_fix():
    """A teacher's review: r_f = -90 mm was refused as "e = 10 mm must be below
    |r + r_b|", and r_f = +90 as "Input should be less than 0"."""
    import json

    from camcore.model import DesignError, design_from_json

    def error(**follower) -> str:
        data = json.loads(load_preset("paper_example").model_dump_json())
        data["follower"].update(follower)
        with pytest.raises(DesignError) as err:
            design_from_json(json.dumps(data))
        return str(err.value)

    text = error(face_radius_mm=-90.0)
    assert "below |r_f| - r_b = 10 mm" in text and "a flatter face (a larger |r_f|)" in text
    text = error(kind="double_roller", offset_mm=100.0)
    assert "below r_c + r_b = 88 mm" in text and "a larger r_b" in text
    # a single follower's offset has a sign: its size is what breaks (a review read
    # "e = 1000 mm" for e_s = -1000 mm)
    text = error(kind="knife_edge", single_offset_mm=-1000.0)
    assert "single_offset_mm: |e_s| = 1000 mm must be below r_b = 80 mm" in text
    text = error(face_radius_mm=90.0)
    assert "face_radius_mm: Input should be less than 0, a concave face's radius" in text
    assert text.endswith("(got 90.0)")


@pytest.mark.parametrize(
    "typed, kept",
    [
        ("Pump cam \ufeff", "Pump cam "),
        ("evil\x1b[2K\rVALID: yes", "evil[2K VALID: yes"),
        ("a\u200bb", "ab"),
        ("line\nbreak\ttab", "line break tab"),
        ("x\u2028y", "x y"),
    ],
)
def test_a_name_drops_control_and_format_characters(typed, kept):
    """A review: a pasted U+FEFF made the PDF fail, and ESC sequences in a name could
    rewrite a terminal's report (hide its violations). They are dropped (a line break
    or tab made a space), in every way a design is made, so a design kept under such a
    name still opens; a name in any script, emoji sequences and the zero-width
    (non-)joiner Persian needs are kept."""
    assert Design(name=typed).name == kept
    assert design_from_json(json.dumps({"name": typed})).name == kept
    d = Design()
    d.name = typed  # (assignment is validated too)
    assert d.name == kept
    for good in ("Ünïcödé 凸轮 ✓", "می\u200cرود", "\U0001f468\u200d\U0001f527 tool cam"):
        assert Design(name=good).name == good


def test_an_error_prints_a_files_own_keys_escaped_and_short():
    """Keys come from the user's file: an ESC in one reached the terminal, and a 900 kB
    key came back whole in the error."""
    text = json.dumps({"cam": {"\x1b[2Kbad": 1, "k" * 5000: 2}})
    with pytest.raises(DesignError) as err:
        design_from_json(text)
    said = str(err.value)
    assert "\x1b" not in said and "cam.\\u001b[2Kbad" in said
    assert len(said) < 400 and "k" * 60 + "…" in said


def test_a_file_that_is_no_json_design_says_what_it_is_in_words():
    """A maker's review: an empty file said "Expecting value: line 1 column 1 (char 0)"
    and an STL "'utf-8' codec can't decode byte 0xfc". Each now says what the file is;
    a JSON text in UTF-8 with a byte-order mark, or in UTF-16, still opens (as
    json.loads reads bytes)."""
    d = load_preset("paper_example")
    text = model.design_to_json(d)
    assert design_from_json(b"\xef\xbb\xbf" + text.encode()) == d
    assert design_from_json(text.encode("utf-16")) == d
    for content, said in (
        (b"", "the file is empty"),
        (b" \n\t", "the file is empty"),
        (b"solid cam\n" + bytes([0x80, 0xFC]) * 50, "not a text file"),
        (b'{"name": }', "not a JSON document: expecting value at line 1, column 10"),
        ('{\n"name": "x",\n', "at line 3, column 1"),
        # (a review: "unterminated string starting at at line 1")
        ('{"name": "x', "not a JSON document: unterminated string starting at line 1, column 10"),
    ):
        with pytest.raises(DesignError, match=said):
            design_from_json(content)


@pytest.mark.parametrize(
    "text, said",
    [
        ('{"cam": {"width_mm": ' + "9" * 400 + "}}", "cam.width_mm"),
        ('{"cam": {"base_radius_mm": -' + "9" * 400 + "}}", "cam.base_radius_mm"),
        ('{"motion": {"lift_mm": "' + "A" * 900_000 + '"}}', "motion.lift_mm"),
        ('{"schema_version": "' + "x" * 5000 + '"}', "schema_version"),
    ],
    ids=["400 digits", "-400 digits", "900 kB string", "5000-char version"],
)
def test_a_refused_value_is_quoted_short_and_never_crashes(text, said):
    """A security review: a 400-digit number in a field raised OverflowError while
    the error quoted it (the CLI exited 3, the app's restore died), and a 900 kB
    string came back whole in the error."""
    with pytest.raises(DesignError, match=said) as err:
        design_from_json(text)
    assert len(str(err.value)) < 200
