"""Type stubs of the extension module (python/src); the public API is the package's."""

from os import PathLike
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class RawModes:
    def to_json(self) -> str: ...
    def columns(self) -> Dict[str, Any]: ...
    def diagram(self) -> Dict[str, np.ndarray]: ...

class RawModel:
    @staticmethod
    def from_config(path: Union[str, PathLike[str]]) -> RawModel: ...
    @staticmethod
    def from_toml(text: str) -> RawModel: ...
    def structure(self) -> str: ...
    def parameter_names(self) -> List[str]: ...
    def base_values(self) -> npt.NDArray[np.float64]: ...
    def bounds(self) -> List[Tuple[float, float]]: ...
    def sensors(self) -> List[str]: ...
    def modes(self, values: npt.NDArray[np.float64], count: Optional[int]) -> Dict[str, Any]: ...
    def frf(
        self,
        values: npt.NDArray[np.float64],
        frequency_hz: npt.NDArray[np.float64],
        pairs: Sequence[Tuple[str, str]],
        quantity_name: str,
    ) -> npt.NDArray[np.complex128]: ...
    def update_frf(self, frf: bytes, values: npt.NDArray[np.float64]) -> str: ...
    def update_modes(
        self, modes_json: str, values: npt.NDArray[np.float64]
    ) -> Tuple[str, List[Tuple[int, int, float]]]: ...
    def synth(
        self,
        inputs: Sequence[str],
        outputs: Sequence[str],
        f_min: float,
        f_max: float,
        step: float,
        noise: float,
        seed: int,
        quantity_name: str,
    ) -> str: ...
    def export_matrices(self, dir: Union[str, PathLike[str]]) -> str: ...

def oma(
    data: npt.NDArray[np.float64],
    fs: float,
    settings_json: str,
    references: Sequence[int],
    sensors: Optional[Sequence[str]] = None,
    start_ns: Optional[int] = None,
) -> RawModes: ...
def identify(
    inputs: npt.NDArray[np.float64],
    outputs: npt.NDArray[np.float64],
    fs: float,
    settings_json: str,
    sensors: Optional[Sequence[str]] = None,
    start_ns: Optional[int] = None,
) -> RawModes: ...
def frf(
    force: npt.NDArray[np.float64],
    responses: npt.NDArray[np.float64],
    fs: float,
    settings_json: str,
) -> Tuple[
    npt.NDArray[np.float64], npt.NDArray[np.complex128], npt.NDArray[np.float64], Dict[str, Any]
]: ...
def fit_modes(
    frequencies: npt.NDArray[np.float64],
    h: npt.NDArray[np.complex128],
    sigma: npt.NDArray[np.float64],
    modes: int,
) -> Dict[str, Any]: ...
def h1_sigma(
    h: npt.NDArray[np.complex128],
    coherence: npt.NDArray[np.float64],
    averages: int,
    inputs: int,
) -> npt.NDArray[np.float64]: ...
def read_recording(
    path: Union[str, PathLike[str]],
) -> Tuple[List[Dict[str, Any]], List[Tuple[str, int, str]]]: ...
def read_results(path: Union[str, PathLike[str]]) -> List[Tuple[str, int, str]]: ...
def result_topics() -> List[str]: ...
