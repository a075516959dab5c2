r"""The trident snake robot: its kinematic forms, geometry and singular sets.

Three modules, one concept each:

* :mod:`~nilpotent.models.trident.forms`: the three kinematic forms
  (:func:`trident_snake`, :func:`trident_snake_paper`,
  :func:`trident_snake_joints`), their derivation from the no-side-slip
  constraints, and :func:`constraint_residuals`;
* :mod:`~nilpotent.models.trident.geometry`: :class:`TridentGeometry` (body
  centre, vertices, wheels, headings, axle lines for one configuration or a
  batch) and :func:`wheel_slip`;
* :mod:`~nilpotent.models.trident.singular`: where the joint form and the
  paper's eq. (vf) are singular (symbolic loci and numeric detectors).

The names below are the public ones; the modules are where they are defined.
"""

from nilpotent.models.trident.forms import BODY_LEG_ANGLES as BODY_LEG_ANGLES
from nilpotent.models.trident.forms import FORMS as FORMS
from nilpotent.models.trident.forms import PAPER_LEG_ANGLES as PAPER_LEG_ANGLES
from nilpotent.models.trident.forms import constraint_residuals as constraint_residuals
from nilpotent.models.trident.forms import trident_snake as trident_snake
from nilpotent.models.trident.forms import trident_snake_joints as trident_snake_joints
from nilpotent.models.trident.forms import trident_snake_paper as trident_snake_paper
from nilpotent.models.trident.geometry import Configs as Configs
from nilpotent.models.trident.geometry import SampledConfigs as SampledConfigs
from nilpotent.models.trident.geometry import TridentGeometry as TridentGeometry
from nilpotent.models.trident.geometry import WheelSlip as WheelSlip
from nilpotent.models.trident.geometry import wheel_slip as wheel_slip
from nilpotent.models.trident.singular import JointSingularity as JointSingularity
from nilpotent.models.trident.singular import PaperSingularity as PaperSingularity
from nilpotent.models.trident.singular import joint_determinant as joint_determinant
from nilpotent.models.trident.singular import joint_singular_locus as joint_singular_locus
from nilpotent.models.trident.singular import joint_singularity as joint_singularity
from nilpotent.models.trident.singular import (
    paper_singular_determinant as paper_singular_determinant,
)
from nilpotent.models.trident.singular import paper_singular_locus as paper_singular_locus
from nilpotent.models.trident.singular import paper_singularity as paper_singularity

__all__ = [
    "BODY_LEG_ANGLES",
    "FORMS",
    "PAPER_LEG_ANGLES",
    "Configs",
    "JointSingularity",
    "PaperSingularity",
    "SampledConfigs",
    "TridentGeometry",
    "WheelSlip",
    "constraint_residuals",
    "joint_determinant",
    "joint_singular_locus",
    "joint_singularity",
    "paper_singular_determinant",
    "paper_singular_locus",
    "paper_singularity",
    "trident_snake",
    "trident_snake_joints",
    "trident_snake_paper",
    "wheel_slip",
]
