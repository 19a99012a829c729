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

JOINTS: list[str]

class Scene:
    @staticmethod
    def read(path: str, up: Optional[str] = None, units: Optional[str] = None) -> "Scene": ...
    @staticmethod
    def generated(seed: int = 0) -> "Scene": ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...
    def region(self, vae_path: str, samples: Optional[int] = None, seed: int = 0) -> "Region": ...

class Plan:
    planner: str
    kind: str
    reached: bool
    seconds: float
    path_ratio: float
    path: np.ndarray  # (steps, 3) float32, metres
    poses: np.ndarray  # (frames, 22, 3) float32, metres
    fps: float
    supported: np.ndarray  # (frames,) bool
    collision_free: np.ndarray  # (frames,) bool

class Region:
    @property
    def points(self) -> np.ndarray: ...
    @property
    def voxel(self) -> float: ...
    @property
    def sit_downs(self) -> list[Tuple[Tuple[float, float, float], Tuple[float, float, float]]]: ...
    def walk(
        self, start: Sequence[float], goal: Sequence[float], planner: str = "ours_exact", seed: int = 0
    ) -> Plan: ...
    def sit_down(self, index: int, planner: str = "ours_exact", seed: int = 0) -> Plan: ...
    @property
    def lie_downs(self) -> list[Tuple[Tuple[float, float, float], Tuple[float, float, float]]]: ...
    def lie_down(self, index: int, planner: str = "ours_exact", seed: int = 0) -> Plan: ...
