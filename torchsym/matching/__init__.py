"""Correspondence search shared by several methods."""

from torchsym.matching.knn import KNNIndex, mutual_nearest

__all__ = ["KNNIndex", "mutual_nearest"]
