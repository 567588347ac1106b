"""One row of a benchmark table (bench/run.py): the median and spread of times [ms]."""

from __future__ import annotations

import numpy as np


def row(name: str, ms, note: str = "") -> dict:
    """{name, median_ms, p10_ms, p90_ms, n, note} of the finite times ``ms`` [ms] (one
    value, or any iterable of them); no figures when there are none."""
    a = np.atleast_1d(np.asarray(ms if np.isscalar(ms) else list(ms), float))
    a = a[np.isfinite(a)]
    if a.size == 0:
        return {
            "name": name,
            "median_ms": None,
            "p10_ms": None,
            "p90_ms": None,
            "n": 0,
            "note": note,
        }
    return {
        "name": name,
        "median_ms": float(np.median(a)),
        "p10_ms": float(np.percentile(a, 10)),
        "p90_ms": float(np.percentile(a, 90)),
        "n": int(a.size),
        "note": note,
    }
