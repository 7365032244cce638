"""The axis stage every image method starts from (thesis Ch. 2): candidates, the
photometric test and refinement, a calibrated score and a decision."""

from torchsym.image.axes.settings import AxisStageSettings, Border, Decision, Photometric, Refine
from torchsym.image.axes.stage import AxisStage, image_axes

__all__ = ["AxisStage", "AxisStageSettings", "Border", "Decision", "Photometric", "Refine", "image_axes"]
