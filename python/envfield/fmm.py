"""Fast marching with scikit-fmm's API, argument for argument, on envfield's marcher.

``distance``, ``travel_time`` and ``extension_velocities`` take and return what
``skfmm``'s functions of the same names do (``dx`` as a number or one per axis, ``order`` 1
or 2, ``narrow``, ``periodic`` as a bool or one per axis, masked arrays in, masked arrays out
where cells are not reached), and pass scikit-fmm's own test suite (``python/tests``). The
march runs with the GIL released, so several Python threads solve at once.

What scikit-fmm lacks: ``path``, the way from any point back down a field to its zero contour.

>>> import numpy as np
>>> from envfield import fmm
>>> phi = np.ones((5, 5)); phi[0, 0] = -1
>>> t = fmm.travel_time(phi, np.ones_like(phi))
>>> bool(t[4, 4] > t[2, 2] > t[0, 1])
True
>>> fmm.path(t, (4, 4))[-1].round().tolist()
[0.0, 0.0]
"""

import operator

import numpy as np

from . import _envfield

__all__ = ["distance", "travel_time", "extension_velocities", "path", "heap"]

_MAX_DIMENSIONS = 12


def _phi_and_mask(phi):
    if isinstance(phi, np.ma.MaskedArray):
        mask = np.ma.getmaskarray(phi)
        data = phi.data
    else:
        data = phi if isinstance(phi, np.ndarray) else np.array(phi)
        mask = None
    return data, mask


def _doubles(a, message):
    """``a`` as a C-ordered float64 array of 1 to 12 axes (no copy when it is one already),
    or ValueError(message) where NumPy would not cast it safely."""
    a = np.asarray(a)
    if not (1 <= a.ndim <= _MAX_DIMENSIONS) or not np.can_cast(a.dtype, np.float64, "safe"):
        raise ValueError(message)
    return np.ascontiguousarray(a, dtype=np.float64)


