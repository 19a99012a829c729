from typing import Optional, Sequence, Tuple

import numpy as np

__version__: str

def march(
    kind: str,
    phi: np.ndarray,
    dx: Sequence[float],
    order: int,
    narrow: float,
    periodic: Sequence[bool],
    self_test: bool,
    mask: Optional[np.ndarray] = None,
    speed: Optional[np.ndarray] = None,
    ext_mask: Optional[np.ndarray] = None,
) -> Tuple[np.ndarray, np.ndarray, Optional[np.ndarray]]: ...
def descend(
    values: np.ndarray, reached: np.ndarray, dx: Sequence[float], start: Sequence[float]
) -> np.ndarray: ...
