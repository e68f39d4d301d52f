"""The compiled kernels of Loop 1 (numba): each step of the fast Hough transform on ONE cluster.

Each step is written as the paper describes it (plain loops). The public functions of
:mod:`fhslam.extraction.fast_hough` validate their input and call these same kernels per
cluster, so what a notebook shows is exactly what the pipeline runs. NumPy vectorisation of
this loop costs 5-15 µs per array call on arrays this small and ~1.4 ms per scan; compiled,
the whole scan takes tens of µs (see ``fhslam bench``).
"""

from __future__ import annotations

import numpy as np

from fhslam._numba import njit
from fhslam.geometry import tls_normal_angle

_JIT = {"cache": True, "nogil": True, "fastmath": False}

_tls_normal_angle = njit(**_JIT)(tls_normal_angle)  # the one TLS formula, compiled


@njit(**_JIT)
def cluster_kernel(p, gap):
    n = p.shape[0]
    labels = np.zeros(n, np.int64)
    g2 = gap * gap
    for i in range(1, n):
        dx = p[i, 0] - p[i - 1, 0]
        dy = p[i, 1] - p[i - 1, 1]
        labels[i] = labels[i - 1] + (1 if dx * dx + dy * dy > g2 else 0)
    return labels


@njit(**_JIT)
def lone_kernel(p, gap):
    n = p.shape[0]
    lone = np.zeros(n, np.bool_)
    for i in range(1, n - 1):
        d_prev = np.hypot(p[i, 0] - p[i - 1, 0], p[i, 1] - p[i - 1, 1])
        d_next = np.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
        d_skip = np.hypot(p[i + 1, 0] - p[i - 1, 0], p[i + 1, 1] - p[i - 1, 1])
        lone[i] = d_prev > gap and d_next > gap and d_skip <= 2 * gap
    return lone


@njit(**_JIT)
def densify_kernel(p, step):
    """Insert points every <= step between consecutive points (one cluster)."""
    n = p.shape[0]
    extra = np.zeros(n, np.int64)
    total = n
    if step > 0:
        for i in range(n - 1):
            d = np.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
            extra[i] = max(int(np.ceil(d / step)) - 1, 0)
            total += extra[i]
    out = np.empty((total, 2))
    src = np.empty(total, np.int64)
    k = 0
    for i in range(n):
        out[k] = p[i]
        src[k] = i
        k += 1
        for j in range(1, extra[i] + 1):
            f = j / (extra[i] + 1)
            out[k, 0] = p[i, 0] + f * (p[i + 1, 0] - p[i, 0])
            out[k, 1] = p[i, 1] + f * (p[i + 1, 1] - p[i, 1])
            src[k] = -1
            k += 1
    return out, src


@njit(**_JIT)
def slope_histogram_kernel(p, u, n_bins, min_pair_dist, all_pairs):
    """Votes of the direction angle in [0, pi) of the line through point pairs (one cluster)."""
    m = p.shape[0]
    hist = np.zeros(n_bins, np.int64)
    d2min = min_pair_dist * min_pair_dist
    n_pairs = m * (m - 1) // 2 if all_pairs else u.shape[0]
    a, b = 0, 0
    for k in range(n_pairs):
        if all_pairs:
            b += 1
            if b >= m:
                a += 1
                b = a + 1
        else:
            a = int(u[k, 0] * m)
            b = int(u[k, 1] * m)
        dx = p[b, 0] - p[a, 0]
        dy = p[b, 1] - p[a, 1]
        if dx * dx + dy * dy < d2min:
            continue
        phi = np.arctan2(dy, dx)
        if phi < 0:
            phi += np.pi
        k_bin = min(int(phi * n_bins / np.pi), n_bins - 1)
        hist[k_bin] += 1
    return hist


