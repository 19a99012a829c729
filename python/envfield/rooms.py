"""People in 3D scenes from NumPy: read a scene, find where people can be, and plan a walk or a
sit-down with the planners of envfield's ``room_nav``; every path and pose comes back as NumPy
arrays with its checks.

>>> from envfield import rooms
>>> scene = rooms.Scene.generated(seed=3)          # or rooms.Scene.read("flat.glb")
>>> region = scene.region(seed=3)                    # doctest: +SKIP
>>> plan = region.walk(region.points[0], region.points[-1])   # doctest: +SKIP
>>> plan.poses.shape                                 # doctest: +SKIP
(frames, 22, 3)

Scenes are z up, metres, their floor at z = 0 after reading (``Scene.read`` moves them there;
``up`` and ``units`` override what is guessed or what the format fixes). Points are torso
locations in metres; poses are SMPL's 22 joints.
"""

import os

from . import _envfield

__all__ = ["Scene", "Region", "Plan", "DEFAULT_VAE", "JOINTS"]

#: The VAE of torso locations the package ships (envfield's models/vae_gated.safetensors).
DEFAULT_VAE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "models",
                           "vae_gated.safetensors")

#: SMPL's 22 body joints, in the order of a pose's rows.
JOINTS = tuple(_envfield.JOINTS)

Region = _envfield.Region
Plan = _envfield.Plan


class Scene:
    """A scene: ``Scene.read(path, up=None, units=None)`` (OBJ, PLY, glTF, GLB) or
    ``Scene.generated(seed)`` (a room the generator furnishes)."""

    def __init__(self, native):
        self._native = native

    @classmethod
    def read(cls, path, up=None, units=None):
        """Reads ``path``. ``up``: "z" or "y"; ``units``: "m", "cm", "mm" or metres
        per unit, as a string or a number. Raises OSError naming the file where it cannot be
        read."""
        if units is not None and not isinstance(units, str):
            units = repr(float(units))
        return cls(_envfield.Scene.read(os.fspath(path), up, units))

    @classmethod
    def generated(cls, seed=0):
        """A room the generator furnishes from ``seed`` (beds, sofas, chairs, tables)."""
        return cls(_envfield.Scene.generated(int(seed)))

    @property
    def bounds(self):
        """``((xmin, ymin, zmin), (xmax, ymax, zmax))`` in metres."""
        return self._native.bounds

    @property
    def warnings(self):
        """What reading the file warned about (an unusual frame, stray pieces)."""
        return self._native.warnings

    def region(self, samples=None, seed=0, vae=None):
        """Where people can be: a ``Region`` of voxels (``points``, ``voxel``, ``sit_downs``,
        ``lie_downs``) whose ``walk``, ``sit_down`` and ``lie_down`` plan motions. ``samples`` torsos are drawn (by default
        240 per square metre of the scene's box) by the VAE in ``vae`` (the shipped one by
        default). Takes seconds to a minute; the GIL is released meanwhile."""
        vae = DEFAULT_VAE if vae is None else os.fspath(vae)
        return self._native.region(vae, samples, int(seed))
