import pytest
import torch

import numpy as np

from torchsym.core.random import draw_seed, make_generator, numpy_rng, random_subset
from torchsym.errors import InputValueError


class TestRandom:
    def test_same_seed_same_bits(self):
        a = random_subset(1000, 10, make_generator(5))
        b = random_subset(1000, 10, make_generator(5))
        assert torch.equal(a, b)

    def test_default_is_seeded(self):
        assert torch.equal(random_subset(100, 7), random_subset(100, 7))

    def test_global_rng_untouched(self):
        torch.manual_seed(123)
        expected = torch.rand(3)
        torch.manual_seed(123)
        random_subset(100, 10, None)
        numpy_rng(None).random()
        assert torch.equal(torch.rand(3), expected)

    def test_numpy_rng_is_seeded_by_one_draw(self):
        a, b = make_generator(9), make_generator(9)
        seed = draw_seed(a)
        assert 0 <= seed < 2**62
        assert np.random.default_rng(seed).random() == numpy_rng(b).random()
        assert draw_seed(a) == draw_seed(b)  # both advanced by one draw

    def test_subset_all(self):
        assert torch.equal(random_subset(5, 9), torch.arange(5))

    def test_exception(self):
        with pytest.raises(InputValueError, match="generator: expected a torch.Generator, an int seed or None"):
            make_generator("seed")
