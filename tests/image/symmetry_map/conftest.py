from __future__ import annotations

import pytest
import torch

from torchsym.image.synthetic import mirrored_photo


@pytest.fixture(scope="session")
def mirrored():
    """A 160 x 200 synthetic photo (textures, no files) with one mirrored object and its exact field."""
    return mirrored_photo(height=160, width=200, generator=torch.Generator().manual_seed(1))


@pytest.fixture(scope="session")
def irs_result(mirrored):
    from torchsym.image.symmetry_map import symmetry_map

    return symmetry_map(mirrored["image"], n_axes=1)
