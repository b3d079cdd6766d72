"""Texture transfer through a precise map, and notebook views (issue 14, items 3 and 6)."""

import sys

import numpy as np
import pytest
import trimesh
from PIL import Image

import meshcorr
from meshcorr import datasets as ds
from meshcorr.errors import MeshError, ParameterError
from meshcorr.maps.texture import TexturedMesh, read_textured_obj, transfer_uv, write_textured_obj


def _checker() -> Image.Image:
    return Image.fromarray((np.indices((64, 64)).sum(axis=0) // 8 % 2 * 255).astype(np.uint8)).convert("RGB")


@pytest.fixture(scope="module")
def figure_and_rigid_copy():
    shape = ds.figure()
    copy, truth = ds.rigid_copy(shape, random_state=4)
    return shape, copy, truth


@pytest.fixture()
def textured(figure_and_rigid_copy, tmp_path):
    _, copy, _ = figure_and_rigid_copy
    uv = (copy.vertices[:, :2] - copy.vertices[:, :2].min(axis=0)) / np.ptp(copy.vertices[:, :2], axis=0)
    mesh = trimesh.Trimesh(copy.vertices, copy.faces, process=False,
                           visual=trimesh.visual.TextureVisuals(uv=uv, image=_checker()))
    mesh.export(tmp_path / "target.obj")
    return tmp_path / "target.obj", uv


def test_uvs_and_texture_carried_through_the_map(figure_and_rigid_copy, textured, tmp_path):
    shape, copy, truth = figure_and_rigid_copy
    path, uv = textured
    target = read_textured_obj(path)
    np.testing.assert_allclose(target.vertices, copy.vertices, atol=1e-6)  # OBJ keeps 8 digits
    np.testing.assert_allclose(target.vertex_uv(), uv, atol=1e-6)
    result = meshcorr.match(shape, target, refine=False)
    np.testing.assert_array_equal(result.map, truth)
    source_uv = transfer_uv(result.precise_map(), target)
    np.testing.assert_allclose(source_uv, uv[truth], atol=1e-3)  # exact map: the target's own UVs
    obj, mtl, png = write_textured_obj(tmp_path / "source.obj", shape.vertices, shape.faces, source_uv,
                                       target.image, inputs=(path,))
    written = read_textured_obj(obj)
    np.testing.assert_allclose(written.vertex_uv(), source_uv, atol=1e-7)
    assert written.image.size == (64, 64) and mtl.exists() and png.exists()
    np.testing.assert_allclose(result.transfer(target.vertex_uv(), precise=True), source_uv, atol=1e-12)


def test_uv_seams_are_merged_back_into_one_surface(tmp_path):
    # two triangles sharing the edge 1-2, whose corners have other UVs in each triangle
    (tmp_path / "seam.mtl").write_text("newmtl m\nmap_Kd seam.png\n")
    _checker().save(tmp_path / "seam.png")
    (tmp_path / "seam.obj").write_text(
        "mtllib seam.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
        "vt 0 0\nvt 0.5 0\nvt 0 0.5\nvt 0.6 0\nvt 0.5 0.6\nvt 1 1\nf 1/1 2/2 3/3\nf 2/4 4/6 3/5\n")
    mesh = read_textured_obj(tmp_path / "seam.obj")
    assert mesh.vertices.shape == (4, 3) and mesh.faces.shape == (2, 3)
    np.testing.assert_array_equal(np.sort(np.unique(mesh.faces)), np.arange(4))
    np.testing.assert_allclose(mesh.corner_uv[1], [[0.6, 0], [1, 1], [0.5, 0.6]])


def test_texture_errors(figure_and_rigid_copy, textured, tmp_path):
    shape, copy, _ = figure_and_rigid_copy
    path, uv = textured
    plain = tmp_path / "plain.obj"
    trimesh.Trimesh(copy.vertices, copy.faces, process=False).export(plain)
    with pytest.raises(MeshError, match="no texture coordinates"):
        read_textured_obj(plain)
    with pytest.raises(MeshError, match="cannot be read"):
        read_textured_obj(tmp_path / "missing.obj")
    target = read_textured_obj(path)
    with pytest.raises(ParameterError, match="is an input file"):
        write_textured_obj(path, copy.vertices, copy.faces, uv, target.image, inputs=(path,))
    with pytest.raises(ParameterError, match="ending in .obj"):
        write_textured_obj(tmp_path / "x.ply", copy.vertices, copy.faces, uv, target.image)
    with pytest.raises(ParameterError, match="one row per vertex"):
        write_textured_obj(tmp_path / "x.obj", copy.vertices, copy.faces, uv[:-1], target.image)
    other = TexturedMesh(shape.vertices, shape.faces[::-1], np.zeros((len(shape.faces), 3, 2)), target.image)
    result = meshcorr.match(shape, target, refine=False)
    with pytest.raises(ParameterError, match="other triangles"):
        transfer_uv(result.precise_map(), other)


# ---------------------------------------------------------------- notebook


def test_notebook_view_renders_offscreen(figure_and_rigid_copy):
    pytest.importorskip("plotly")
    shape, copy, truth = figure_and_rigid_copy
    result = meshcorr.match(shape, copy, refine=False)
    figure = result.show()
    source_trace, target_trace = figure.data
    assert source_trace.type == target_trace.type == "mesh3d"
    # linked colours: each source vertex wears its image's colour
    np.testing.assert_array_equal(np.asarray(source_trace.vertexcolor), np.asarray(target_trace.vertexcolor)[truth])
    page = figure.to_html(include_plotlyjs=False, full_html=False)
    assert len(page) > 10_000 and "mesh3d" in page
    same = meshcorr.viz.show((shape.vertices, shape.faces), (copy.vertices, copy.faces), result.map)
    np.testing.assert_array_equal(np.asarray(same.data[0].vertexcolor), np.asarray(source_trace.vertexcolor))


def test_notebook_view_errors(figure_and_rigid_copy):
    pytest.importorskip("plotly")
    shape, copy, truth = figure_and_rigid_copy
    with pytest.raises(ParameterError, match="entries but the source mesh has"):
        meshcorr.viz.show(shape, copy, truth[:-1])
    with pytest.raises(ParameterError, match="one RGB row per target vertex"):
        meshcorr.viz.show(shape, copy, truth, colors=np.zeros((3, 3)))


def test_obj_with_uvs_but_no_image_is_refused(tmp_path):
    (tmp_path / "bare.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    with pytest.raises(MeshError, match="names no texture image"):
        read_textured_obj(tmp_path / "bare.obj")


def test_notebook_view_without_plotly_says_how_to_install_it(figure_and_rigid_copy, monkeypatch):
    shape, copy, truth = figure_and_rigid_copy
    monkeypatch.setitem(sys.modules, "plotly.graph_objects", None)
    with pytest.raises(ParameterError, match=r"pip install 'meshcorr\[notebook\]'"):
        meshcorr.viz.show(shape, copy, truth)


def test_correspondence_figure_takes_any_mesh_form(figure_and_rigid_copy, tmp_path):
    pytest.importorskip("matplotlib")
    from meshcorr.viz.figures import correspondence_figure

    shape, copy, truth = figure_and_rigid_copy
    info = correspondence_figure(shape, meshcorr.as_mesh(copy), truth, tmp_path / "f.png", truth=truth)
    assert info["mean_error"] == 0.0 and (tmp_path / "f.png").stat().st_size > 1000
