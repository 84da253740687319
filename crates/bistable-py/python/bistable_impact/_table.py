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
        self._cols: Dict[str, np.ndarray] = {}
        for name, dtype, data in columns:
            self._cols[name] = np.frombuffer(data, dtype="<" + dtype).copy()

    @property
    def columns(self) -> List[str]:
        return list(self._cols)

    def __getitem__(self, name: str) -> np.ndarray:
        return self._cols[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._cols)

    def __len__(self) -> int:
        first = next(iter(self._cols.values()), None)
        return 0 if first is None else len(first)

    def to_pandas(self):
        import pandas as pd

        return pd.DataFrame(self._cols)

    def __repr__(self) -> str:
        return f"Table({len(self)} rows: {', '.join(self._cols)})"
