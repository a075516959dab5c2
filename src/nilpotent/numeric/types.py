"""Shape aliases for the float arrays of the numeric layer (annotations only).

numpy cannot check shapes statically; these names say in every signature
which shape an array has (``n`` coordinates, ``m`` inputs, ``B`` trajectories
of a batch, ``T`` sample times)::

    State         (n,)        one state
    States        (B, n)      a batch of states (or (T, n): one trajectory's samples)
    Samples       (B, T, n)   a batch of sampled trajectories
    Times         (T,)        sample times
    Inputs        (B, m)      the inputs of a batch at one time
    PerTrajectory (B,)        one number per trajectory (status codes, errors)
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
import numpy.typing as npt

__all__ = ["Inputs", "PerTrajectory", "Samples", "State", "States", "Times"]

State: TypeAlias = npt.NDArray[np.float64]
States: TypeAlias = npt.NDArray[np.float64]
Samples: TypeAlias = npt.NDArray[np.float64]
Times: TypeAlias = npt.NDArray[np.float64]
Inputs: TypeAlias = npt.NDArray[np.float64]
PerTrajectory: TypeAlias = npt.NDArray[np.generic]