@njit(**_JIT)
def dominant_kernel(hist):
    """Peak of the circularly [1, 2, 1]/4-smoothed histogram: (direction, support)."""
    n = hist.shape[0]
    best, k_best = -1.0, 0
    for k in range(n):
        s = 0.5 * hist[k] + 0.25 * (hist[k - 1] + hist[(k + 1) % n])
        if s > best:
            best, k_best = s, k
    return (k_best + 0.5) * np.pi / n, best


@njit(**_JIT)
def window_hough_kernel(p, phi, half, dtheta, rho_step):
    """rho-theta accumulator restricted to normal angles phi + pi/2 + [-half, half]*dtheta.

    rho is measured from the centroid of ``p``. Returns the peak (rho in the points' frame,
    theta), its votes, the accumulator (W, R), its thetas and the local rho of column 0.
    """
    m = p.shape[0]
    cx, cy = 0.0, 0.0
    for i in range(m):
        cx += p[i, 0]
        cy += p[i, 1]
    cx /= m
    cy /= m
    n_w = 2 * half + 1
    thetas = np.empty(n_w)
    for w in range(n_w):
        thetas[w] = phi + 0.5 * np.pi + (w - half) * dtheta
    idx = np.empty((n_w, m), np.int64)
    lo, hi = 1 << 62, -(1 << 62)
    for w in range(n_w):
        c, s = np.cos(thetas[w]), np.sin(thetas[w])
        for i in range(m):
            r = int(np.floor(((p[i, 0] - cx) * c + (p[i, 1] - cy) * s) / rho_step + 0.5))
            idx[w, i] = r
            lo = min(lo, r)
            hi = max(hi, r)
    acc = np.zeros((n_w, hi - lo + 1), np.int64)
    best, w_best, r_best = -1, 0, 0
    for w in range(n_w):
        for i in range(m):
            r = idx[w, i] - lo
            acc[w, r] += 1
            if acc[w, r] > best or (acc[w, r] == best and (w, r) < (w_best, r_best)):
                best, w_best, r_best = acc[w, r], w, r
    theta = thetas[w_best]
    rho = (r_best + lo) * rho_step + cx * np.cos(theta) + cy * np.sin(theta)
    return rho, theta, best, acc, thetas, lo * rho_step, cx, cy


@njit(**_JIT)
def tls_kernel(p, mask, theta_prev):
    """Total least squares over p[mask]: (rho, theta, count); theta kept near theta_prev."""
    n = 0
    mx, my = 0.0, 0.0
    for i in range(p.shape[0]):
        if mask[i]:
            n += 1
            mx += p[i, 0]
            my += p[i, 1]
    if n < 2:
        return np.nan, theta_prev, n
    mx /= n
    my /= n
    cxx, cyy, cxy = 0.0, 0.0, 0.0
    for i in range(p.shape[0]):
        if mask[i]:
            dx, dy = p[i, 0] - mx, p[i, 1] - my
            cxx += dx * dx
            cyy += dy * dy
            cxy += dx * dy
    if cxx + cyy == 0.0:
        return np.nan, theta_prev, n
    theta = _tls_normal_angle(cxx, cyy, cxy)
    if np.cos(theta - theta_prev) < 0:
        theta += np.pi
    return mx * np.cos(theta) + my * np.sin(theta), theta, n


@njit(**_JIT)
def inliers_kernel(p, rho, theta, tol, out):
    c, s = np.cos(theta), np.sin(theta)
    n = 0
    for i in range(p.shape[0]):
        out[i] = abs(p[i, 0] * c + p[i, 1] * s - rho) <= tol
        n += out[i]
    return n


@njit(**_JIT)
def refine_kernel(pts, alive, inl, rho, theta, tol, refine_iterations):
    """Inliers of the line ``(rho, theta)`` among the remaining scan points (``alive``), written
    into ``inl``, with the line refitted to them by least squares ``refine_iterations`` times.
    Returns the refined ``(rho, theta)``."""
    for _it in range(refine_iterations + 1):
        inliers_kernel(pts, rho, theta, tol, inl)
        inl &= alive
        if _it == refine_iterations:
            break
        r2, t2, k = tls_kernel(pts, inl, theta)
        if k < 2 or np.isnan(r2):
            break
        rho, theta = r2, t2
    return rho, theta


