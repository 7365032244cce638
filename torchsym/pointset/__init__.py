"""Reflection symmetry of d-dimensional point sets (thesis Ch. 7)."""

__all__: list[str] = []
