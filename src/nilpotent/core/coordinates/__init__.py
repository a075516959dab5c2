"""Weighted jets, non-holonomic orders, privileged coordinates and the nilpotent approximation."""

from nilpotent.core.coordinates.approximation import Certificate as Certificate
from nilpotent.core.coordinates.approximation import (
    NilpotentApproximation as NilpotentApproximation,
)
from nilpotent.core.coordinates.approximation import approximate as approximate
from nilpotent.core.coordinates.approximation import certify as certify
from nilpotent.core.coordinates.jets import Poly as Poly
from nilpotent.core.coordinates.jets import weighted_jets as weighted_jets
from nilpotent.core.coordinates.orders import field_order as field_order
from nilpotent.core.coordinates.orders import function_order as function_order
from nilpotent.core.coordinates.orders import weighted_order as weighted_order
from nilpotent.core.coordinates.privileged import (
    PrivilegedCoordinates as PrivilegedCoordinates,
)
from nilpotent.core.coordinates.privileged import privileged_coordinates as privileged_coordinates

__all__ = [
    "Certificate", "NilpotentApproximation", "Poly", "PrivilegedCoordinates", "approximate",
    "certify", "field_order", "function_order", "privileged_coordinates", "weighted_jets",
    "weighted_order",
]