@njit(**_JIT)
def peak_line_kernel(
    pts, vp, hist, alive, inl, n_bins, half, dtheta, rho_step, tol, refine_iterations,
    min_points, max_peaks,
):  # fmt: skip
    """The line of the histogram's maximum, else of its sub-maxima: a slope voted by pairs
    across two walls may hold no line while the next peak does. Each peak tried without a
    line of ``min_points`` inliers is suppressed in ``hist`` with its window.

    Returns ``(rho, theta, n_inl)``, the last line tried and its inlier count; ``inl`` holds
    its inliers among the scan points ``pts``.
    """
    m = pts.shape[0]
    rho, theta = 0.0, 0.0
    n_inl = 0
    for _peak in range(max_peaks):
        phi, support = dominant_kernel(hist)
        if support <= 0:
            break
        rho, theta = window_hough_kernel(vp, phi, half, dtheta, rho_step)[:2]
        rho, theta = refine_kernel(pts, alive, inl, rho, theta, tol, refine_iterations)
        n_inl = 0
        for i in range(m):
            n_inl += inl[i]
        if n_inl >= min_points:
            break
        k_peak = int(phi * n_bins / np.pi)  # suppress this peak and its window
        w_bins = max(1, int(np.ceil(half * dtheta * n_bins / np.pi)))
        for b in range(k_peak - w_bins, k_peak + w_bins + 1):
            hist[b % n_bins] = 0
    return rho, theta, n_inl


@njit(**_JIT)
def runs_kernel(pts, inl, theta, gap, base, min_points, min_length, seg, offsets, flat, n_seg):
    """Split the line's inliers ``inl`` at gaps wider than ``gap`` and append each run long
    enough as a segment (:func:`emit_kernel`). Returns the new segment count."""
    m = pts.shape[0]
    run_start = -1
    last = -1
    for i in range(m + 1):
        is_in = i < m and inl[i]
        cut = not is_in
        if is_in and last >= 0:
            dx = pts[i, 0] - pts[last, 0]
            dy = pts[i, 1] - pts[last, 1]
            cut = dx * dx + dy * dy > gap * gap
        if cut and run_start >= 0:
            n_seg = emit_kernel(
                pts,
                inl,
                run_start,
                last,
                theta,
                base,
                min_points,
                min_length,
                seg,
                offsets,
                flat,
                n_seg,
            )
            run_start = -1
        if is_in:
            if run_start < 0:
                run_start = i
            last = i
    return n_seg


@njit(**_JIT)
def cluster_lines_kernel(
    pts, base, u, gap, dense_step, n_bins, min_pair_dist, all_pairs, half, dtheta, rho_step,
    tol, refine_iterations, min_points, min_length, max_rounds, max_peaks, seg, offsets, flat,
    n_seg,
):  # fmt: skip
    """The lines of one cluster ``pts`` (scan points ``base`` on), round after round on the
    points no line took yet, appended to ``seg``, ``offsets`` and ``flat``. Returns the new
    segment count."""
    m = pts.shape[0]
    votes, _src = densify_kernel(pts, dense_step)
    alive = np.ones(m, np.bool_)
    valive = np.ones(votes.shape[0], np.bool_)
    inl = np.zeros(m, np.bool_)
    vinl = np.zeros(votes.shape[0], np.bool_)
    n_alive = m
    for _round in range(max_rounds):
        vp = votes[valive]
        if vp.shape[0] < 2:
            break
        hist = slope_histogram_kernel(vp, u, n_bins, min_pair_dist, all_pairs)
        rho, theta, n_inl = peak_line_kernel(
            pts, vp, hist, alive, inl, n_bins, half, dtheta, rho_step, tol, refine_iterations,
            min_points, max_peaks,
        )  # fmt: skip
        if n_inl < min_points:
            break  # support under the threshold at every peak: this cluster is done
        # Split the line's inliers at gaps; keep long-enough runs as segments.
        n_seg = runs_kernel(
            pts, inl, theta, gap, base, min_points, min_length, seg, offsets, flat, n_seg
        )
        for i in range(m):
            if inl[i]:
                alive[i] = False
                n_alive -= 1
        inliers_kernel(votes, rho, theta, tol, vinl)
        valive &= ~vinl
        if n_alive < min_points:
            break
    return n_seg


