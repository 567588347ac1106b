"""The README's Section 6 results (its table of the four followers and the dwell
ratios) are what camcore computes now, to their printed digits: an independent review
found three of them a digit off after the code had moved on."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from camcore.analysis import analyze, compare
from camcore.model import Design, FollowerKind, load_preset
from camcore.report import summary

README = Path(__file__).resolve().parents[1] / "README.md"
ROWS = {
    "single roller": FollowerKind.single_roller,
    "double rollers": FollowerKind.double_roller,
    "single concave face": FollowerKind.single_concave,
    "double concave faces": FollowerKind.double_concave,
}


def _table() -> dict[str, list[str]]:
    """Follower label -> the cells of its row in the README's Section 6 table."""
    out = {}
    for line in README.read_text(encoding="utf-8").splitlines():
        cells = [c.strip().strip("*") for c in line.strip().strip("|").split("|")]
        if cells and cells[0] in ROWS and len(cells) == 6:
            out[cells[0]] = cells
    return out


def _printed(pattern: str) -> tuple[str, ...]:
    """The numbers the README prints where ``pattern`` matches (its lines joined)."""
    m = re.search(pattern, " ".join(README.read_text(encoding="utf-8").split()))
    assert m is not None, pattern
    return m.groups()


@pytest.fixture(scope="module")
def sums():
    return {k: summary(a) for k, a in compare(load_preset("paper_example")).items()}


def test_the_section_6_table_is_what_camcore_computes(sums):
    table = _table()
    assert set(table) == set(ROWS)
    for label, kind in ROWS.items():
        s = sums[kind]
        two, whole, _paper, stress = table[label][1:5]
        fn = s["contact_force_max_N"]
        assert two == (
            "—" if fn["high_dwell_two_contact"] is None else f"{fn['high_dwell_two_contact']:.3f}"
        )
        assert whole == f"{fn['high_dwell']:.3f}", label
        assert stress == f"{s['contact_stress_max_MPa']['cycle']:.2f}", label


def test_the_dwell_ratios_are_what_camcore_computes(sums):
    rollers, concave = _printed(
        r"Ratios double/single in the dwell: ([0-9.]+) % \(rollers.*?and ([0-9.]+) %"
    )
    for printed, double, single in (
        (rollers, FollowerKind.double_roller, FollowerKind.single_roller),
        (concave, FollowerKind.double_concave, FollowerKind.single_concave),
    ):
        ratio = (
            sums[double]["contact_force_max_N"]["high_dwell_two_contact"]
            / sums[single]["contact_force_max_N"]["high_dwell"]
        )
        assert printed == f"{100 * ratio:.2f}"


def test_the_section_6_geometry_is_what_camcore_computes(sums):
    printed = _printed(
        r"Geometry: R = ([0-9.]+) mm, psi_h = ([0-9.]+) deg, psi_l = ([0-9.]+) deg, .*?"
        r"max pressure angle ([0-9.]+) deg rise, ([0-9.]+) deg fall"
    )
    s = sums[FollowerKind.double_concave]
    pa = s["pressure_angle_max_deg"]
    assert printed == (
        f"{s['dwell_radius_mm']:.4f}",
        f"{s['psi_h_deg']:.4f}",
        f"{s['psi_l_deg']:.4f}",
        f"{pa['rise']:.2f}",
        f"{pa['fall']:.2f}",
    )


def test_the_offset_figures_are_what_camcore_computes():
    """The README's figures for the offset's turn (Offset single followers): the rise's
    largest |phi| of the paper example as a single roller at four offsets."""
    from camcore.analysis import analyze

    printed = _printed(
        r"largest \|phi\| is ([0-9.]+) deg at e_s = 0, ([0-9.]+) at 10 mm, ([0-9.]+) at "
        r"15 mm and ([0-9.]+) at 20 mm"
    )
    data = load_preset("paper_example").with_kind(FollowerKind.single_roller).model_dump()
    computed = []
    for e_s in (0.0, 10.0, 15.0, 20.0):
        data["follower"]["single_offset_mm"] = e_s
        s = summary(analyze(Design.model_validate(data), verify=False))
        computed.append(f"{s['pressure_angle_max_deg']['rise']:.2f}")
    assert printed == tuple(computed)


def test_the_download_name_shown_is_the_papers_example_s():
    """The README's example download name is the one the app gives the paper's example
    now (its fingerprint moves with every new design field: a maker's review found it
    stale)."""
    from app.panels import file_stem

    (printed,) = _printed(r"design \(`([a-z0-9_-]+)\.stl` for the")
    assert printed == file_stem(load_preset("paper_example"))


def test_the_proposed_spring_s_jump_speed():
    """The README's example of *Use the proposed spring rate*: the paper example's k
    and jump speed before and after (the proposal at the design's preload)."""
    k0, k1, n0, n1 = _printed(r"k ([\d.]+) → ([\d.]+) N/m, jump speed (\d+) → (\d+) rpm")
    d = load_preset("paper_example")
    before = summary(analyze(d, verify=False))
    k = before["spring_proposal"]["spring_rate_N_per_m"]
    dyn = d.dynamics.model_copy(update={"spring_rate_N_per_m": k})
    after = summary(analyze(d.model_copy(update={"dynamics": dyn}), verify=False))
    assert (float(k0), float(k1)) == (d.dynamics.spring_rate_N_per_m, k)
    assert (int(n0), int(n1)) == (round(before["jump_speed_rpm"]), round(after["jump_speed_rpm"]))


def test_the_explore_list_example():
    """The README's example of Explore's list of front designs: the review's smallest
    double-roller cam (20 mm / 120 deg at 300 rpm, r_b 12, r_c 8)."""
    from camcore import sweep

    r_b, r_c, big_r, stress = _printed(
        r'"double roller, r_b (\d+), r_c (\d+) → R ([\d.]+) mm, σ_H ([\d.]+) MPa"'
    )
    data = load_preset("paper_example").model_dump(mode="json")
    data["motion"].update(lift_mm=20, rise_deg=120, high_dwell_deg=60, fall_deg=120)
    data["cam"].update(speed_rpm=300)
    point = {
        "follower.kind": "double_roller",
        "cam.base_radius_mm": float(r_b),
        "follower.roller_radius_mm": float(r_c),
    }
    (row,) = sweep.fast_rows(data, [point])
    assert row["valid"]
    assert (big_r, stress) == (
        f"{row['dwell_radius_mm']:.4g}",
        f"{row['contact_stress_max_MPa.cycle']:.4g}",
    )
