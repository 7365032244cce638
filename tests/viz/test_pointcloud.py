"""torchsym.viz.pointcloud: the pictures of a reflection plane."""

import torchsym.viz
from torchsym.pointcloud import detect_reflection_plane, planted_symmetric_cloud


class TestWriteReflectionPlane:
    def test_smoke(self, tmp_path):
        cloud = planted_symmetric_cloud(800, generator=0)
        res = detect_reflection_plane(cloud.points)
        paths = torchsym.viz.write_artifacts(res, cloud.points, tmp_path, "cloud")
        assert [p.name for p in paths] == ["cloud_plane.ply", "cloud_plane.png"]
        assert all(p.stat().st_size > 0 for p in paths)
        assert not hasattr(type(res), "write_artifacts") or "write_artifacts" not in vars(type(res))