@njit(**_JIT)
def extract_kernel(
    p,
    u,
    gap,
    dense_step,
    n_bins,
    min_pair_dist,
    all_pairs,
    half,
    dtheta,
    rho_step,
    tol,
    refine_iterations,
    min_points,
    min_length,
    max_rounds,
    max_peaks,
):
    """The whole of Loop 1 for one scan: the lines of each cluster of at least ``min_points``
    points (:func:`cluster_lines_kernel`).

    Returns per segment ``(rho, theta, rms, sp_x, sp_y, ep_x, ep_y)`` in the paper's form and
    its inlier indices (``flat[offsets[k]:offsets[k + 1]]``).
    """
    n = p.shape[0]
    labels = cluster_kernel(p, gap)
    seg = np.empty((n // 2 + 1, 7))
    offsets = np.zeros(n // 2 + 2, np.int64)
    flat = np.empty(n, np.int64)
    n_seg = 0
    start = 0
    while start < n:
        stop = start
        while stop < n and labels[stop] == labels[start]:
            stop += 1
        if stop - start >= min_points:
            n_seg = cluster_lines_kernel(
                p[start:stop], start, u, gap, dense_step, n_bins, min_pair_dist, all_pairs,
                half, dtheta, rho_step, tol, refine_iterations, min_points, min_length,
                max_rounds, max_peaks, seg, offsets, flat, n_seg,
            )  # fmt: skip
        start = stop
    return seg[:n_seg], offsets[: n_seg + 1], flat[: offsets[n_seg]]


@njit(**_JIT)
def emit_kernel(
    pts, inl, first, last, theta_prev, base, min_points, min_length, seg, offsets, flat, n_seg
):
    """Fit the run inl[first..last] and append it as a segment if it is long enough."""
    mask = np.zeros(pts.shape[0], np.bool_)
    mask[first : last + 1] = inl[first : last + 1]
    rho, theta, k = tls_kernel(pts, mask, theta_prev)
    if k < min_points or np.isnan(rho):
        return n_seg
    c, s = np.cos(theta), np.sin(theta)
    t_lo, t_hi = np.inf, -np.inf
    ss = 0.0
    for i in range(first, last + 1):
        if mask[i]:
            t = -pts[i, 0] * s + pts[i, 1] * c
            t_lo, t_hi = min(t_lo, t), max(t_hi, t)
            r = pts[i, 0] * c + pts[i, 1] * s - rho
            ss += r * r
    if t_hi - t_lo < min_length:
        return n_seg
    t_first = -pts[first, 0] * s + pts[first, 1] * c
    t_last = -pts[last, 0] * s + pts[last, 1] * c
    if t_first > t_last:
        t_lo, t_hi = t_hi, t_lo
    if rho < 0:  # the paper's form: rho >= 0, theta in [0, 2 pi)
        rho, theta, c, s, t_lo, t_hi = -rho, theta + np.pi, -c, -s, -t_lo, -t_hi
    seg[n_seg, 0] = rho
    seg[n_seg, 1] = theta % (2.0 * np.pi)
    seg[n_seg, 2] = np.sqrt(ss / k)
    seg[n_seg, 3] = rho * c - t_lo * s  # sp
    seg[n_seg, 4] = rho * s + t_lo * c
    seg[n_seg, 5] = rho * c - t_hi * s  # ep
    seg[n_seg, 6] = rho * s + t_hi * c
    o = offsets[n_seg]
    for i in range(first, last + 1):
        if mask[i]:
            flat[o] = base + i
            o += 1
    offsets[n_seg + 1] = o
    return n_seg + 1
