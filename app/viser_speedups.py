"""Two changes to viser 1.1.1 (pinned), installed by app.main.

1. Every scene or GUI handle viser creates computes ``typing.get_type_hints`` of its
   props class in a per-instance cached property: ~0.2 ms per node, 4-5 ms of a 17 ms
   redraw that re-adds about twenty nodes. The hints depend only on the class, so they
   are cached per class here; the values are the same objects viser would compute.

2. Setting a prop casts its value to the prop's hint, and the cast builds the hints it
   compares against (``npt.NDArray[np.float64]``, ...) anew on every call (~0.5 ms of
   a redraw). It also casts uPlot data to float64, although the client reads any
   typed array: the curves are most of what a tab receives per edit (30 students
   editing once a second need the server's network), so float32 curve data, which
   app.plots sends, is kept as it is (half the bytes; 7 significant digits, more than
   a plot shows), and so are its int8 columns (the shading and the vertical lines).
   Everything else is cast as viser does.
"""

from __future__ import annotations

import functools
from typing import Any, get_type_hints

import numpy as np
import numpy.typing as npt
from viser import _assignable_props_api as props_api

_F16 = npt.NDArray[np.float16]
_F32 = npt.NDArray[np.float32]
_F64 = npt.NDArray[np.float64]
_U8 = npt.NDArray[np.uint8]
_KEPT = (np.dtype(np.float32), np.dtype(np.int8))  # uPlot data sent as app.plots makes it
VISER_CAST = props_api.AssignablePropsBase._cast_value_recursive  # viser's own (tests)


@functools.cache
def _hints(props_type: Any) -> dict[str, Any]:
    return get_type_hints(props_type)


def _prop_hints(self) -> dict[str, Any]:
    props_type: Any = type(self._impl.props)
    return _hints(props_type)


def _cast_value_recursive(self, hint: Any, value: Any, prop_name: str) -> Any:
    """viser 1.1.1's AssignablePropsBase._cast_value_recursive with the hints built
    once, and float32 uPlot ``data`` kept (module docstring)."""
    if hint == _F64:
        if prop_name == "data" and isinstance(value, np.ndarray) and value.dtype in _KEPT:
            return value
        return np.asarray(value).astype(np.float64)
    if hint == _F32:
        return np.asarray(value).astype(np.float32)
    if hint == _F16:
        return np.asarray(value).astype(np.float16)
    if hint == _U8 and "color" in prop_name:
        return props_api.colors_to_uint8(value)
    if isinstance(value, np.ndarray):
        return value
    args = getattr(hint, "__args__", None)
    if (
        isinstance(value, tuple)
        and getattr(hint, "__origin__", None) is tuple
        and args is not None
        and len(args) == 2
        and args[1] is ...
    ):
        return tuple(_cast_value_recursive(self, args[0], item, prop_name) for item in value)
    return value


def install() -> None:
    """Replace the per-instance hints property and the cast (idempotent)."""
    cls = props_api.AssignablePropsBase
    if not isinstance(cls.__dict__.get("_prop_hints"), property):
        cls._prop_hints = property(_prop_hints)  # type: ignore[assignment]
    cls._cast_value_recursive = _cast_value_recursive  # type: ignore[method-assign]
