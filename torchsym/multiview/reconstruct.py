"""Sparse reconstruction of a scene by COLMAP, and one SIFT descriptor per 3D point
(thesis Sec. 5.3.1-5.3.2).

COLMAP (through pycolmap) extracts SIFT features, matches every pair of photos and runs
incremental mapping, as the thesis does (its [137]). Each 3D point's descriptor is the
mean of the SIFT descriptors of its observations (Sec. 5.3.2).
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import torch

from torchsym.errors import InputFileError, SolverError
from torchsym.multiview.result import Cameras
from torchsym.multiview.settings import ReconstructionSettings
from torchsym.multiview.views import Views

logger = logging.getLogger(__name__)

log = logging.getLogger(__name__)

__all__ = ["SparseModel", "number_by_name", "point_descriptors", "reconstruct"]


@dataclasses.dataclass(frozen=True)
class SparseModel:
    """A sparse reconstruction and what the detector reads of it.

    Attributes:
        points: ``(M, 3)`` float64 3D points in the reconstruction's frame.
        colors: ``(M, 3)`` uint8 RGB colours.
        descriptors: ``(M, 128)`` float32 mean SIFT descriptor of each point's
            observations, in COLMAP's layout (4 x 4 cells of 8 orientation bins).
        cameras: the registered photos' cameras.
        n_photos: photos given.
        reconstruction: the ``pycolmap.Reconstruction`` (for writing in COLMAP's format).
        timings: seconds per stage (``features``, ``matching``, ``mapping``, ``descriptors``).
    """

    points: torch.Tensor
    colors: torch.Tensor
    descriptors: torch.Tensor
    cameras: Cameras
    n_photos: int
    reconstruction: Any
    timings: dict[str, float]


def _stage_photos(views: Views, folder: Path) -> list[str]:
    """Copy (or write) the photos into ``folder``, checking each can be decoded."""
    names = views.names
    if views.paths:
        for name, path in zip(names, views.paths):
            header = cv2.imread(str(path), cv2.IMREAD_REDUCED_GRAYSCALE_8)
            if header is None:
                raise InputFileError(f"images: '{path}' cannot be read as an image")
            shutil.copyfile(path, folder / name)
    else:
        for name, image in zip(names, views.images):
            a = (image.detach().float().clamp(0, 1).cpu() * 255).round().to(torch.uint8)
            a = a.expand(3, -1, -1) if a.shape[0] == 1 else a
            cv2.imwrite(str(folder / name), a.permute(1, 2, 0).numpy()[:, :, ::-1])
    return names


def number_by_name(database_path: Path) -> None:
    """Give the photos of a COLMAP database ids in the order of their names.

    Threaded extraction numbers the photos in the order their threads finish; matching
    and mapping visit photos by id, so without this their results would vary from run to
    run. The features of each photo do not depend on the thread count. The photos must
    share one camera (``single_camera``): ids are reassigned, cameras are not.
    """
    import pycolmap

    db = pycolmap.Database.open(str(database_path))
    try:
        images = sorted(db.read_all_images(), key=lambda im: im.image_id)
        names = sorted(im.name for im in images)
        if [im.name for im in images] == names:
            return
        features = {im.name: (db.read_keypoints(im.image_id), db.read_descriptors(im.image_id)) for im in images}
        db.clear_keypoints()
        db.clear_descriptors()
        for im in images:  # two passes: names are unique in the database
            im.name = "~" + im.name
            db.update_image(im)
        for im, name in zip(images, names):
            im.name = name
            db.update_image(im)
            db.write_keypoints(im.image_id, features[name][0])
            db.write_descriptors(im.image_id, features[name][1])
    finally:
        db.close()


def point_descriptors(reconstruction: Any, database_path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Each 3D point's id and the mean of its observations' SIFT descriptors (Sec. 5.3.2).

    Returns:
        ``ids (M,)`` int64 point ids and ``descriptors (M, 128)`` float32.
    """
    import pycolmap

    db = pycolmap.Database.open(str(database_path))
    try:
        per_image = {int(i): db.read_descriptors(int(i)).data.astype(np.float32) for i in reconstruction.reg_image_ids()}
    finally:
        db.close()
    ids = np.array(sorted(reconstruction.point3D_ids()), dtype=np.int64)
    out = np.zeros((len(ids), 128), dtype=np.float32)
    for row, pid in enumerate(ids):
        elements = reconstruction.points3D[int(pid)].track.elements
        out[row] = np.mean([per_image[int(e.image_id)][int(e.point2D_idx)] for e in elements], axis=0)
    return ids, out


@contextlib.contextmanager
def _colmap_log_level() -> Iterator[None]:
    """COLMAP's INFO lines (about 80 a scene: each photo's features, each match, each
    registration) held back unless torchsym logs at INFO (``-v``); warnings still show."""
    import pycolmap

    saved = pycolmap.logging.minloglevel
    if not logger.isEnabledFor(logging.INFO):
        pycolmap.logging.minloglevel = max(int(saved), 1)  # glog: 0 INFO, 1 WARNING
    try:
        yield
    finally:
        pycolmap.logging.minloglevel = saved


def reconstruct(views: Views, settings: ReconstructionSettings, seed: int) -> SparseModel:
    """Sparse structure from motion of ``views`` by COLMAP (thesis Sec. 5.3.1).

    Raises:
        InputFileError: a photo cannot be read.
        SolverError: COLMAP could not register two photos (the photos do not overlap,
            or have too few features).
    """
    import pycolmap

    timings: dict[str, float] = {}
    with _colmap_log_level(), tempfile.TemporaryDirectory(prefix="torchsym-sfm-") as tmp:
        work = Path(tmp)
        (work / "images").mkdir()
        names = _stage_photos(views, work / "images")
        db = work / "database.db"
        t0 = time.perf_counter()
        # Renumbering by name (number_by_name) keeps each photo's camera only when they share one.
        threads = settings.n_extraction_threads if settings.single_camera else 1
        extraction = pycolmap.FeatureExtractionOptions(max_image_size=settings.max_image_side, num_threads=threads)
        extraction.sift.max_num_features = settings.max_features
        mode = pycolmap.CameraMode.SINGLE if settings.single_camera else pycolmap.CameraMode.AUTO
        pycolmap.extract_features(
            db, work / "images", image_names=names, camera_mode=mode, extraction_options=extraction, device=pycolmap.Device.cpu
        )
        number_by_name(db)
        timings["features"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        matching = pycolmap.FeatureMatchingOptions(num_threads=settings.n_threads)
        pycolmap.match_exhaustive(db, matching_options=matching, device=pycolmap.Device.cpu)
        timings["matching"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        pycolmap.set_random_seed(seed)
        options = pycolmap.IncrementalPipelineOptions(num_threads=settings.n_threads, random_seed=seed, multiple_models=False)
        models = pycolmap.incremental_mapping(db, work / "images", work / "sparse", options=options)
        timings["mapping"] = time.perf_counter() - t0
        if not models or models[max(models)].num_points3D() == 0:
            raise SolverError(
                f"images: reconstruction failed: COLMAP registered no two of the {len(names)} photos "
                "(they share too few matching features)"
            )
        rec = max(models.values(), key=lambda r: (r.num_reg_images(), r.num_points3D()))
        t0 = time.perf_counter()
        ids, desc = point_descriptors(rec, db)
        timings["descriptors"] = time.perf_counter() - t0
    pts = np.stack([rec.points3D[int(i)].xyz for i in ids])
    cols = np.stack([rec.points3D[int(i)].color for i in ids]).astype(np.uint8)
    images = [rec.images[int(i)] for i in sorted(rec.reg_image_ids())]
    poses = [im.cam_from_world() for im in images]
    return SparseModel(
        points=torch.from_numpy(pts),
        colors=torch.from_numpy(cols),
        descriptors=torch.from_numpy(desc),
        cameras=Cameras(
            image_names=[im.name for im in images],
            intrinsics=torch.from_numpy(np.stack([im.camera.calibration_matrix() for im in images])),
            rotations=torch.from_numpy(np.stack([p.rotation.matrix() for p in poses])),
            translations=torch.from_numpy(np.stack([np.asarray(p.translation) for p in poses])),
            sizes=torch.tensor([[im.camera.width, im.camera.height] for im in images]),
        ),
        n_photos=len(names),
        reconstruction=rec,
        timings=timings,
    )
