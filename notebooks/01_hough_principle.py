# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     notebook_metadata_filter: -jupytext.text_representation.jupytext_version
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 01 · The Hough transform principle (paper Fig. 1)
#
# The paper extracts straight walls from laser points with the **Hough transform**. A line is
# written in polar (Hessian) form, paper eq. (1):
#
# $$\rho = x\cos\theta + y\sin\theta$$
#
# with $\rho$ the distance from the origin O to the line and $\theta$ the angle of the
# perpendicular OP. Every point $(x, y)$ maps to a sinusoid in $(\theta, \rho)$ space; points on
# one line give sinusoids that cross in one common point — the line's $(\rho, \theta)$.
#
# This notebook reproduces **Fig. 1**, then builds the classical accumulator for a real
# simulated scan and counts what it costs — the cost the *fast* Hough transform (notebook 03)
# avoids.

# %% [markdown]
# **Paper.** Wu Zu Yu, Huang Xin Han, Li Xin De, Wang Min and Yan Huai Cheng, "A Simultaneous Localization and Mapping Method Based on Fast-Hough Transform", *Information Technology Journal* 7(1):190–194, 2008, doi:[10.3923/itj.2008.190.194](https://doi.org/10.3923/itj.2008.190.194). "Paper Fig. N" and "paper eq. (N)" below refer to it.
#
# **You will learn to**
#
# - write a line in Hessian normal form, $\rho = x\cos\theta + y\sin\theta$, compute the $(\rho, \theta)$ of the line through two points, and say why every point becomes a sinusoid in $(\theta, \rho)$;
# - read a Hough accumulator: find its strongest cell and the wall it stands for, and tell parallel walls by their peaks in one column;
# - count what the classical accumulator costs (its cells, points × angle steps votes, then a 2D peak search) — the cost the fast Hough transform avoids.
#
# **Prerequisites.** Python and NumPy basics, polar coordinates and the sine and cosine. No robotics needed.
#
# **Duration.** about 20 minutes to work through, exercises included; Run All takes about 15 s on a busy 2-core machine, 5 s of it in the cells (measured with `jupyter nbconvert --execute`).

# %%
# %matplotlib inline
import matplotlib.pyplot as plt
import numpy as np

import fhslam
from fhslam import plotting
from fhslam.figures import figure_scan, paper_log

SEED = 0  # every random number below comes from this seed
np.set_printoptions(precision=3, suppress=True)
print(f"fhslam {fhslam.__version__}")

# %% [markdown]
# ## Fig. 1: four points, four sinusoids, one crossing

# %%
from fhslam.figures import fig01_hough_principle

fig01_hough_principle()
plt.show()


# %% [markdown]
# ## Exercise 1.1 (implement) — the line through two points
#
# Two points fix a line, and eq. (1) writes that line as one point $(\rho, \theta)$ of Hough
# space: the cell where the two points' sinusoids cross. Write `my_line_through(p, q)` that
# returns `(rho, theta)` for the line through the distinct points `p` and `q` (NumPy arrays
# `[x, y]`, metres) in the paper's form: $\rho \ge 0$ in metres, the distance OP, and $\theta$ in
# $[0, 2\pi)$ in radians, the angle of the normal OP — not of the line itself. The normal is
# perpendicular to `q - p` (`np.arctan2(dy, dx)` gives the angle of a vector), and when $\rho$
# comes out negative the same line is $(-\rho, \theta + \pi)$.
#
# The check compares your line with `fhslam.geometry.line_through` in ten cases: horizontal and
# vertical lines on either side of the origin, the two points in either order, lines with normals
# at 45°, 233° and 330°, Fig. 1's line, and a line through the origin (where $\rho = 0$ and
# either normal is right).
#
# Fill in the cell below, then run it and the check under it. A solution is hidden under the check (click the collapsed cell to show it).

# %% tags=["exercise"]
def my_line_through(p, q):
    # your code here: return (rho, theta), rho >= 0 in metres, theta in [0, 2 pi) radians
    raise NotImplementedError


# %% tags=["check", "nbval-check-output"]
from fhslam.exercises.nb01 import check_line_through

print(check_line_through(my_line_through))


# %% jupyter={"outputs_hidden": true, "source_hidden": true} tags=["solution", "nbval-check-output"]
# Solution
# The direction q - p turned by +90° is a normal; rho = p · n. A negative rho means that
# normal points away from the line: the same line is (-rho, theta + pi).
def solution_line_through(p, q):
    d = q - p
    theta = np.arctan2(d[1], d[0]) + np.pi / 2
    rho = p[0] * np.cos(theta) + p[1] * np.sin(theta)
    if rho < 0:
        rho, theta = -rho, theta + np.pi
    return rho, theta % (2 * np.pi)


