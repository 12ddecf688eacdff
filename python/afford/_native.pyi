"""The native half of afford (pyo3); called through afford/__init__.py only."""

from typing import Any, Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str

def detect_array(
    points: npt.NDArray[Any],
    name: str,
    heights: List[float],
    agents: List[str],
    affordances: List[str],
    up: str,
    units: str,
    camera: bool,
    floor: str,
    transform: Optional[str],
    threads: Optional[int],
) -> Dict[str, Any]: ...
def detect_file(
    path: str,
    heights: List[float],
    agents: List[str],
    affordances: List[str],
    up: str,
    units: str,
    camera: bool,
    floor: str,
    transform: Optional[str],
    sample: Optional[float],
    threads: Optional[int],
) -> Dict[str, Any]: ...
def read(
    path: str,
    up: str,
    units: str,
    camera: bool,
    floor: str,
    transform: Optional[str],
    sample: Optional[float],
) -> Tuple[npt.NDArray[np.float64], int]: ...
def documents(results: List[Dict[str, Any]]) -> Tuple[str, str, str]: ...
def cli_main(argv: List[str]) -> int: ...
