"""fhslam: the fast-Hough-transform line SLAM of the paper, as a teaching and research workbook."""

from fhslam.lines import Line, fit_line, line_from_points

__all__ = ["Line", "fit_line", "line_from_points"]
__version__ = "0.1.0"
