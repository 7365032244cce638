"""Reading inputs and writing results."""

from torchsym.io.read import (
    IMAGE_SUFFIXES,
    MAX_PIXELS,
    MAX_POINTS,
    MESH_SUFFIXES,
    POINT_SUFFIXES,
    infer_kind,
    load_input,
    read_image,
    read_mesh,
    read_pointcloud,
)
from torchsym.io.write import write_image, write_json, write_mesh, write_ply

__all__ = [
    "IMAGE_SUFFIXES",
    "MAX_PIXELS",
    "MAX_POINTS",
    "MESH_SUFFIXES",
    "POINT_SUFFIXES",
    "infer_kind",
    "load_input",
    "read_image",
    "read_mesh",
    "read_pointcloud",
    "write_image",
    "write_json",
    "write_mesh",
    "write_ply",
]
