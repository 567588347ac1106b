"""One speed-up of viser 1.1.1 (pinned), installed by app.main.

Every scene or GUI handle viser creates computes ``typing.get_type_hints`` of its
props class in a per-instance cached property: ~0.2 ms per node, 4-5 ms of a 17 ms
redraw that re-adds about twenty nodes. The hints depend only on the class, so they
are cached per class here; the values are the same objects viser would compute.
"""

from __future__ import annotations

import functools
from typing import Any, get_type_hints

from viser import _assignable_props_api as props_api


@functools.cache
def _hints(props_type: Any) -> dict[str, Any]:
    return get_type_hints(props_type)


def _prop_hints(self) -> dict[str, Any]:
    props_type: Any = type(self._impl.props)
    return _hints(props_type)


def install() -> None:
    """Replace the per-instance hints property (idempotent)."""
    cls = props_api.AssignablePropsBase
    if not isinstance(cls.__dict__.get("_prop_hints"), property):
        cls._prop_hints = property(_prop_hints)  # type: ignore[assignment]
