"""nilpotent: privileged coordinates, nilpotent approximation, simulation and steering
of driftless control systems.

The public API is re-exported here; implementation lives in the sub-packages.
"""

from nilpotent.core.system import ControlSystem as ControlSystem
from nilpotent.errors import NilpotentError as NilpotentError

__version__ = "0.1.0"
