import pytest
import torch

from torchsym.core.random import make_generator, numpy_rng, random_subset
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

    def test_subset_all(self):
        assert torch.equal(random_subset(5, 9), torch.arange(5))

    def test_exception(self):
        with pytest.raises(InputValueError, match="generator: expected a torch.Generator, an int seed or None"):
            make_generator("seed")
