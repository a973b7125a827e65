"""Results of a fit and the identified model, as pandas objects around the extension's
classes."""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional, Union

import pandas as pd

from . import _mrsysid
from ._tables import Table, columns

PathLike = Union[str, "os.PathLike[str]"]

#: Columns of ``Results.parameters``.
PARAMETER_COLUMNS = ["estimate", "std", "std_white", "t", "p", "ci_low", "ci_high", "unit"]
#: Output columns of a prediction: force (N) and moment (N m) in body FRD axes.
OUTPUT_COLUMNS = ["fx", "fy", "fz", "mx", "my", "mz"]


class Model:
    """An identified model: vehicle, model structure, estimated parameters and their
    covariance. ``predict`` gives force and moment for states; ``save`` writes the model
    file that ``mrsysid.load_model`` and ``mrsysid predict --model`` read."""

    def __init__(self, native: _mrsysid.Model) -> None:
        self._native = native

    @property
    def parameters(self) -> pd.DataFrame:
        """Estimates and standard deviations, indexed by parameter name: ``estimate``,
        ``std``, ``unit``."""
        p = self._native.parameters()
        return pd.DataFrame(
            {"estimate": p["estimate"], "std": p["std"], "unit": p["unit"]},
            index=pd.Index(p["name"], name="parameter"),
        )

    @property
    def rotor_count(self) -> int:
        """Rotors of the model's vehicle (columns ``omega_1 ... omega_N``)."""
        return self._native.rotor_count

    def predict(self, states: Table) -> pd.DataFrame:
        """Force (N) and moment (N m) of the model, body FRD axes, per row of ``states``.

        ``states`` is a DataFrame or a dict of columns named as in the data contract:
        ``u v w`` (m/s, air-relative), ``p q r`` (rad/s), ``omega_1..omega_N`` (rad/s)
        and, where the model's terms need them, ``omega_dot_1..N`` (rad/s²), ``height``
        (m) and ``qw qx qy qz``. Measured ``fx ... mz`` columns are ignored. Returns
        columns ``fx fy fz mx my mz`` with the index of ``states``.

        Terms that need signals the fit pipeline derives from a log's time series (the
        rotor-acceleration rate of a rotor-speed delay, the slow rotor thrust of a trim
        moment) cannot be evaluated on states: use ``predict_log`` for such a model.
        """
        out = self._native.predict("states", columns(states, "states"))
        return pd.DataFrame(out, columns=OUTPUT_COLUMNS, index=_index(states))

    def prediction_std(self, states: Table) -> Optional[pd.DataFrame]:
        """Standard deviation (N, N m) of the predicted mean force and moment per row of
        ``states`` from the parameter covariance: the parameters' uncertainty, without
        the residual noise. ``None`` for a model saved without a covariance."""
        out = self._native.prediction_std("states", columns(states, "states"))
        if out is None:
            return None
        return pd.DataFrame(out, columns=OUTPUT_COLUMNS, index=_index(states))

    def predict_log(self, path: PathLike, mapping: Optional[PathLike] = None) -> pd.DataFrame:
        """Force and moment per sample of a log file (CSV, MCAP, ULog; ``mapping`` a
        mapping file), read and derived exactly as ``mrsysid predict`` does: columns
        ``t fx fy fz mx my mz``."""
        out = self._native.predict_log(os.fspath(path), None if mapping is None else os.fspath(mapping))
        return pd.DataFrame(out, columns=["t"] + OUTPUT_COLUMNS)

    def save(self, path: PathLike) -> None:
        """Writes the model file (TOML), whole or not at all."""
        self._native.save(os.fspath(path))

    def __repr__(self) -> str:
        return repr(self._native)


def load_model(path: PathLike) -> Model:
    """Reads a model file written by ``Model.save`` or ``mrsysid fit --model-out``."""
    return Model(_mrsysid.Model.load(os.fspath(path)))


class Results:
    """What ``mrsysid.fit`` produced: the final model (Eq. 22 after the diagnosis when it
    ran) with its statistics, and the report of ``mrsysid fit``."""

    def __init__(self, native: _mrsysid.Results) -> None:
        self._native = native

    @property
    def parameters(self) -> pd.DataFrame:
        """The final model's parameters, indexed by name: ``estimate``, ``std`` (with the
        coloured-residual correction: the one to use on flight data), ``std_white``
        (white residuals, seed Eq. 24), ``t`` = estimate/std, ``p`` (two-sided P-value of
        θ = 0), ``ci_low``/``ci_high`` (95 % confidence interval) and ``unit``."""
        p = self._native.parameters()
        frame = pd.DataFrame(
            {c: p[c] for c in PARAMETER_COLUMNS}, index=pd.Index(p["name"], name="parameter")
        )
        return frame

    @property
    def metrics(self) -> pd.DataFrame:
        """Goodness of fit per axis, indexed by (``data``, ``stage``, ``axis``), columns
        ``r2`` (centred R²), ``rmse`` (N or N m), ``nrmse`` and ``tic``. ``data`` is
        ``fit`` (all fit data), ``cross-validated`` (every fold's held-out predictions
        pooled) or ``validation`` (the validation logs, when given); ``stage`` is
        ``before`` (the Eq. 22 model) or ``after`` (the adopted model, when the
        diagnosis ran: the final model, with the Eq. 22 model on any axis whose held-out
        data the final model predicted worse, ``eq22_axes`` of the report)."""
        rows = self._native.metrics()
        frame = pd.DataFrame(
            rows, columns=["data", "stage", "axis", "r2", "rmse", "nrmse", "tic"]
        )
        return frame.set_index(["data", "stage", "axis"])

    @property
    def model(self) -> Model:
        """The final model: predict, prediction_std, save."""
        return Model(self._native.model())

    @property
    def variance_inflation(self) -> float:
        """Coloured-residual variance inflation κ ≥ 1 applied to σ² (1 without the
        residual pass)."""
        return self._native.variance_inflation

    def covariance(self) -> pd.DataFrame:
        """Parameter covariance of the final model (coloured-residual corrected), over
        all parameters of its structure (rows and columns of dropped ones zero)."""
        names = self._native.structure_parameters()
        return pd.DataFrame(self._native.covariance(), index=names, columns=names)

    def summary(self) -> str:
        """The tables ``mrsysid fit`` prints (FSOA, MMR estimates, fit metrics,
        diagnosis), then the final model's parameters."""
        return self._native.summary()

    def report(self) -> Dict[str, Any]:
        """The JSON report of ``mrsysid fit --json`` as a dict (schema in
        docs/report-schema.md of the repository)."""
        return json.loads(self._native.report_json())

    def equations(self) -> str:
        """The final model as equations, one line per axis, estimates in place."""
        return self._native.equations()

    def __repr__(self) -> str:
        p = self._native.parameters()
        return f"<mrsysid.Results: {len(p['name'])} parameters>"


def _index(states: Table) -> Any:
    """The index of a DataFrame, else a range."""
    index = getattr(states, "index", None)
    return index if isinstance(index, pd.Index) else None


__all__ = ["Model", "Results", "load_model"]
