"""Validation and timestamp helpers shared by the trajectory and relations metrics."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def _stamps(t: ArrayLike, name: str) -> NDArray[np.float64]:
    a = np.asarray(t, dtype=float)
    if a.ndim != 1:
        raise ValueError(f"{name} must have shape (N,), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def _nearest(query: NDArray[np.float64], stamps: NDArray[np.float64]) -> NDArray[np.intp]:
    """Index into ``stamps`` (any order) of the stamp nearest to each query, shape (Q,)."""
    order = np.argsort(stamps, kind="stable")
    s = stamps[order]
    pos = np.searchsorted(s, query)
    lo = np.clip(pos - 1, 0, len(s) - 1)
    hi = np.clip(pos, 0, len(s) - 1)
    take_hi = np.abs(s[hi] - query) < np.abs(s[lo] - query)
    return order[np.where(take_hi, hi, lo)]


def _poses(p: ArrayLike, name: str, cols: tuple[int, ...] = (3,)) -> NDArray[np.float64]:
    a = np.asarray(p, dtype=float)
    if a.ndim != 2 or a.shape[1] not in cols:
        shapes = " or ".join(f"(N, {c})" for c in cols)
        raise ValueError(f"{name} must have shape {shapes}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def _pair(est: ArrayLike, ref: ArrayLike, cols: tuple[int, ...]) -> tuple[NDArray, NDArray]:
    e, r = _poses(est, "est_poses", cols), _poses(ref, "ref_poses", cols)
    if len(e) != len(r):
        raise ValueError(
            f"est_poses and ref_poses must be associated pose by pose (fhslam.metrics."
            f"associate), got {len(e)} and {len(r)} poses"
        )
    if len(e) == 0:
        raise ValueError("no poses to compare")
    return e, r
