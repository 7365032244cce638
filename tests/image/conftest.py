from __future__ import annotations

import pytest
import torch

from torchsym.image.synthetic import mirrored_objects_image


@pytest.fixture(scope="session")
def single_objects():
    """Five 240 x 240 images, one mirror-symmetric object each at a random angle."""
    return [mirrored_objects_image(1, height=240, width=240, generator=torch.Generator().manual_seed(s)) for s in range(5)]


@pytest.fixture(scope="session")
def three_objects():
    return mirrored_objects_image(3, height=360, width=480, generator=torch.Generator().manual_seed(7))