def _spacing(dx, ndim):
    if isinstance(dx, (int, float, np.integer, np.floating)) and not isinstance(dx, bool):
        dx = [dx] * ndim
    try:
        dx = np.asarray(dx, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("dx must be a 1D array of doubles") from None
    if dx.ndim != 1:
        raise ValueError("dx must be a 1D array of doubles")
    return dx


def _periodic(periodic, ndim):
    if isinstance(periodic, (bool, np.bool_)):
        return [bool(periodic)] * ndim
    if hasattr(periodic, "__len__") and len(periodic) == ndim:
        return [bool(v) for v in periodic]
    raise ValueError(
        'parameter "periodic" must be of type bool or sequence of type bool of length phi.ndim.'
    )


def _march(kind, phi, speed, dx, self_test, order, narrow, periodic, ext_mask=None):
    data, mask = _phi_and_mask(phi)
    periodic = _periodic(periodic, np.ndim(data))
    if narrow < 0:
        raise ValueError('parameter "narrow" must be greater than or equal to zero.')
    self_test = int(self_test)
    if self_test not in (0, 1):
        raise ValueError("self_test must be 0 or 1")
    order = operator.index(order)
    if order not in (1, 2):
        raise ValueError("order must be 1 or 2")
    data = _doubles(data, "phi must be a 1 to 12-D array of doubles")
    dx = _spacing(dx, data.ndim)
    if speed is not None:
        speed = _doubles(speed, "speed must be a 1D to 12-D array of doubles")
        if speed.shape != data.shape:
            raise ValueError("phi and speed must have the same shape")
    if len(dx) != data.ndim:
        raise ValueError("dx must be of length len(phi.shape)")
    if (dx <= 0).any():
        raise ValueError("dx must be greater than zero")
    if mask is not None:
        mask = np.ascontiguousarray(mask, dtype=bool)
    if ext_mask is not None:
        try:
            ext_mask = np.ascontiguousarray(np.asarray(ext_mask) != 0, dtype=bool)
        except (TypeError, ValueError):
            raise ValueError("ext_mask must be a 1D, 12-D array of integers") from None
        if ext_mask.shape != data.shape:
            raise ValueError("phi and ext_mask must have the same shape")
    values, reached, velocity = _envfield.march(
        kind, data, list(dx), order, float(narrow), periodic, bool(self_test),
        mask=mask, speed=speed, ext_mask=ext_mask,
    )
    return values, reached, velocity


def _masked(values, reached):
    """As scikit-fmm: a masked array (data 0 where masked) when some cell was not reached."""
    if reached.all():
        return values
    missing = ~reached
    values[missing] = 0
    return np.ma.MaskedArray(values, missing)


def distance(phi, dx=1.0, self_test=False, order=2, narrow=0.0, periodic=False):
    """Return the signed distance from the zero contour of the array phi.

    Parameters
    ----------
    phi : array-like
        the zero contour of this array is the boundary location for the distance
        calculation. Phi can be of 1 to 12 dimensions and can be a masked array (masked
        cells are never entered).
    dx : float or an array-like of len phi.ndim, optional
        the cell length in each dimension.
    self_test : bool, optional
        if True the priority queue's invariant is checked after every operation (slow).
    order : int, optional
        order of the upwind stencil, 1 or 2 (default 2).
    narrow : float, optional
        narrow band half-width: the march stops at the first value beyond it and the cells
        left are masked. 0 (default) means no band.
    periodic : bool or an array-like of len phi.ndim, optional
        whether (and along which axes) the grid wraps around.

    Returns
    -------
    d : an array the same shape as phi, signed as phi; a masked array where cells were not
        reached (masked, cut off by the mask, or beyond the narrow band).
    """
    values, reached, _ = _march("distance", phi, None, dx, self_test, order, narrow, periodic)
    return _masked(values, reached)


def travel_time(phi, speed, dx=1.0, self_test=False, order=2, narrow=0.0, periodic=False):
    """Return the travel time from the zero contour of the array phi given the scalar
    velocity field speed.

    Parameters are those of :func:`distance`, and

    speed : array-like, the same shape as phi
        the speed of the front at each point; points slower than machine epsilon are never
        entered (and come back masked).

    Returns
    -------
    t : an array the same shape as phi (non-negative); masked where not reached.
    """
    if speed is None:
        raise ValueError("speed must be a 1D to 12-D array of doubles")
    values, reached, _ = _march("travel_time", phi, speed, dx, self_test, order, narrow, periodic)
    return _masked(values, reached)


def extension_velocities(phi, speed, dx=1.0, self_test=False, order=2, ext_mask=None,
                         narrow=0.0, periodic=False):
    """Extend the velocities defined at the zero contour of phi, in the normal direction, to
    the rest of the domain, such that grad f_ext . grad d = 0 where d is the signed
    distance.

    Parameters are those of :func:`travel_time`, and

    ext_mask : array-like, the same shape as phi, optional
        cells whose own speed is left out of the value on the contour (their neighbour's
        across the contour is used).

    Returns
    -------
    (d, f_ext) : the signed distance and the extension velocities, each masked where not
        reached.
    """
    if speed is None:
        raise ValueError("speed must be a 1D to 12-D array of doubles")
    values, reached, velocity = _march(
        "extension_velocities", phi, speed, dx, self_test, order, narrow, periodic, ext_mask
    )
    return _masked(values, reached), _masked(velocity, reached.copy())


def path(field, start, dx=1.0):
    """The shortest path from ``start`` back to the zero contour a field was marched from.

    ``field`` is what :func:`distance` or :func:`travel_time` returned (masked cells are
    walls; a signed distance is followed by its magnitude); ``start`` is a point in index
    coordinates (fractions allowed). Each step follows the field's gradient, half a cell
    long, or moves to the lowest neighbouring cell where the gradient cannot be read (beside
    a mask); the field falls at every step, so the path always ends: within half a step of
    the contour, or at a cell with no lower neighbour.

    Returns an array of shape ``(steps, phi.ndim)`` in index coordinates, ``start`` first.
    """
    if isinstance(field, np.ma.MaskedArray):
        reached = ~np.ma.getmaskarray(field)
        values = np.ma.getdata(field)
    else:
        values = np.asarray(field)
        reached = np.isfinite(values)
    values = _doubles(values, "field must be a 1 to 12-D array of doubles")
    reached = np.ascontiguousarray(reached, dtype=bool)
    dx = _spacing(dx, values.ndim)
    if len(dx) != values.ndim:
        raise ValueError("dx must be of length len(field.shape)")
    start = [float(s) for s in np.atleast_1d(start)]
    return _envfield.descend(values, reached, list(dx), start)


class heap:
    """scikit-fmm's binary min-heap, for code (and its tests) that import it; envfield's
    marcher keeps its own queue in Rust.

    ``push(address, value)`` returns an index, ``update(index, value)`` moves an entry,
    ``pop()`` returns ``(address, value)`` of the smallest, ``empty()``.
    """

    def __init__(self, max_size, self_test=False):
        self._max = int(max_size)
        self._self_test = bool(self_test)
        self._values = []
        self._addresses = []
        self._queue = []  # entry indices, a binary heap on their values
        self._where = []

    def _less(self, a, b):
        return self._values[self._queue[a]] < self._values[self._queue[b]]

    def _swap(self, a, b):
        q = self._queue
        q[a], q[b] = q[b], q[a]
        self._where[q[a]] = a
        self._where[q[b]] = b

    def _up(self, k):
        while k > 0 and self._less(k, (k - 1) // 2):
            self._swap(k, (k - 1) // 2)
            k = (k - 1) // 2

    def _down(self, k):
        n = len(self._queue)
        while True:
            small = k
            for c in (2 * k + 1, 2 * k + 2):
                if c < n and self._less(c, small):
                    small = c
            if small == k:
                return
            self._swap(k, small)
            k = small

    def _check(self):
        if self._self_test:
            for k in range(1, len(self._queue)):
                if self._less(k, (k - 1) // 2):
                    raise RuntimeError("heap self-test failed at position %d" % k)

    def push(self, address, value):
        if len(self._values) == self._max:
            raise RuntimeError("heap push error: heap full\n")
        index = len(self._values)
        self._values.append(float(value))
        self._addresses.append(address)
        self._where.append(len(self._queue))
        self._queue.append(index)
        self._up(len(self._queue) - 1)
        self._check()
        return index

    def update(self, index, value):
        if not 0 <= index < len(self._values) or self._where[index] < 0:
            raise RuntimeError("heap update error: no such entry\n")
        self._values[index] = float(value)
        k = self._where[index]
        self._up(k)
        self._down(self._where[index])
        self._check()

    def pop(self):
        if not self._queue:
            raise RuntimeError("heap pop error: empty heap\n")
        top = self._queue[0]
        self._swap(0, len(self._queue) - 1)
        self._queue.pop()
        self._where[top] = -1
        if self._queue:
            self._down(0)
        self._check()
        return self._addresses[top], self._values[top]

    def empty(self):
        return not self._queue
