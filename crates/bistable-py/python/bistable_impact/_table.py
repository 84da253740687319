"""Named numpy columns handed over by the native module."""

from __future__ import annotations

from typing import Dict, Iterator, List, Mapping

import numpy as np


class Table(Mapping[str, np.ndarray]):
    """Named numpy columns of equal length (``table['t']``), in a fixed column order.

    ``len(table)`` is the number of rows; ``table.columns`` the names; ``to_pandas()`` a
    DataFrame (needs pandas).
    """

    def __init__(self, columns: List[tuple]):
        # (name, dtype, little-endian bytes) from the native module; each column becomes a
        # numpy array when first read (most callers read a few columns of a few tables).
        self._raw: Dict[str, tuple] = {name: (dtype, data) for name, dtype, data in columns}
        self._cols: Dict[str, np.ndarray] = {}

    @property
    def columns(self) -> List[str]:
        return list(self._raw)

    def __getitem__(self, name: str) -> np.ndarray:
        col = self._cols.get(name)
        if col is None:
            dtype, data = self._raw[name]
            col = np.frombuffer(data, dtype="<" + dtype).copy()
            self._cols[name] = col
        return col

    def __iter__(self) -> Iterator[str]:
        return iter(self._raw)

    def __len__(self) -> int:
        first = next(iter(self._raw.values()), None)
        return 0 if first is None else len(first[1]) // np.dtype(first[0]).itemsize

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame({name: self[name] for name in self._raw})

    def __repr__(self) -> str:
        return f"Table({len(self)} rows: {', '.join(self._raw)})"
