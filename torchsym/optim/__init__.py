"""Riemannian optimisation on :mod:`torchsym.manifolds`: trust region and steepest descent."""

from torchsym.optim.gradient_descent import gradient_descent
from torchsym.optim.result import OptimResult
from torchsym.optim.trust_region import trust_region

__all__ = ["OptimResult", "gradient_descent", "trust_region"]
