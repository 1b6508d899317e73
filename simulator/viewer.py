"""The self-contained HTML viewer of a saved simulation result: :func:`write_viewer` turns a
directory written by :meth:`~simulator.SimulationResult.save` into one HTML file that opens
offline (the deformed sheet coloured by temperature, a slider over the records, the fold angle,
temperature and power of a picked crease)."""

from .io.viewer import load_viewer_data, viewer_html, write_viewer

__all__ = ["write_viewer", "viewer_html", "load_viewer_data"]
