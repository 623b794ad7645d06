"""Named errors of the multibody library."""


class MultibodyError(ValueError):
    """Base class of every multibody modelling error."""


class RedundantConstraintError(MultibodyError):
    """``[Phi_q B T; P]`` is rank deficient: redundant constraints or a dependent choice of
    independent velocities."""


class AssemblyError(MultibodyError):
    """The initial configuration cannot be assembled (a constraint residual stays large)."""


class SingularMassMatrixError(MultibodyError):
    """The reduced mass matrix ``R^T T^T M T R`` is singular or not positive definite."""
