from typing import Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Spacing = Union[float, Sequence[float], npt.ArrayLike]
_Periodic = Union[bool, Sequence[bool]]
_Field = Union[np.ndarray, np.ma.MaskedArray]

def distance(
    phi: npt.ArrayLike,
    dx: _Spacing = ...,
    self_test: bool = ...,
    order: int = ...,
    narrow: float = ...,
    periodic: _Periodic = ...,
) -> _Field: ...
def travel_time(
    phi: npt.ArrayLike,
    speed: npt.ArrayLike,
    dx: _Spacing = ...,
    self_test: bool = ...,
    order: int = ...,
    narrow: float = ...,
    periodic: _Periodic = ...,
) -> _Field: ...
def extension_velocities(
    phi: npt.ArrayLike,
    speed: npt.ArrayLike,
    dx: _Spacing = ...,
    self_test: bool = ...,
    order: int = ...,
    ext_mask: npt.ArrayLike | None = ...,
    narrow: float = ...,
    periodic: _Periodic = ...,
) -> Tuple[_Field, _Field]: ...
def path(field: npt.ArrayLike, start: Sequence[float], dx: _Spacing = ...) -> np.ndarray: ...

class heap:
    def __init__(self, max_size: int, self_test: bool = ...) -> None: ...
    def push(self, address: int, value: float) -> int: ...
    def update(self, index: int, value: float) -> None: ...
    def pop(self) -> Tuple[int, float]: ...
    def empty(self) -> bool: ...
