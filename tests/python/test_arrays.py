"""Round trips of every array type through Model/Mesh and through files; dtypes and layouts."""
import numpy as np
import pytest

import linesurf


def random_model(n=50, m=20, seed=0):
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 3))
    nrm = rng.normal(size=(n, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    seg = rng.normal(size=(m, 2, 3))
    d = seg[:, 1] - seg[:, 0]
    sn = np.cross(d, rng.normal(size=(m, 3)))
    sn /= np.linalg.norm(sn, axis=1, keepdims=True)
    en = np.stack([sn, -sn], axis=1)
    fields = dict(points=pts, normals=nrm, colors=rng.uniform(size=(n, 4)), radii=rng.uniform(0.1, 1, n),
                  segments=seg, segment_normals=sn, segment_colors=rng.uniform(size=(m, 4)),
                  segment_radii=rng.uniform(0.1, 1, m), segment_uv=rng.uniform(size=(m, 2, 2)),
                  segment_endpoint_normals=en)
    return fields, linesurf.Model(**fields)


def test_every_array_round_trips_in_memory():
    fields, model = random_model()
    for name, value in fields.items():
        got = getattr(model, name)
        assert got.dtype == np.float32, name
        assert got.shape == value.shape, name
        np.testing.assert_allclose(got, value.astype(np.float32), rtol=0, atol=0, err_msg=name)


@pytest.mark.parametrize("ascii", [False, True])
def test_every_array_round_trips_through_ply(tmp_path, ascii):
    fields, model = random_model()
    path = str(tmp_path / "m.ply")
    linesurf.write(path, model, ascii=ascii)
    back = linesurf.read(path)
    for name, value in fields.items():
        got = getattr(back, name)
        if name == "segment_endpoint_normals" and got is None:
            continue  # checked separately below
        assert got is not None, name
        atol = 0.5 / 255 + 1e-6 if "color" in name else 1e-6  # PLY stores colours as uchar
        np.testing.assert_allclose(got, value.astype(np.float32), rtol=1e-6, atol=atol, err_msg=name)


def test_endpoint_normals_through_ply(tmp_path):
    fields, model = random_model()
    linesurf.write(str(tmp_path / "e.ply"), model)
    back = linesurf.read(str(tmp_path / "e.ply"))
    if back.segment_endpoint_normals is None:
        pytest.skip("this build's PLY writer does not store endpoint normals")
    np.testing.assert_allclose(back.segment_endpoint_normals, fields["segment_endpoint_normals"], atol=1e-6)


def test_provenance_and_point_properties_read_back(tmp_path, igea):
    cloud = linesurf.Model(points=igea.points[:3000])
    r = linesurf.extract_eps_delta(cloud, provenance=True)
    linesurf.write(str(tmp_path / "h.ply"), r.model)
    back = linesurf.read(str(tmp_path / "h.ply"))
    assert len(back.provenance) == r.stats["segments"] > 0
    for a, b in zip(back.provenance, r.model.provenance):
        np.testing.assert_array_equal(a, b)


def test_mesh_round_trip(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    f = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    n = v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-9)
    c = np.random.default_rng(1).uniform(size=(4, 4))
    mesh = linesurf.Mesh(v, f, normals=n, colors=c)
    for ext in ("ply", "obj"):
        path = str(tmp_path / f"t.{ext}")
        linesurf.write(path, mesh)
        back = linesurf.read_mesh(path)
        np.testing.assert_allclose(back.vertices, v, atol=1e-6)
        np.testing.assert_array_equal(back.faces, f)
        np.testing.assert_allclose(back.normals, n, atol=1e-5)
        if ext == "ply":
            np.testing.assert_allclose(back.colors, c, atol=1 / 255)


def test_mesh_uv_from_obj(tmp_path):
    (tmp_path / "q.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n")
    mesh = linesurf.read_mesh(str(tmp_path / "q.obj"))
    np.testing.assert_allclose(mesh.uv, [[[0, 0], [1, 0], [0, 1]]])


@pytest.mark.parametrize("layout", ["c32", "c64", "f32", "f64", "strided", "list"])
def test_points_accepted_in_any_layout(layout):
    base = np.random.default_rng(2).normal(size=(40, 3))
    arr = {"c32": base.astype(np.float32), "c64": base, "f32": np.asfortranarray(base.astype(np.float32)),
           "f64": np.asfortranarray(base), "strided": np.repeat(base, 2, axis=0)[::2],
           "list": base.tolist()}[layout]
    model = linesurf.Model(points=arr)
    np.testing.assert_allclose(model.points, base.astype(np.float32))


def test_setting_points_of_another_count_drops_attributes():
    _, model = random_model()
    model.points = np.zeros((7, 3))
    assert model.points.shape == (7, 3)
    assert model.normals is None and model.radii is None and model.colors is None


def test_outputs_are_copies():
    _, model = random_model()
    p = model.points
    p[:] = 0
    assert np.abs(model.points).sum() > 0


def test_point_masses_set_read_back_and_weigh(tmp_path):
    fields, model = random_model()
    assert model.point_masses is None
    n = len(fields["points"])
    masses = np.linspace(0.5, 2.0, n)
    model.point_masses = masses
    np.testing.assert_array_equal(model.point_masses, masses.astype(np.float32))
    assert model.point_properties.keys() == {"mass"}
    linesurf.write(str(tmp_path / "m.ply"), model)
    np.testing.assert_array_equal(linesurf.read(str(tmp_path / "m.ply")).point_masses, masses.astype(np.float32))
    for bad in ([1.0] * (n - 1), [0.0] * n, [-1.0] * n, [np.nan] * n, [1e7] * n):
        with pytest.raises(ValueError):
            model.point_masses = bad
    np.testing.assert_array_equal(model.point_masses, masses.astype(np.float32))  # unchanged by a refused set
    model.point_masses = None
    assert model.point_masses is None and "mass" not in model.point_properties


def test_uniform_masses_cancel_in_the_normalised_blend(santa_path):
    santa = linesurf.read(str(santa_path))
    plain = linesurf.render(santa, size=(96, 96))
    santa.point_masses = np.full(len(santa.points), 3.0)
    np.testing.assert_array_equal(linesurf.render(santa, size=(96, 96)), plain)  # every weight x3: the same blend
    santa.point_masses = np.where(np.arange(len(santa.points)) % 2 == 0, 0.2, 5.0)
    assert np.abs(linesurf.render(santa, size=(96, 96)) - plain).max() > 0.01


def test_a_model_of_points_keeps_the_normals_it_is_given():
    pts = np.eye(3, dtype=np.float32)
    m = linesurf.Model(points=pts, normals=pts)  # segment_normals left out: None must not clear them
    assert m.normals is not None and np.array_equal(m.normals, pts)
