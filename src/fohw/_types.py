"""Type aliases of the public API's annotations (the package ships ``py.typed``).

The aliases that name fohw's own classes live with them (``BasisLike`` in
:mod:`fohw.model.basis`, ``OrdersLike`` in :mod:`fohw.model.orders`). Annotations only:
nothing here is checked at run time (the validation layer, :mod:`fohw._validation`, checks
values and names the argument in its errors).
"""

from __future__ import annotations

from typing import Union

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["ArrayLike", "RandomStateLike", "PairLike"]

#: ``None``, a seed, or a :class:`numpy.random.Generator` (scikit-learn's ``random_state``).
RandomStateLike = Union[None, int, np.random.Generator]
#: A pair of floats such as ``(u0, y0)``.
PairLike = tuple[float, float]
