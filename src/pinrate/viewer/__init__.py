"""The browser view: a robot, its frames and its servo path in Meshcat (the only package
that imports meshcat)."""

from ..errors import ViewerError
from .markers import path_colours, triad
from .scene import ROOT, Viewer
from .server import MeshcatServer

__all__ = ["ROOT", "MeshcatServer", "Viewer", "ViewerError", "path_colours", "triad"]
