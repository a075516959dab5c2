"""Steering: exact steering of nilpotent systems, iterative steering of the true system.

* :func:`plan` — iterative steering of a system with its nilpotent
  approximations (the mathematics page, §7), returning a :class:`Plan`;
* :func:`steer_nilpotent` — exact steering of a nilpotent (triangular
  polynomial) system in privileged coordinates;
* :class:`Segment`, :class:`InputSignal` — controls as data (the
  ``nilpotent/plan@1`` segment format).
"""

from nilpotent.planning.controls import InputSignal as InputSignal
from nilpotent.planning.controls import Segment as Segment
from nilpotent.planning.controls import reverse_segments as reverse_segments
from nilpotent.planning.exact_flow import endpoint as endpoint
from nilpotent.planning.iterative import Iteration as Iteration
from nilpotent.planning.iterative import Plan as Plan
from nilpotent.planning.iterative import plan as plan
from nilpotent.planning.local_model import LocalModel as LocalModel
from nilpotent.planning.nilpotent import NilpotentSteering as NilpotentSteering
from nilpotent.planning.nilpotent import steer_nilpotent as steer_nilpotent
from nilpotent.planning.triangular import TriangularSystem as TriangularSystem
from nilpotent.simulation.trajectory import Trajectory as Trajectory

__all__ = [
    "InputSignal",
    "Iteration",
    "LocalModel",
    "NilpotentSteering",
    "Plan",
    "Segment",
    "Trajectory",
    "TriangularSystem",
    "endpoint",
    "plan",
    "reverse_segments",
    "steer_nilpotent",
]
