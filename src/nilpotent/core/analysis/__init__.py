"""Generic growth, orbits, the singular locus and the filtration of a system at a point."""

from nilpotent.core.analysis.filtration import Filtration as Filtration
from nilpotent.core.analysis.filtration import analyze as analyze
from nilpotent.core.analysis.filtration import singular_locus as singular_locus
from nilpotent.core.analysis.growth import generic_growth_vector as generic_growth_vector
from nilpotent.core.analysis.orbit import OrbitCertificate as OrbitCertificate
from nilpotent.core.analysis.orbit import certify_by_orbit as certify_by_orbit
from nilpotent.core.analysis.singular import SingularLocus as SingularLocus
from nilpotent.core.analysis.singular import singular_set as singular_set

__all__ = [
    "Filtration", "OrbitCertificate", "SingularLocus", "analyze", "certify_by_orbit",
    "generic_growth_vector", "singular_locus", "singular_set",
]
