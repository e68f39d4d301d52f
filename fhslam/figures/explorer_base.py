"""What every explorer is made of: :class:`Explorer`, a figure drawn from named controls and
shown as an image updated in place, and :func:`slider`, the labelled slider that acts when
released.
"""

from __future__ import annotations

import io
import time
from collections.abc import Callable
from typing import Any

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

__all__ = ["FIGSIZE", "Explorer", "slider"]

FIGSIZE = (7.5, 4.5)


def slider(value: float, low: float, high: float, step: float, description: str, **kw: Any):
    """A labelled slider that acts when released, its whole name shown."""
    import ipywidgets as widgets

    cls = (
        widgets.IntSlider
        if all(isinstance(v, int) for v in (value, low, high, step))
        else (widgets.FloatSlider)
    )
    return cls(
        value=value,
        min=low,
        max=high,
        step=step,
        description=description,
        continuous_update=False,
        style={"description_width": "initial"},
        layout={"width": "460px"},
        **kw,
    )


class Explorer:
    """A figure drawn by ``draw(**values)`` from named controls (ipywidgets).

    Parameters
    ----------
    draw : callable
        ``draw(**{name: value}) -> Figure``; the figure is closed after it is shown.
    controls : dict
        Control name (``draw``'s keyword) -> ipywidgets value widget.
    title : str
        What the controls do, shown above them.
    """

    def __init__(self, draw: Callable[..., Figure], controls: dict[str, Any], title: str):
        self.draw, self.controls, self.title = draw, controls, title
        self.seconds = float("nan")  # the last redraw's duration
        self._handle = None
        for c in controls.values():
            c.observe(self._changed, names="value")

    def values(self) -> dict[str, Any]:
        return {name: c.value for name, c in self.controls.items()}

    def figure(self) -> Figure:
        return self.draw(**self.values())

    def png(self) -> bytes:
        t0 = time.perf_counter()
        fig = self.figure()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=80)
        plt.close(fig)
        self.seconds = time.perf_counter() - t0
        return buf.getvalue()

    def set(self, **values: Any) -> None:
        """Move controls from code, as a slider would (the figure follows)."""
        for name, value in values.items():
            if name not in self.controls:
                raise KeyError(f"no control {name!r}; controls: {', '.join(self.controls)}")
            self.controls[name].value = value

    def _changed(self, change: Any) -> None:
        if self._handle is not None:
            from IPython.display import Image

            self._handle.update(Image(data=self.png(), format="png"))

    def _ipython_display_(self) -> None:
        import ipywidgets as widgets
        from IPython.display import Image, display

        self._handle = display(Image(data=self.png(), format="png"), display_id=True)
        box = widgets.VBox(
            [widgets.HTML(f"<b>{self.title}</b>"), *self.controls.values()],
            layout={"border": "1px solid #ddd", "padding": "4px 8px"},
        )
        bundle = box._repr_mimebundle_()
        bundle["text/plain"] = (
            f"[{self.title}: sliders {', '.join(self.controls)} — run this cell to use them]"
        )
        display(bundle, raw=True)
