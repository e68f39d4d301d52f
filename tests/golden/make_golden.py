"""Record the golden outputs that pin the package's numbers across a refactor.

Run from the repository root: ``python tests/golden/make_golden.py [--check]``. Writes
``tests/golden/golden.npz`` (or, with ``--check``, compares against it and prints the largest
difference per case). The cases are computed by :func:`cases` through the package's public
calls; ``tests/test_golden.py`` recomputes them and compares.
"""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "golden.npz"


def arithmetic_fingerprint() -> str:
    """A hash of the floating-point results of the primitives the package's numbers rest on:
    NumPy's transcendental ufuncs (SIMD paths differ by CPU), BLAS products and LAPACK
    solves, SciPy's sparse solver, OpenCV's distance transform (as the scan matcher rounds it) and
    a numba kernel. Where it
    equals the recorded one, the golden numbers must come out bit for bit."""
    import cv2
    import scipy.sparse as sp
    from numba import njit
    from scipy.sparse.linalg import spsolve

    @njit(cache=False)
    def kernel(x):  # pragma: no cover
        out = np.empty_like(x)
        for i in range(x.shape[0]):
            out[i] = np.cos(x[i]) * np.sin(0.5 * x[i]) + np.floor(x[i] / 0.02) * np.hypot(x[i], 1.0)
        return out

    rng = np.random.default_rng(0)
    x = rng.uniform(-50, 50, 4096)
    y = x[::-1].copy()
    a = rng.normal(size=(64, 64))
    img = (rng.random((64, 64)) > 0.05).astype(np.uint8) * 255
    precise = cv2.DIST_MASK_PRECISE
    parts = [
        np.sin(x), np.cos(x), np.arctan2(x, y), np.exp(x / 50), np.hypot(x, y),
        np.sqrt(np.abs(x)), np.log1p(np.abs(x)), np.mod(x, 2 * np.pi),
        a @ a, a[:, :3].T @ a[:, :3], np.linalg.eigh(a + a.T)[0],
        np.linalg.lstsq(a, x[:64], rcond=None)[0],
        spsolve(sp.csc_matrix(a @ a.T + 64 * np.eye(64)), x[:64]),
        np.rint(np.square(cv2.distanceTransform(img, cv2.DIST_L2, precise), dtype=np.float64)),
        kernel(x),
    ]  # fmt: skip
    h = hashlib.sha256()
    for p in parts:
        h.update(np.ascontiguousarray(p, dtype=np.float64).tobytes())
    return h.hexdigest()


def lines_array(lines) -> np.ndarray:
    """Lines as rows (rho, theta, n, length, sp_x, sp_y, ep_x, ep_y, rms)."""
    return np.array(
        [[ln.rho, ln.theta, ln.n, ln.length, *ln.sp, *ln.ep, ln.rms] for ln in lines], float
    ).reshape(-1, 9)


def difference(case: str, got: np.ndarray, want: np.ndarray) -> float:
    """Largest absolute difference, angles wrapped (pose theta, line theta); inf for a shape
    mismatch, 0 for two empty arrays."""
    if got.shape != want.shape:
        return float("inf")
    if got.size == 0:
        return 0.0
    d = np.abs(got - want)
    col = 2 if case.endswith("/poses") else 1 if case.endswith(("/map", "/lines")) else None
    if col is not None:
        a = d[:, col]
        d[:, col] = np.minimum(a, np.abs(2 * np.pi - a))
    return float(np.max(d))


def cases(api, data_dir: Path | None) -> dict[str, np.ndarray]:
    """Every golden case, by name. ``api`` provides the calls (old or new layout)."""
    out: dict[str, np.ndarray] = {}
    log = api.paper_log()
    rows = []
    for k in range(0, len(log), 5):
        pts, _ = api.scan_to_points(log.ranges[k], log.angles, log.max_range)
        for ln in api.extract_lines(pts):
            rows.append([*lines_array([ln])[0], k, ln.inliers.sum()])
    out["extract/paper/lines"] = np.array(rows)
    drift = api.slam_log()
    for method in ("fht", "graph", "classical", "ekf", "odometry"):
        r = api.run_slam(drift, method)
        out[f"slam/paper/{method}/poses"] = r.poses
        out[f"slam/paper/{method}/map"] = lines_array(r.map)
    deg = api.degrade(drift, drop_fraction=0.1, clutter_fraction=0.05, seed=1)
    for method in ("fht", "graph", "ekf"):
        r = api.run_slam(deg, method)
        out[f"slam/degraded/{method}/poses"] = r.poses
        out[f"slam/degraded/{method}/map"] = lines_array(r.map)
    laps = api.three_laps()
    r = api.run_slam(laps, "graph")
    out["slam/random109x3/graph/poses"] = r.poses
    out["slam/random109x3/graph/map"] = lines_array(r.map)
    if data_dir is not None:
        for name, n, methods in (
            ("mit-csail", 400, ("fht", "graph")),
            ("fr079", 600, ("fht", "graph")),
            ("fr-clinic", 400, ("fht",)),
            ("intel", 2500, ("graph",)),
        ):
            real = api.head(api.load_log(name), n)
            for method in methods:
                r = api.run_slam(real, method)
                out[f"real/{name}/{method}/poses"] = r.poses
                out[f"real/{name}/{method}/map"] = lines_array(r.map)
    return out


class API:
    """The package calls the cases use (update them when a module moves)."""

    def __init__(self):
        from dataclasses import replace

        from fhslam import figures
        from fhslam.datasets import load_log
        from fhslam.extraction import extract_lines
        from fhslam.pipeline import run_slam
        from fhslam.scan import scan_to_points
        from fhslam.sim import OdometryNoise, degrade, load_world, simulate

        self.paper_log = figures.paper_log
        self.slam_log = figures.slam_log
        self.scan_to_points = lambda r, a, m: scan_to_points(r, a, max_range=m)
        self.extract_lines = extract_lines
        self.run_slam = run_slam
        self.degrade = degrade
        self.load_log = load_log
        self.three_laps = lambda: simulate(
            load_world("random:109"), seed=0, odometry=OdometryNoise.drifting(), laps=3
        )

        def head(log, n):
            return replace(
                log,
                timestamps=log.timestamps[:n],
                ranges=log.ranges[:n],
                odometry=log.odometry[:n],
                angle_offsets=None if log.angle_offsets is None else log.angle_offsets[:n],
            )

        self.head = head


def main() -> int:
    data = Path(__file__).resolve().parents[3] / "shared" / "data"
    got = cases(API(), data if data.is_dir() else None)
    if "--check" in sys.argv:
        want = np.load(GOLDEN)
        same = str(want["fingerprint"]) == arithmetic_fingerprint()
        print(f"arithmetic fingerprint {'matches' if same else 'differs from'} the recording")
        worst = 0.0
        for k, v in got.items():
            d = difference(k, v, want[k])
            worst = max(worst, d)
            print(f"{k:45s} {v.shape!s:>12} max |diff| {d:.3g}")
        print(f"worst {worst:.3g}")
        return 0
    import matplotlib

    np.savez_compressed(
        GOLDEN,
        fingerprint=np.array(arithmetic_fingerprint()),
        matplotlib=np.array(matplotlib.__version__),
        **got,
    )
    print(f"wrote {len(got)} cases to {GOLDEN}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
