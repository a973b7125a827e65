"""Type stubs of the extension module ``mrsysid._mrsysid`` (the Rust layer). Use the
package ``mrsysid``, which wraps these classes with pandas."""

from typing import Dict, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

__version__: str
CHUNK_SAMPLES: int

Columns = Dict[str, npt.NDArray[np.float64]]

class Vehicle:
    """A multirotor vehicle: rotor layout, mass, inertia, rotor size."""

    @staticmethod
    def from_toml(path: str) -> Vehicle:
        """Reads and checks a vehicle TOML file (raises ``VehicleError``)."""
    @staticmethod
    def from_toml_str(text: str) -> Vehicle:
        """Parses and checks vehicle TOML text (raises ``VehicleError``)."""
    @property
    def name(self) -> str:
        """The vehicle's name."""
    @property
    def rotor_count(self) -> int:
        """Number of rotors."""
    @property
    def mass(self) -> float:
        """Mass, kg."""
    @property
    def configuration(self) -> str:
        """Configuration class of the seed's Definition 1."""
    def notes(self) -> List[str]:
        """Notes on Assumption 2 breaches (empty when it holds)."""

class Model:
    """An identified model."""

    @staticmethod
    def load(path: str) -> Model: ...
    def save(self, path: str) -> None: ...
    def parameters(self) -> Dict[str, list]: ...
    @property
    def rotor_count(self) -> int: ...
    @property
    def has_covariance(self) -> bool: ...
    def predict(self, name: str, columns: Columns) -> Columns: ...
    def prediction_std(self, name: str, columns: Columns) -> Optional[Columns]: ...
    def predict_log(self, path: str, mapping: Optional[str] = None) -> Columns: ...

class Results:
    """The results of ``fit``."""

    def parameters(self) -> Dict[str, list]: ...
    def metrics(self) -> List[Tuple[str, str, str, float, float, float, float]]: ...
    def report_json(self) -> str: ...
    def summary(self) -> str: ...
    def equations(self) -> str: ...
    @property
    def variance_inflation(self) -> float: ...
    def structure_parameters(self) -> List[str]: ...
    def theta(self) -> List[float]: ...
    def covariance(self) -> npt.NDArray[np.float64]: ...
    def model(self) -> Model: ...

def fit(
    vehicle: Vehicle,
    *,
    logs: List[str],
    tables: List[Tuple[str, Columns]],
    validate_logs: List[str],
    validate_tables: List[Tuple[str, Columns]],
    mapping: Optional[str],
    diagnose: bool,
    threads: Optional[int],
    inflow: str,
    linear_vh: bool,
    rotor_inertia: str,
    drop_invalid: bool,
    holdout_blocks: int,
    holdout_guard: float,
    loads_low_pass: Optional[float],
    estimate_loads_low_pass: bool,
    keep_ground: bool,
    residual_pass: bool,
    groups: List[str],
) -> Results:
    """Runs the fit with the GIL released; Ctrl-C raises ``KeyboardInterrupt``."""

def accumulate(
    vehicle: Vehicle,
    *,
    logs: List[str],
    tables: List[Tuple[str, Columns]],
    mapping: Optional[str],
    threads: Optional[int],
    inflow: str,
    linear_vh: bool,
    rotor_inertia: str,
    drop_invalid: bool,
    loads_low_pass: Optional[float],
    keep_ground: bool,
    diagnose: bool,
) -> bytes:
    """The logs' first-pass statistics as the bytes of one statistics part."""

def merge_stats(parts: List[bytes]) -> bytes:
    """The parts merged in order."""

def fit_from_stats(
    vehicle: Vehicle,
    *,
    parts: bytes,
    validate_parts: Optional[bytes],
    mapping: Optional[str],
    threads: Optional[int],
    inflow: str,
    linear_vh: bool,
    rotor_inertia: str,
    drop_invalid: bool,
    loads_low_pass: Optional[float],
    keep_ground: bool,
    groups: List[str],
) -> Results:
    """The Eq. 22 fit from statistics parts (no residual pass, no diagnosis)."""

class PlannedFit:
    """The Eq. 22 fit of the parts' logs and the plan of their second pass."""

    def __init__(
        self,
        vehicle: Vehicle,
        *,
        parts: List[bytes],
        validate_parts: List[bytes],
        mapping: Optional[str],
        threads: Optional[int],
        inflow: str,
        linear_vh: bool,
        rotor_inertia: str,
        drop_invalid: bool,
        loads_low_pass: Optional[float],
        keep_ground: bool,
        groups: List[str],
    ) -> None: ...
    def plan(self) -> bytes:
        """The plan's bytes, for PreparedPass on every worker."""
    def diagnose(self, passes: List[bytes]) -> "PendingFit":
        """The fit and diagnosis from one second-pass part per log (once only)."""

class PreparedPass:
    """A second-pass plan prepared once per process for passing its logs."""

    def __init__(
        self,
        vehicle: Vehicle,
        plan: bytes,
        *,
        mapping: Optional[str],
        threads: Optional[int],
        inflow: str,
        linear_vh: bool,
        rotor_inertia: str,
        drop_invalid: bool,
        loads_low_pass: Optional[float],
        keep_ground: bool,
    ) -> None: ...
    def pass_log(self, path: str) -> bytes:
        """The second pass of one of the plan's logs, as bytes."""
    def remainder_log(self, model: bytes, path: str) -> bytes:
        """The remainder pass of a fit log with the final model, as bytes."""

class PendingFit:
    """The fit and diagnosis from statistics, waiting for the remainder pass."""

    def remainder_plan(self) -> Optional[Tuple[bytes, List[str]]]:
        """(final model bytes, fit log names), or None when no remainder pass runs."""
    def finish(self, parts: List[bytes]) -> Results:
        """The results with one remainder part per fit log (once only)."""
