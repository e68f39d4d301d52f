"""Classical Hough transform line extractors: the baselines the paper argues against.

Every point votes for every line ``rho = x cos(theta) + y sin(theta)`` through it (paper
eq. (1)) in a (rho, theta) accumulator over the whole scan; peaks of the accumulator are
lines. Four variants, all with the call shape of the main extractor
``f(points, params=None, pose=None) -> list[Line]``:

- :func:`hough_numpy_accumulator` -- the plain full accumulator in NumPy, easy to read;
- :func:`hough_opencv_pointset` -- the same on the points, ``cv2.HoughLinesPointSet``;
- :func:`hough_opencv_raster` -- the scan drawn into an image, ``cv2.HoughLines``;
- :func:`hough_opencv_probabilistic` -- that image, ``cv2.HoughLinesP`` (Matas et al. 2000).

All four turn their peaks into segments with the same rule
(:func:`fhslam.baselines._peaks.lines_from_peaks`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from fhslam.baselines._peaks import lines_from_peaks
from fhslam.geometry import as_points, line_through
from fhslam.lines import Line

#: Largest raster (pixels) the image-based variants will allocate.
MAX_RASTER_PIXELS = 25_000_000


@dataclass(frozen=True)
class ClassicalHoughParams:
    """Parameters of the classical Hough baselines.

    Attributes
    ----------
    rho_step : float
        Accumulator resolution in rho, metres.
    theta_step_deg : float
        Accumulator resolution in theta, degrees (theta spans [0, 180)).
    max_range : float
        Accumulator spans rho in [-max_range, max_range], metres (widened to the points'
        largest distance from the origin when they reach further).
    vote_threshold : int
        Fewest votes for a peak (points for the point-set variants, pixels for the raster ones).
    inlier_dist : float
        Largest orthogonal distance of a point from a peak's line to support it, metres.
    max_gap : float
        Largest distance between consecutive inliers inside one segment, metres.
    min_points : int
        Fewest points in a segment (>= 2).
    min_length : float
        Shortest segment, metres.
    max_lines : int
        Most lines returned.
    refine : bool
        False: report the peak's (rho, theta) itself (classical Hough); True: least-squares
        refit of each segment.
    pixel : float
        Pixel size of the raster variants, metres per pixel.
    hough_p_min_line_length : float
        ``cv2.HoughLinesP`` minimum segment length, metres.
    hough_p_max_gap : float
        ``cv2.HoughLinesP`` largest gap bridged inside a segment, metres.
    """

    rho_step: float = 0.01
    theta_step_deg: float = 1.0
    max_range: float = 8.0
    vote_threshold: int = 6
    inlier_dist: float = 0.03
    max_gap: float = 0.3
    min_points: int = 6
    min_length: float = 0.3
    max_lines: int = 30
    refine: bool = False
    pixel: float = 0.02
    hough_p_min_line_length: float = 0.3
    hough_p_max_gap: float = 0.3

    def __post_init__(self) -> None:
        for name in ("rho_step", "theta_step_deg", "max_range", "inlier_dist", "max_gap", "pixel"):
            if not getattr(self, name) > 0:
                raise ValueError(
                    f"ClassicalHoughParams.{name} must be > 0, got {getattr(self, name)}"
                )
        for name in ("min_length", "hough_p_min_line_length", "hough_p_max_gap"):
            if not getattr(self, name) >= 0:
                raise ValueError(
                    f"ClassicalHoughParams.{name} must be >= 0, got {getattr(self, name)}"
                )
        if self.theta_step_deg >= 180:
            raise ValueError(f"theta_step_deg must be < 180, got {self.theta_step_deg}")
        if self.vote_threshold < 1 or self.max_lines < 1 or self.min_points < 2:
            raise ValueError(
                "ClassicalHoughParams needs vote_threshold >= 1, max_lines >= 1, min_points >= 2; "
                f"got {self.vote_threshold}, {self.max_lines}, {self.min_points}"
            )

    @property
    def theta_step(self) -> float:
        """Accumulator resolution in theta, radians."""
        return float(np.radians(self.theta_step_deg))


def _peaks_to_lines(
    p: NDArray[np.float64], peaks: ArrayLike, params: ClassicalHoughParams, pose: ArrayLike | None
) -> list[Line]:
    return lines_from_peaks(
        p,
        peaks,
        inlier_dist=params.inlier_dist,
        max_gap=params.max_gap,
        min_points=params.min_points,
        min_length=params.min_length,
        max_lines=params.max_lines,
        refine=params.refine,
        pose=pose,
    )


def _rho_max(p: NDArray[np.float64], params: ClassicalHoughParams) -> float:
    return max(params.max_range, float(np.hypot(p[:, 0], p[:, 1]).max()) + params.rho_step)


# --- the plain NumPy accumulator ------------------------------------------------------------


def hough_accumulator(
    points: ArrayLike, rho_step: float, theta_step: float, rho_max: float
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
    """The full classical Hough accumulator: every point votes once at every theta.

    Point ``(x, y)`` votes for the cell nearest ``(x cos(theta) + y sin(theta), theta)``
    (paper eq. (1)) in every theta column. Votes beyond ``rho_max`` are dropped.

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Points, metres.
    rho_step : float
        Rho resolution, metres.
    theta_step : float
        Theta resolution, radians; theta spans [0, pi).
    rho_max : float
        Rho spans [-rho_max, rho_max] (rounded up to whole steps), metres.

    Returns
    -------
    acc : ndarray of int, shape (n_theta, n_rho)
        Votes; ``acc[i, j]`` counts points near the line ``(rhos[j], thetas[i])``.
    thetas : ndarray, shape (n_theta,)
        Cell centres in theta, radians: ``0, theta_step, ...`` below pi.
    rhos : ndarray, shape (n_rho,)
        Cell centres in rho, metres: ``-k rho_step, ..., 0, ..., k rho_step``.
    """
    p = as_points(points)
    if not (rho_step > 0 and 0 < theta_step < np.pi and rho_max > 0):
        raise ValueError(
            "hough_accumulator needs rho_step > 0, 0 < theta_step < pi, rho_max > 0; "
            f"got {rho_step}, {theta_step}, {rho_max}"
        )
    thetas = np.arange(int(np.ceil(np.pi / theta_step - 1e-9))) * theta_step
    k = int(np.ceil(rho_max / rho_step - 1e-9))
    rhos = np.arange(-k, k + 1) * rho_step
    # rho of every point at every theta, shape (N, n_theta), as a rho cell index.
    r = p[:, :1] * np.cos(thetas) + p[:, 1:] * np.sin(thetas)
    ri = np.rint(r / rho_step).astype(np.intp) + k
    ti = np.broadcast_to(np.arange(len(thetas)), ri.shape)
    ok = (ri >= 0) & (ri < len(rhos))
    flat = ti[ok] * len(rhos) + ri[ok]
    acc = np.bincount(flat, minlength=len(thetas) * len(rhos)).reshape(len(thetas), len(rhos))
    return acc, thetas, rhos


def _local_maxima(acc: NDArray[np.int64], threshold: int) -> tuple[NDArray, NDArray]:
    """Cells with at least ``threshold`` votes and no larger 3x3 neighbour, best first.

    Returns the (theta, rho) index arrays of the peaks, ordered by votes, most first.
    """
    ti, ri = np.nonzero(acc >= threshold)
    votes = acc[ti, ri]
    is_max = np.ones(len(votes), dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            # Clipping at the border compares an edge cell with itself, which never rejects it.
            ni = np.clip(ti + di, 0, acc.shape[0] - 1)
            nj = np.clip(ri + dj, 0, acc.shape[1] - 1)
            is_max &= votes >= acc[ni, nj]
    order = np.argsort(-votes[is_max], kind="stable")
    return ti[is_max][order], ri[is_max][order]


def hough_numpy_accumulator(
    points: ArrayLike, params: ClassicalHoughParams | None = None, pose: ArrayLike | None = None
) -> list[Line]:
    """Classical Hough with a plain NumPy (rho, theta) accumulator over the whole scan.

    Builds :func:`hough_accumulator` at ``rho_step`` x ``theta_step_deg``, takes the cells with
    at least ``vote_threshold`` votes that are maxima of their 3x3 neighbourhood, strongest
    first, and turns them into segments (:func:`~fhslam.baselines._peaks.lines_from_peaks`).

    Parameters
    ----------
    points : array-like, shape (N, 2)
        Finite scan points in scan order, metres (any frame).
    params : ClassicalHoughParams, optional
    pose : array-like, shape (3,), optional
        Robot pose in the points' frame, for ``Line.dir`` and ``Line.d``.

    Returns
    -------
    list of Line
        ``inliers`` index ``points``; ``[]`` for fewer than 2 points.
    """
    p = as_points(points)
    params = params or ClassicalHoughParams()
    if len(p) < 2:
        return []
    acc, thetas, rhos = hough_accumulator(
        p, params.rho_step, params.theta_step, _rho_max(p, params)
    )
    ti, ri = _local_maxima(acc, params.vote_threshold)
    return _peaks_to_lines(p, np.column_stack([rhos[ri], thetas[ti]]), params, pose)


# --- OpenCV on the point set -----------------------------------------------------------------


def hough_opencv_pointset(
    points: ArrayLike, params: ClassicalHoughParams | None = None, pose: ArrayLike | None = None
) -> list[Line]:
    """Classical Hough on the points with ``cv2.HoughLinesPointSet``.

    Accumulator ``rho_step`` x ``theta_step_deg`` over rho in [-R, R], theta in [0, pi);
    OpenCV's peaks (votes > ``vote_threshold - 1``, at most ``4 * max_lines + 50``), strongest
    first, become segments as in :func:`hough_numpy_accumulator`.

    Parameters and returns as :func:`hough_numpy_accumulator`.
    """
    p = as_points(points)
    params = params or ClassicalHoughParams()
    if len(p) < 2:
        return []
    r_max = _rho_max(p, params)
    found = cv2.HoughLinesPointSet(
        p.astype(np.float32).reshape(-1, 1, 2),
        4 * params.max_lines + 50,  # lines_max: room for weaker peaks of the same walls
        params.vote_threshold - 1,  # OpenCV keeps votes > threshold
        -r_max,
        r_max,
        params.rho_step,
        0.0,
        np.pi,
        params.theta_step,
    )
    if found is None:
        return []
    found = found.reshape(-1, 3)  # rows (votes, rho, theta); OpenCV 4 gave (K, 1, 3)
    found = found[np.argsort(-found[:, 0], kind="stable")]
    return _peaks_to_lines(p, found[:, 1:3], params, pose)


# --- OpenCV on a raster image ----------------------------------------------------------------


def rasterise(
    points: NDArray[np.float64], pixel: float, margin_px: int = 2
) -> tuple[NDArray[np.uint8], NDArray[np.float64]]:
    """Draw points into a binary image for the image-based Hough transforms.

    Pixel ``(col, row)`` is the point ``origin + pixel * (col, row)`` (column = x, row = y,
    no flip), so OpenCV's image lines map back with ``x = origin + pixel * u``.

    Parameters
    ----------
    points : ndarray, shape (N, 2), N >= 1
        Points, metres.
    pixel : float
        Pixel size, metres.
    margin_px : int
        Empty border, pixels.

    Returns
    -------
    image : ndarray of uint8, shape (H, W)
        255 where a point falls, 0 elsewhere.
    origin : ndarray, shape (2,)
        Metric position of pixel (0, 0): the bounding-box minimum minus the margin.
    """
    origin = points.min(axis=0) - margin_px * pixel
    uv = np.rint((points - origin) / pixel).astype(np.intp)  # (col, row)
    w, h = uv.max(axis=0) + margin_px + 1
    if w * h > MAX_RASTER_PIXELS:
        raise ValueError(
            f"rasterising the points at {pixel} m/pixel needs a {w}x{h} image; "
            "use a larger ClassicalHoughParams.pixel or crop the scan"
        )
    image = np.zeros((h, w), dtype=np.uint8)
    image[uv[:, 1], uv[:, 0]] = 255
    return image, origin


def _rasterised_input(points: ArrayLike, params: ClassicalHoughParams | None):
    """Validated points, params and the scan drawn as an image (None for < 2 points)."""
    p = as_points(points)
    params = params or ClassicalHoughParams()
    if len(p) < 2:
        return p, params, None, None
    image, origin = rasterise(p, params.pixel)
    return p, params, image, origin


def hough_opencv_raster(
    points: ArrayLike, params: ClassicalHoughParams | None = None, pose: ArrayLike | None = None
) -> list[Line]:
    """Classical Hough on the scan drawn as an image, with ``cv2.HoughLines``.

    Pixels of ``pixel`` metres; accumulator ``rho_step`` (in pixels: ``rho_step / pixel``) x
    ``theta_step_deg``. OpenCV's image line ``(rho_px, theta)`` is the metric line
    ``rho = rho_px * pixel + origin . (cos(theta), sin(theta))`` in the points' frame.

    Parameters and returns as :func:`hough_numpy_accumulator`.
    """
    p, params, image, origin = _rasterised_input(points, params)
    if image is None:
        return []
    found = cv2.HoughLines(
        image, params.rho_step / params.pixel, params.theta_step, params.vote_threshold - 1
    )
    if found is None:
        return []
    rho_px, theta = found.reshape(-1, 2).astype(float).T  # OpenCV sorts by votes
    rho = rho_px * params.pixel + origin[0] * np.cos(theta) + origin[1] * np.sin(theta)
    return _peaks_to_lines(p, np.column_stack([rho, theta]), params, pose)


def hough_opencv_probabilistic(
    points: ArrayLike, params: ClassicalHoughParams | None = None, pose: ArrayLike | None = None
) -> list[Line]:
    """Probabilistic Hough (``cv2.HoughLinesP``) on the scan drawn as an image.

    Each OpenCV segment (longer than ``hough_p_min_line_length``, gaps up to
    ``hough_p_max_gap``) gives the infinite metric line through its end points; longest
    segments first, they become lines as in :func:`hough_numpy_accumulator`.

    Parameters and returns as :func:`hough_numpy_accumulator`.
    """
    p, params, image, origin = _rasterised_input(points, params)
    if image is None:
        return []
    found = cv2.HoughLinesP(
        image,
        params.rho_step / params.pixel,
        params.theta_step,
        params.vote_threshold,  # HoughLinesP keeps votes >= threshold
        minLineLength=params.hough_p_min_line_length / params.pixel,
        maxLineGap=params.hough_p_max_gap / params.pixel,
    )
    if found is None:
        return []
    # (K, 4) pixel rows (u1, v1, u2, v2) -> (K, 2 ends, xy) metres, longest segment first.
    ends = origin + params.pixel * found.reshape(-1, 4).reshape(-1, 2, 2).astype(float)
    ends = ends[np.argsort(-np.hypot(*(ends[:, 1] - ends[:, 0]).T), kind="stable")]
    peaks = [line_through(a, b) for a, b in ends if np.any(a != b)]
    return _peaks_to_lines(p, peaks, params, pose)
