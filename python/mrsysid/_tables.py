"""Tables from Python (pandas DataFrames, dicts of arrays) as the columns the
extension reads: a dict of column name -> one-dimensional float64 array in C order.

A float64 column already contiguous (a column of a float64 DataFrame, a float64 numpy
array) is passed as a view, without a copy; other columns are converted once.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any, Dict, List, Tuple, Union

import numpy as np

from .errors import InputError

#: Anything accepted as a table: a pandas (or polars) DataFrame, or a mapping of column
#: name -> 1-D array-like.
Table = Any
PathLike = Union[str, "os.PathLike[str]"]


def is_table(value: Any) -> bool:
    """True for a DataFrame-like object (has ``columns``) or a mapping of columns."""
    if isinstance(value, Mapping):
        return True
    return hasattr(value, "columns") and hasattr(value, "__getitem__")


def is_path(value: Any) -> bool:
    """True for a path to a file."""
    return isinstance(value, (str, os.PathLike))


def columns(table: Table, name: str) -> Dict[str, np.ndarray]:
    """The columns of ``table`` (named ``name`` in errors) as float64 arrays."""
    if isinstance(table, Mapping):
        items = list(table.items())
    elif is_table(table):
        items = [(c, table[c]) for c in table.columns]
    else:
        raise InputError(
            f"{name}: not a table (a DataFrame or a dict of column name -> array)",
            file=name,
            reason="format",
        )
    out: Dict[str, np.ndarray] = {}
    for key, values in items:
        label = str(key)
        try:
            array = np.asarray(values)
            if array.ndim != 1:
                raise ValueError(f"{array.ndim} dimensions")
            out[label] = np.ascontiguousarray(array, dtype=np.float64)
        except (TypeError, ValueError) as e:
            raise InputError(
                f'{name}: column "{label}": not a one-dimensional column of numbers ({e})',
                file=name,
                field=f'column "{label}"',
                reason="not a number",
            ) from None
    return out


def named_tables(samples: Any, default: str) -> List[Tuple[str, Dict[str, np.ndarray]]]:
    """``samples`` — one table, a list of tables, or a mapping of name -> table — as
    (name, columns) pairs. One table is named ``default``, the k-th of a list
    ``default[k]``."""
    if samples is None:
        return []
    if isinstance(samples, Mapping) and samples and all(
        is_table(v) for v in samples.values()
    ):
        return [(str(k), columns(v, str(k))) for k, v in samples.items()]
    if is_table(samples):
        return [(default, columns(samples, default))]
    tables = list(samples)
    return [(f"{default}[{k}]", columns(t, f"{default}[{k}]")) for k, t in enumerate(tables)]
