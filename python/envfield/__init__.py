"""envfield: environment fields from Python.

- ``envfield.fmm``: fast marching with scikit-fmm's API (``distance``, ``travel_time``,
  ``extension_velocities``), and ``path`` back down a field.
- ``envfield.rooms``: read a scene, build where people can be, plan a walk or a sit-down,
  and get the path and every pose as NumPy arrays.
"""

from . import fmm, rooms
from ._envfield import __version__

__all__ = ["fmm", "rooms", "__version__"]
