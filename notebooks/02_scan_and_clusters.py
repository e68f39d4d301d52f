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
# # 02 · The scan and its clusters (paper Figs. 2, 3, 4)
#
# Loop 1 of the paper starts from the raw scan: 181 beams over 0–180° at 1° from a SICK
# LMS200-like laser on a Pioneer II. This notebook shows
#
# * **Fig. 2** — the environment and one scan taken in it;
# * **Fig. 3** — "extend laser scan points": points added between neighbours of a cluster;
# * **Fig. 4** — the scan clustered: a new cluster starts wherever two neighbouring points are
#   farther apart than a threshold (`cluster_gap`).

# %% [markdown]
# **Paper.** Wu Zu Yu, Huang Xin Han, Li Xin De, Wang Min and Yan Huai Cheng, "A Simultaneous Localization and Mapping Method Based on Fast-Hough Transform", *Information Technology Journal* 7(1):190–194, 2008, doi:[10.3923/itj.2008.190.194](https://doi.org/10.3923/itj.2008.190.194). "Paper Fig. N" and "paper eq. (N)" below refer to it.
#
# **You will learn to**
#
# - read a 2D laser scan: beams, bearings, ranges, and the beams without a return;
# - turn a scan into points and follow the paper's "extend laser scan points" step (Fig. 3);
# - cluster a scan by the distance between neighbouring points (Fig. 4) and explain how the threshold shapes the clusters;
# - implement the clustering rule yourself, vectorised with NumPy.
#
# **Prerequisites.** Notebook 01; NumPy arrays, boolean masks and `np.cumsum`.
#
# **Duration.** about 30 minutes to work through, exercises included; Run All takes about 6 s on a 2-core machine (measured with `jupyter nbconvert --execute`).

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

# %%
from fhslam.extraction import ExtractionParams, cluster_scan, densify
from fhslam.figures import fig02_environment, fig03_extended_points, fig04_clusters

log = paper_log(SEED)
k = figure_scan(log)  # the first scan whose points fall into five clusters, as in Fig. 4
print(
    f"{log.name}: {len(log)} scans, {len(log.angles)} beams each, max range {log.max_range} m; scan {k}"
)

# %% [markdown]
# ## Fig. 2 — the environment and scan `k`
# Invalid beams (no return within 8 m) are dropped, never turned into points.

# %%
fig02_environment(log, k)
plt.show()

# %% [markdown]
# ## Fig. 3 — extending the points
# The paper adds points between neighbours "to make the line features more prominent". Points are added only *inside* a cluster, never across a gap; they vote in the Hough step but lines are fitted to real scan points only.

# %%
fig03_extended_points(log, k)
plt.show()

# %% [markdown]
# ## Fig. 4 — clustering by neighbour distance

# %%
fig04_clusters(log, k)
plt.show()

# %%
# NBVAL_CHECK_OUTPUT
params = ExtractionParams()
points, beams = log.scan(k).points()  # fhslam.scan.scan_to_points: invalid beams dropped
labels = cluster_scan(points, params.cluster_gap)
sizes = np.bincount(labels)
dense, dense_labels, source = densify(points, labels, params.densify_step)
print(f"{len(points)} valid points in {len(sizes)} clusters of sizes {sizes.tolist()}")
print(
    f"clusters with >= {params.min_points} points (can hold a line): {int((sizes >= params.min_points).sum())}"
)
print(f"densified to {len(dense)} voting points ({int((source < 0).sum())} added)")

# %% [markdown]
# ## Exercise 2.1 (predict) — How far apart are neighbouring points?
#
# The laser's beams are 1° apart. A wall stands 4 m in front of the robot, square to the
# beam straight ahead. **Before running anything**, work out how far apart (in metres) the two
# points are that the beams at +0.5° and −0.5° from straight ahead make on that wall. Is that
# more or less than the default `cluster_gap` of 0.3 m, and than 5 cm?
#
# Fill in the cell below, then run it and the check under it. A solution is hidden under the check (click the collapsed cell to show it).

# %% tags=["exercise"]
my_spacing = ...  # your prediction, in metres

# %% tags=["check", "nbval-check-output"]
from fhslam.exercises.nb02 import check_point_spacing

print(check_point_spacing(my_spacing))

# %% jupyter={"outputs_hidden": true, "source_hidden": true} tags=["solution", "nbval-check-output"]
# Solution
# Each beam is 0.5° from the perpendicular: the points lie 4 m × tan(0.5°) either side.
solution_spacing = 2 * 4.0 * np.tan(np.radians(0.5))  # about 4 m × 1° in radians = 7 cm

