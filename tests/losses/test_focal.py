import torch

from torchsym.losses import binary_focal_loss_with_logits


def test_kornia_focal_equals_equisym():
    # EquiSym's sigmoid_focal_loss (ahyunSeo/EquiSym utils.py), alpha 0.25, gamma 2, written out:
    # (equal for binary targets; for soft targets EquiSym's p_t form and kornia's split form differ)
    # p = sigmoid(x), ce = BCE(x, t), p_t = p t + (1-p)(1-t), loss = alpha_t ce (1 - p_t)^2
    x = torch.tensor([-2.0, -0.5, 0.3, 1.7], dtype=torch.float64)
    t = torch.tensor([0.0, 1.0, 1.0, 0.0], dtype=torch.float64)
    p = torch.sigmoid(x)
    ce = -(t * torch.log(p) + (1 - t) * torch.log(1 - p))
    p_t = p * t + (1 - p) * (1 - t)
    alpha_t = 0.25 * t + 0.75 * (1 - t)
    theirs = alpha_t * ce * (1 - p_t) ** 2
    ours = binary_focal_loss_with_logits(x.view(1, 1, 4), t.view(1, 1, 4), alpha=0.25, gamma=2.0, reduction="none").view(4)
    assert torch.allclose(ours, theirs)
