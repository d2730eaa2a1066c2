"""Broadcasting of scalar-or-array arguments for the native row functions."""

from typing import Any, Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray


def broadcast_call(
    native: Callable[..., NDArray[np.float64]], *args: ArrayLike, **keywords: Any
) -> float | NDArray[np.float64]:
    """``native`` over the broadcast of ``args`` (numbers or arrays), as one
    contiguous float64 column each; the result has the broadcast shape (a
    float for scalar arguments)."""
    try:
        arrays = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in args))
    except ValueError as error:
        raise ValueError(f"arguments do not broadcast together: {error}") from None
    shape = arrays[0].shape
    columns = [np.ascontiguousarray(a.reshape(-1)) for a in arrays]
    out = native(*columns, **keywords).reshape(shape)
    return float(out) if shape == () else out
