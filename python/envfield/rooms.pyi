import os
from typing import Optional, Tuple, Union

from ._envfield import Plan as Plan, Region as Region

DEFAULT_VAE: str
JOINTS: Tuple[str, ...]

class Scene:
    @classmethod
    def read(
        cls,
        path: Union[str, os.PathLike],
        up: Optional[str] = None,
        units: Union[str, float, None] = None,
    ) -> "Scene": ...
    @classmethod
    def generated(cls, seed: int = 0) -> "Scene": ...
    @property
    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]: ...
    @property
    def warnings(self) -> list[str]: ...
    def region(
        self, samples: Optional[int] = None, seed: int = 0, vae: Union[str, os.PathLike, None] = None
    ) -> Region: ...