# %% [markdown]
# ## The classical accumulator on a laser scan
#
# We simulate the built-in `paper` world (an 18.7 × 14.0 m office, see notebook 02), take one
# scan, and let every point vote for every $\theta$ in 0–180° at `THETA_STEP_DEG` = 1° and every
# $\rho$ from −8 to 8 m at `RHO_STEP` = 2 cm: the "classical Hough transform" the paper argues
# against. Each point's votes trace its sinusoid; each wall becomes a bright peak where its
# points' sinusoids cross. Most cells get no vote at all, and a linear colour scale shows little
# but the strongest peak, so the colours follow the votes to the power 0.4; circles mark the five
# strongest peaks (a cell is a peak when no cell within ±4° and ±0.24 m has more votes).

# %%
from matplotlib.colors import PowerNorm
from scipy.ndimage import maximum_filter

from fhslam.baselines import hough_accumulator

RHO_STEP, THETA_STEP_DEG, RHO_MAX = 0.02, 1.0, 8.0  # the accumulator's grid: m, deg, m

log = paper_log(SEED)
k = figure_scan(log)
points, beams = log.scan(k).points()  # laser frame; beams without a return dropped
acc, thetas, rhos = hough_accumulator(
    points, rho_step=RHO_STEP, theta_step=np.radians(THETA_STEP_DEG), rho_max=RHO_MAX
)

fig, ax = plt.subplots(figsize=(10, 4))
half = THETA_STEP_DEG / 2, RHO_STEP / 2  # the cells' centres sit on thetas and rhos
im = ax.imshow(
    acc.T,
    aspect="auto",
    origin="lower",
    cmap="magma",
    norm=PowerNorm(gamma=0.4),
    extent=[-half[0], 180 - half[0], rhos[0] - half[1], rhos[-1] + half[1]],
)
fig.colorbar(im, ax=ax, label="votes per cell (power scale, γ = 0.4)")
# a peak: a cell with the most votes within ±4° and ±0.24 m; circle the five strongest
ti, ri = np.nonzero(acc == maximum_filter(acc, size=(9, 25), mode="constant"))
top = np.argsort(-acc[ti, ri], kind="stable")[:5]
ax.scatter(
    np.degrees(thetas[ti[top]]),
    rhos[ri[top]],
    s=150,
    facecolors="none",
    edgecolors="cyan",
    label="the five strongest peaks",
)
ax.legend(loc="lower left")
ax.set(xlabel=r"$\theta$ [deg]", ylabel=r"$\rho$ [m]", title=f"Classical accumulator of scan {k}")
plt.show()

# %% [markdown]
# ## Exercise 1.2 (interpret) — several peaks in one column
#
# In the accumulator above, three of the five circled peaks stand one above the other in the
# column $\theta = 90°$ (the top one, near $\rho = 6$ m, is the faintest). Why do several peaks
# share one $\theta$?
#
# - **a** — they are one wall: every point votes once in every column, so one wall leaves
#   several peaks in each column;
# - **b** — they are parallel walls: parallel lines share the normal angle $\theta$ and differ
#   only in $\rho$, their distance from the laser;
# - **c** — the column $\theta = 90°$ receives more votes than the others, because
#   $\sin\theta = 1$ there;
# - **d** — they are corners, where the points of two walls add up.
#
# Fill in the cell below, then run it and the check under it. A solution is hidden under the check (click the collapsed cell to show it).

# %% tags=["exercise"]
my_reading = ...  # "a", "b", "c" or "d"

# %% tags=["check", "nbval-check-output"]
from fhslam.exercises.nb01 import check_accumulator_reading

print(check_accumulator_reading(my_reading, acc, thetas, rhos))

# %% jupyter={"outputs_hidden": true, "source_hidden": true} tags=["solution", "nbval-check-output"]
# Solution
# Parallel walls have the same normal direction: one theta, one peak per distance rho.
solution_reading = "b"

# %% [markdown]
# The strongest cell and the wall it stands for (the true walls come from the simulator). The
# circles at the left and right edges, near $\theta$ = 0° and 179°, are one more wall, about 3.7
# m ahead: $(\rho, \theta)$ and $(-\rho, \theta + 180°)$ are the same line, so a wall whose
# normal is near 0° peaks at both edges.

