"""Large FE bodies: matrices and their readers, interface couplings, Craig-Bampton
condensation, and (with scikit-fem) solid meshes for examples."""

from .coupling import Coupling, coupling_transform
from .craig_bampton import CondensedFE, condense
from .matrices import FEModel

__all__ = ["CondensedFE", "Coupling", "FEModel", "condense", "coupling_transform"]
