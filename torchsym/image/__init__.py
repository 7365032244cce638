"""Reflection symmetry in photographs (thesis Ch. 2-4)."""

__all__: list[str] = []