# %% [markdown]
# ## How the threshold shapes the clusters
#
# Too small a gap cuts a wall seen at a grazing angle into pieces; too large a gap joins walls
# across a doorway. The count of clusters for a few thresholds:

# %%
# NBVAL_CHECK_OUTPUT
for gap in (0.05, 0.1, 0.2, 0.3, 0.5, 1.0, 2.0):
    n = np.bincount(cluster_scan(points, gap))
    print(
        f"gap {gap:4.2f} m: {len(n):3d} clusters, {int((n >= params.min_points).sum()):2d} with >= {params.min_points} points"
    )

# %% [markdown]
# ## Exercise 2.2 (interpret) — why a 5 cm gap makes 156 clusters
#
# The table above gives 156 clusters at a gap of 0.05 m, only one of them big enough to hold a
# line, and 5 clusters from 0.2 m to 0.5 m. Which explanation is right?
#
# - **a** — the laser is noisy, so neighbouring points jitter more than 5 cm apart;
# - **b** — neighbouring beams spread apart with range, so on the walls farther away the points
#   are more than 5 cm apart and every point becomes its own cluster;
# - **c** — a smaller gap adds more densified points, which form clusters of their own.
#
# Exercise 2.1 helps.
#
# Fill in the cell below, then run it and the check under it. A solution is hidden under the check (click the collapsed cell to show it).

# %% tags=["exercise"]
my_answer = ...  # "a", "b" or "c"

# %% tags=["check", "nbval-check-output"]
from fhslam.exercises.nb02 import check_small_gap_reading

print(check_small_gap_reading(my_answer))

# %% jupyter={"outputs_hidden": true, "source_hidden": true} tags=["solution", "nbval-check-output"]
# Solution
# 1° between beams is 1.7 cm per metre of range: beyond about 3 m the points are > 5 cm apart.
solution_answer = "b"

# %% [markdown]
# ## Explore the gap
#
# The clusters of scan `k` under the gap you choose, and of any other scan of the run. Move
# **cluster gap** down to 0.05 m and watch the far walls fall apart point by point (Exercise
# 2.2), then up past 1 m and watch walls join across the doorways. On the right, the gap from
# each point to the next along the scan, with your gap drawn across it: every gap above the line
# (a black cross) starts a new cluster. No gap of scan `k` lies between 0.15 m and 0.84 m: there
# the line moves and the clusters stay. The title counts the clusters and those with enough
# points to hold a line. The figure above the sliders is what the saved notebook shows; the
# sliders need a running kernel.

# %% tags=["nbval-ignore-output"]
from fhslam.figures.explorers import clustering_explorer

clustering_explorer(log, k)


# %% [markdown]
# ## Exercise 2.3 (implement) — the clustering rule
#
# Write `my_cluster(points, gap)` that returns an integer label for each point (shape
# `(N,)`), in scan order, such that a new cluster starts at point `i+1` exactly when
# `|p[i+1] - p[i]| > gap` (paper, *Feature extraction process*). Use NumPy, no Python loop:
# `np.diff`, `np.hypot` and `np.cumsum` are all you need. The check compares your clusters with
# `fhslam.extraction.cluster_scan` on six small cases, one with neighbours exactly `gap` apart.
#
# Fill in the cell below, then run it and the check under it. A solution is hidden under the check (click the collapsed cell to show it).

# %% tags=["exercise"]
def my_cluster(points, gap):
    # your code here: return one integer label per point
    raise NotImplementedError


# %% tags=["check", "nbval-check-output"]
from fhslam.exercises.nb02 import check_clustering

print(check_clustering(my_cluster))


# %% jupyter={"outputs_hidden": true, "source_hidden": true} tags=["solution", "nbval-check-output"]
# Solution
def solution_cluster(points, gap):
    step = np.hypot(*np.diff(points, axis=0).T)  # distance to the previous point
    return np.concatenate([[0], np.cumsum(step > gap)])  # +1 at every break

# %% [markdown]
# ## Summary
#
# - A scan of the paper's laser is 181 ranges at 1° steps over 180°; beams without a return are dropped, never turned into points.
# - Points are added between neighbours only inside a cluster, and they only vote: lines are fitted to real points.
# - A new cluster starts where two neighbouring points lie farther apart than `cluster_gap`: too small a gap cuts a wall seen at a grazing angle into pieces, too large a gap joins walls across a doorway.
# - Each cluster is then searched for lines on its own (notebook 03).
