"""Interactive explorers for the notebooks: sliders for a threshold or a parameter, and one
figure that follows them.

An explorer shows its figure as an ordinary image output, updated in place when a slider
moves, so that the notebook as saved shows the last figure — useful before the kernel runs,
in a static viewer, on GitHub — and the sliders (ipywidgets) under it with a plain-text line
saying to run the cell, instead of ``interactive(children=(IntSlider(...``. Sliders act when
released (``continuous_update=False``); every redraw takes well under a second on a 2-core
machine (each explorer's work is one scan, one pair of lines or one short run).

Every control changes what its figure draws in one step from its default, up (down from the
top), not only a number in a title: a threshold is drawn where it acts (a line across the
quantity it is compared with, a band, a window, a box), the iterations by what each one does
(the tests move every control and compare the figures with their texts blanked; the browser
test moves each explorer's first). Each
``*_explorer`` function returns the :class:`Explorer`; ``explorer.set(name=value)`` moves
a control from code (what the tests do) and ``explorer.figure()`` draws the current state.

The explorers live in :mod:`fhslam.figures.scan_explorers` (notebooks 02-03, with the panels
of :mod:`fhslam.figures.scan_panels`), :mod:`fhslam.figures.matching_explorers` (04-05) and
:mod:`fhslam.figures.slam_explorers` (06), on :mod:`fhslam.figures.explorer_base`; this
module gathers them.
"""

from fhslam.figures.explorer_base import FIGSIZE as FIGSIZE
from fhslam.figures.explorer_base import Explorer, slider
from fhslam.figures.matching_explorers import calibration_explorer, similarity_explorer
from fhslam.figures.scan_explorers import clustering_explorer, extraction_explorer
from fhslam.figures.slam_explorers import slam_noise_explorer

__all__ = [
    "Explorer",
    "calibration_explorer",
    "clustering_explorer",
    "extraction_explorer",
    "similarity_explorer",
    "slam_noise_explorer",
    "slider",
]
