"""mrsysid: offline nonlinear system identification of multirotor aircraft, after
Hopwood & Woolsey, "Towards Large-Domain Nonlinear System Identification of Multirotor
Aircraft" (2023), from Python.

The engine is the Rust library ``mrsysid`` (this package is a thin layer over it, never
a second implementation)::

    import mrsysid
    vehicle = mrsysid.Vehicle.from_toml("data/vehicles/quad_x.toml")
    results = mrsysid.fit(vehicle, ["data/quad_x_flight_quadratic_drag.csv"])
    print(results.summary())
    results.parameters           # DataFrame: estimate, std, std_white, t, p, ci_low, ci_high, unit
    results.metrics              # DataFrame per (data, stage, axis): r2, rmse, nrmse, tic
    results.model.predict(frame) # DataFrame fx ... mz
"""

from ._mrsysid import CHUNK_SAMPLES, Vehicle, __version__
from ._fit import fit
from ._results import Model, Results, load_model
from ._stats import accumulate, fit_from_stats, merge_stats
from .errors import (
    AccumulateError,
    DiagnoseError,
    EstimateError,
    InputError,
    ModelError,
    ModelFileError,
    MrsysidError,
    RequestError,
    SpillError,
    StatsError,
    VehicleError,
)

__all__ = [
    "CHUNK_SAMPLES",
    "Vehicle",
    "__version__",
    "fit",
    "accumulate",
    "merge_stats",
    "fit_from_stats",
    "Model",
    "Results",
    "load_model",
    "AccumulateError",
    "DiagnoseError",
    "EstimateError",
    "InputError",
    "ModelError",
    "ModelFileError",
    "MrsysidError",
    "RequestError",
    "SpillError",
    "StatsError",
    "VehicleError",
]
