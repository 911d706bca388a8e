"""Results of :meth:`estimators.ukf.UnscentedKalmanFilter.batch_filter`."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from estimators.errors import UnknownStateError

__all__ = ["UKFResult"]


@dataclass(frozen=True, eq=False)
class UKFResult:
    """Estimates of :meth:`UnscentedKalmanFilter.batch_filter`.

    Attributes
    ----------
    times : ndarray, shape (N,), s
    x : ndarray, shape (N, n)
        Posterior means; row 0 is the filter's state before the run.
    P : ndarray, shape (N, n, n)
        Posterior covariances.
    state_names : tuple of str
    units : tuple of str
    """

    times: np.ndarray
    x: np.ndarray
    P: np.ndarray
    state_names: tuple
    units: tuple = ()

    def __getitem__(self, name: str) -> np.ndarray:
        """Estimates of state `name`, shape (N,)."""
        try:
            return self.x[:, self.state_names.index(name)]
        except ValueError:
            raise UnknownStateError(f"no state {name!r}; states are {', '.join(self.state_names)}") from None

    @property
    def std(self) -> np.ndarray:
        """Standard deviations, shape (N, n): square roots of the diagonals of ``P``."""
        return np.sqrt(np.einsum("kii->ki", self.P))
