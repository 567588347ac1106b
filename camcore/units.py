"""Unit conversion at the edges: the one place that knows how many metres a millimetre is.

camcore computes in SI (metres, radians, newtons, pascals, seconds). Designs carry
engineering units in their field names (``_mm``, ``_deg``, ``_rpm``, ``_GPa``, ``_g``);
reports, exports and the app show millimetres, degrees, MPa. Convert with these
helpers, never with a bare ``1e3`` or ``1e-3`` in the code.

Each helper works on floats and numpy arrays alike.
"""

from __future__ import annotations

import math

MM = 1e-3  # metres per millimetre
UM = 1e-6  # metres per micrometre
DEG = math.pi / 180.0  # radians per degree
GPA = 1e9  # pascals per gigapascal
MPA = 1e6  # pascals per megapascal
GRAM = 1e-3  # kilograms per gram
RPM = 2.0 * math.pi / 60.0  # rad/s per rev/min


def to_mm(x_m):
    """Metres -> millimetres."""
    return x_m / MM


def from_mm(x_mm):
    """Millimetres -> metres."""
    return x_mm * MM


def to_deg(x_rad):
    """Radians -> degrees."""
    return x_rad / DEG


def from_deg(x_deg):
    """Degrees -> radians."""
    return x_deg * DEG


def to_mpa(x_pa):
    """Pascals -> megapascals."""
    return x_pa / MPA


def to_um_per_mcycle(x_m_per_cycle):
    """Metres per cycle -> micrometres per million cycles (wear depth)."""
    return x_m_per_cycle / UM * 1e6
