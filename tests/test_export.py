"""Exports with a shaft bore: a watertight solid with the exact volume, a DXF circle."""

import io
import math

import ezdxf
import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from camcore import export
from camcore.analysis import analyze
from camcore.model import Design, FollowerKind, load_preset


def with_bore(diameter_mm: float, kind=FollowerKind.double_concave) -> Design:
    data = load_preset("paper_example").with_kind(kind).model_dump()
    data["cam"]["bore_diameter_mm"] = diameter_mm
    return Design.model_validate(data)


@pytest.mark.parametrize("kind", list(FollowerKind))
def test_bored_cam_is_watertight_with_exact_volume(kind):
    a = analyze(with_bore(25.0, kind), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    m = export.BORE_SEGMENTS
    hole_mm2 = 0.5 * m * 12.5**2 * math.sin(2 * math.pi / m)  # the bore polygon
    assert mesh.volume == pytest.approx((a.profile.area * 1e6 - hole_mm2) * 15.0, rel=1e-6)
    # the hole goes right through: a closed surface of genus 1 (Euler number 0; 2 without)
    assert mesh.euler_number == 0
    solid = trimesh.load(io.BytesIO(export.stl_bytes(analyze(with_bore(0.0, kind)))), "stl")
    assert solid.euler_number == 2


def test_bore_in_dxf():
    a = analyze(with_bore(30.0), verify=False)
    doc = ezdxf.read(io.StringIO(export.dxf_bytes(a).decode()))
    bores = [e for e in doc.modelspace() if e.dxf.layer == "BORE"]
    assert len(bores) == 1 and bores[0].dxf.radius == pytest.approx(15.0)


def test_bore_larger_than_base_circle_is_rejected():
    with pytest.raises(ValidationError, match="bore_diameter_mm"):
        with_bore(160.0)


@settings(max_examples=25, deadline=None, derandomize=True)
@given(
    preset=st.sampled_from(["paper_example", "indexer_345", "valve_lift_roller",
                            "classroom_harmonic"]),
    fraction=st.floats(min_value=0.0, max_value=0.999),
)
def test_any_bore_inside_the_base_circle_exports_a_solid(preset, fraction):
    d = load_preset(preset)
    data = d.model_dump()
    data["cam"]["bore_diameter_mm"] = fraction * 2 * d.cam.base_radius_mm
    data["limits"]["resolution_deg"] = 0.5
    a = analyze(Design.model_validate(data), verify=False)
    mesh = export.cam_mesh(a)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert mesh.euler_number == (0 if fraction > 0 else 2)


@pytest.mark.parametrize("kind", [FollowerKind.double_roller, FollowerKind.double_concave])
@pytest.mark.parametrize("offset_mm", [0.0, 1e-9, 1e-6, 1e-4])
def test_tiny_offsets_give_watertight_stl_once_read_back(kind, offset_mm):
    """STL stores float32: contact points 1e-6 mm apart merge when read back. The export
    welds in float32 first, so the file as read is still a closed solid."""
    data = load_preset("paper_example").with_kind(kind).model_dump()
    data["follower"]["offset_mm"] = offset_mm
    a = analyze(Design.model_validate(data), verify=False)
    mesh = trimesh.load(io.BytesIO(export.stl_bytes(a)), file_type="stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume == pytest.approx(a.profile.area * 1e6 * 15.0, rel=1e-7)


def test_weld_refuses_a_profile_that_turns_back():
    square = np.array([[1.0, 0], [0, 1], [-1, 0], [0.5, 0.9], [0, -1]])
    with pytest.raises(export.ExportError, match="not star-shaped"):
        export.weld_float32(square)