# %%
# NBVAL_CHECK_OUTPUT
from fhslam.geometry import normalize_line
from fhslam.metrics import line_difference
from fhslam.sim import true_lines

i, j = np.unravel_index(acc.argmax(), acc.shape)
truth, _ = true_lines(log.hits[k], log.world.walls, log.truth[k])
best = min(truth, key=lambda t: line_difference(rhos[j], thetas[i], t.rho, t.theta))
rho, theta = normalize_line(rhos[j], thetas[i])  # the paper's form: rho >= 0, theta in [0, 360)
print(f"peak: {acc[i, j]} votes at rho = {rho:.2f} m, theta = {np.degrees(theta):.0f} deg")
print(f"true wall:      rho = {best.rho:.2f} m, theta = {np.degrees(best.theta):.1f} deg")

# %% [markdown]
# ## Exercise 1.3 (predict) — how many cells?
#
# The accumulator above has one column per $\theta$, from 0° in steps of `THETA_STEP_DEG` = 1°
# up to, not including, 180°, and one row per $\rho$, from `-RHO_MAX` to `RHO_MAX` (8 m) in
# steps of `RHO_STEP` = 2 cm, both ends included. **Before running the next section**, work out
# how many cells it has: the memory the classical transform fills and then searches for peaks.
# (Why does $\theta$ stop at 180° here, when the paper's $\theta$ runs to 360°? Because this
# $\rho$ is signed: $(\rho, \theta + 180°)$ is the line $(-\rho, \theta)$.)
#
# Fill in the cell below, then run it and the check under it. A solution is hidden under the check (click the collapsed cell to show it).

# %% tags=["exercise"]
my_cells = ...  # your prediction: the number of cells

# %% tags=["check", "nbval-check-output"]
from fhslam.exercises.nb01 import check_accumulator_cells

print(check_accumulator_cells(my_cells, RHO_STEP, THETA_STEP_DEG, RHO_MAX, len(points)))

# %% jupyter={"outputs_hidden": true, "source_hidden": true} tags=["solution", "nbval-check-output"]
# Solution
# 180 theta columns (0°, 1°, ..., 179°) x 801 rho rows (-8.00, -7.98, ..., 8.00 m: 2 x 400 + 1).
solution_cells = round(180 / THETA_STEP_DEG) * (2 * round(RHO_MAX / RHO_STEP) + 1)

# %% [markdown]
# ## What the classical transform costs
#
# Every point votes in every angle column, so the work grows with the number of points times
# the number of angles, and the memory with the whole $(\rho, \theta)$ plane. The fast Hough
# transform of the paper votes only in a few degrees around the dominant slope of each cluster.

# %%
# NBVAL_CHECK_OUTPUT
from fhslam.extraction import ExtractionParams

p = ExtractionParams()
window = 2 * round(p.window_deg / p.theta_step_deg) + 1
print(f"{len(points)} points")
print(
    f"classical: {acc.shape[0]} angles x {acc.shape[1]} rho cells = {acc.size} cells, "
    f"{len(points) * acc.shape[0]} votes"
)
print(f"cells with at least one vote: {(acc > 0).mean():.0%}")
print(
    f"fast Hough window: {window} angles around the dominant slope "
    f"({2 * p.window_deg:.0f} deg instead of 180 deg), {len(points) * window} votes per line"
)

# %% [markdown]
# ## Try it
#
# - **Your line on the scan's points.** Once `my_line_through` passes, run
#   `rho, theta = my_line_through(points[0], points[20])` and `print(rho, np.degrees(theta))`:
#   the first points of the scan lie on the wall of the strongest peak (ρ = 2.20 m, θ = 270°).
#   Then try `points[0]` and `points[10]`. Two noisy points close together tilt the line by
#   degrees; the accumulator's peak pools the votes of all the wall's points.
# - **Another scan.** In the accumulator cell, replace `k = figure_scan(log)` by `k = 30` (the
#   robot has turned since) and run that cell and all below it. The walls that peaked in the
#   column θ = 90° now peak together in another column: θ is measured in the laser's frame, so
#   when the robot turns by α every peak moves by −α.

# %% [markdown]
# ## Summary
#
# - A line is one point $(\rho, \theta)$ of parameter space; a laser point is a sinusoid there, and the points of one wall give sinusoids through one common cell.
# - The classical transform votes every point into every angle column of the accumulator and then searches the whole accumulator for peaks: its cost grows with the number of points times the angular resolution.
# - Notebook 03 votes only where the points' own slopes say a line is — the paper's *fast* Hough transform.
