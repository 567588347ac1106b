"""camcore: disk cams with translating followers, after Chuang, Hsu & Chang.

Data flows one way: ``Design`` (camcore.model) -> ``analyze`` (camcore.analysis)
-> summaries (camcore.report) and exports (camcore.export). Modules, one concept each:

- model    : the pydantic design model (units in field names), JSON load/save, presets
- motion   : motion laws and the displacement program S(theta) with V, A, J
- profile  : profile synthesis by instant centres (Eqs. 1-21), signed radii for all followers
- forces   : follower forces with guide friction and the four guide-contact modes (Eqs. 29-41)
- contact  : Hertz line-contact stress (Eq. 42)
- checks   : design limits as violations (Eqs. 22, 27, 28, pressure angle, jump, ...)
- verify   : independent geometric check of the finished profile
- analysis : the pipeline tying these together
- report, export, cli : numbers, files and the command line
"""

import functools
import hashlib
from pathlib import Path

from .analysis import Analysis, analyze, compare
from .model import Design, DesignError, FollowerKind, MotionLaw, load_design, load_preset


@functools.cache
def code_fingerprint() -> str:
    """A short hash of camcore's own files (its .py and the preset .json): two
    checkouts of one version (or an edited install) differ here, where
    ``package_version`` does not. A sweep's finished chunks and the Dask workers it
    uses must share it (camcore.sweep)."""
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    # the files a wheel ships, by name: not whatever else lies in a source tree (a
    # review's stray .ipynb_checkpoints/*.py had made one commit two codes)
    files = [
        *root.glob("*.py"),
        *(root / "presets").glob("*.py"),
        *(root / "presets").glob("*.json"),
    ]
    for f in sorted(files):
        h.update(f.relative_to(root).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]


def package_version() -> str:
    """The installed camdesigner's version ("unknown" in a source tree never installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("camdesigner")
    except PackageNotFoundError:
        return "unknown"


__all__ = [
    "Analysis",
    "Design",
    "DesignError",
    "FollowerKind",
    "MotionLaw",
    "analyze",
    "compare",
    "load_design",
    "load_preset",
    "package_version",
]
