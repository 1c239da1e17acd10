"""§6.1 geometry through Python: normals of an analytic sphere, neighbours, curvature, spacing."""
import numpy as np
import pytest

import linesurf
from conftest import fibonacci_sphere


def test_sphere_normals_within_one_degree_and_outward():
    pts = fibonacci_sphere(20000, radius=2.0) + [0.3, -0.2, 0.1]
    n = linesurf.normals(pts, k=12)
    exact = (pts - [0.3, -0.2, 0.1]) / 2.0
    cos = np.sum(n * exact, axis=1)
    assert n.shape == (20000, 3) and n.dtype == np.float32
    assert np.all(cos > np.cos(np.radians(1.0))), np.degrees(np.arccos(cos.min()))


def test_neighbours_match_brute_force():
    pts = np.random.default_rng(3).uniform(size=(300, 3))
    idx, dist = linesurf.neighbours(pts, k=8)
    d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
    np.fill_diagonal(d, np.inf)
    np.testing.assert_allclose(dist, np.sort(d, axis=1)[:, :8], rtol=1e-5)
    np.testing.assert_allclose(np.take_along_axis(d, idx, axis=1), dist, rtol=1e-5)


def test_sphere_curvature_and_spacing():
    pts = fibonacci_sphere(6000, radius=2.0)
    kmin, kmax, dmin, dmax = linesurf.curvature(pts, k=12, curvature_fit="quadric")
    assert abs(np.median(kmin) - 0.5) < 0.01 and abs(np.median(kmax) - 0.5) < 0.01  # 1 / radius
    assert dmin.shape == (6000, 3)
    s, avg = linesurf.spacing(pts, k=6)
    assert s.shape == (6000,) and abs(avg - s.mean()) < 1e-3 * avg
    # Fibonacci points on a sphere of area A: spacing ~ sqrt(A / n)
    assert 0.5 < avg / np.sqrt(4 * np.pi * 4 / 6000) < 2


def test_geometry_namespace_fields():
    g = linesurf.geometry(fibonacci_sphere(500), k=10, delaunay_neighbours=True)
    assert g.neighbours.shape == (500, 10) and g.normals.shape == (500, 3)
    assert g.delaunay_offsets.shape == (501,) and g.delaunay_indices.shape[0] == g.delaunay_offsets[-1]
    assert g.flags.dtype == np.uint8 and g.surface_variation.shape == (500,)


def test_prepare_adds_normals_and_radii(igea):
    p = linesurf.prepare(igea)
    assert igea.normals is None  # the input is not changed
    assert p.normals.shape == igea.points.shape and p.radii.shape == (len(igea.points),)
    assert np.all(p.radii > 0)


def test_orient_chooses_each_components_side():
    pts = fibonacci_sphere(5000, radius=1.0)
    outward = np.sum(linesurf.normals(pts) * pts, axis=1)
    assert np.all(outward > 0)  # auto: a closed object faces outward
    inward = np.sum(linesurf.normals(pts, orient="towards", viewpoint=(0.1, 0, 0)) * pts, axis=1)
    assert np.all(inward < 0)  # a room seen from its scanner faces the scanner
    rng = np.random.default_rng(5)
    sheet = np.column_stack([rng.uniform(0, 10, 4000), rng.uniform(0, 10, 4000), rng.normal(0, 0.01, 4000)])
    assert np.all(linesurf.normals(sheet)[:, 2] > 0)  # terrain faces up
    assert np.all(linesurf.normals(sheet, orient="away-from", viewpoint=(5, 5, 3))[:, 2] < 0)
    for bad in [dict(orient="sideways"), dict(orient="towards", viewpoint=(0, 0)), dict(viewpoint=(0, float("nan"), 0))]:
        with pytest.raises(ValueError):
            linesurf.normals(pts, **bad)


def test_mls_projection_lands_on_a_sphere():
    pts = fibonacci_sphere(8000, radius=1.0)
    model = linesurf.Model(points=pts, normals=pts)
    rng = np.random.default_rng(3)
    q = fibonacci_sphere(200, radius=1.0) * (1 + 0.02 * rng.standard_normal((200, 1)))
    r = linesurf.mls_project(model, q, curvature=True)
    assert r.converged.all()
    assert np.abs(np.linalg.norm(r.points, axis=1) - 1).max() < 5e-3  # IMLS: within 0.13 spacing
    assert np.all(np.sum(r.normals * r.points, axis=1) > 0.999)
    assert np.abs(np.median(r.k_max) - 1) < 0.05 and np.abs(np.median(r.k_min) - 1) < 0.05
    with pytest.raises(ValueError):
        linesurf.mls_project(model, q, support_scale=0.5)


def test_estimate_noise_reads_the_noise_along_the_normals():
    n = 20000
    pts = fibonacci_sphere(n)
    spacing = np.sqrt(4 * np.pi / n)
    rng = np.random.default_rng(4)
    noisy = pts + pts * (0.5 * spacing * rng.standard_normal(n))[:, None].astype(np.float32)
    e = linesurf.estimate_noise(noisy)
    assert abs(e.sigma / (0.5 * spacing) - 1) < 0.2, e.sigma / spacing
    assert e.lower_quartile <= e.sigma <= e.upper_quartile and e.fitted > 0.9 * e.samples
    assert linesurf.estimate_noise(pts).sigma < 0.02 * spacing  # curvature is not noise
    with pytest.raises(ValueError):
        linesurf.estimate_noise(pts, samples=3)


def test_render_warns_when_the_normals_face_away():
    pts = fibonacci_sphere(6000)
    with pytest.warns(UserWarning, match="back of its surface"):
        linesurf.render(linesurf.Model(points=pts, normals=-pts), size=(96, 96))
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        linesurf.render(linesurf.Model(points=pts, normals=pts), size=(96, 96))


def test_robust_projection_keeps_a_cube_edge():
    n = 30
    g = -1 + 2 * (np.arange(n) + 0.5) / n
    u, v = [a.ravel() for a in np.meshgrid(g, g)]
    faces = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            p = np.zeros((n * n, 3)); p[:, axis] = side
            p[:, (axis + 1) % 3], p[:, (axis + 2) % 3] = u, v
            nrm = np.zeros_like(p); nrm[:, axis] = side
            faces.append((p, nrm))
    pts = np.concatenate([f[0] for f in faces]).astype(np.float32)
    nrm = np.concatenate([f[1] for f in faces]).astype(np.float32)
    cube = linesurf.Model(points=pts, normals=nrm)
    q = np.stack([1 - np.linspace(0.01, 0.15, 20), np.zeros(20), np.ones(20)], axis=1)  # near the edge x = z = 1
    plain = linesurf.mls_project(cube, q)
    robust = linesurf.mls_project(cube, q, robust=True)
    assert plain.converged.all() and robust.converged.all()
    err = lambda r: np.degrees(np.arccos(np.clip(r.normals[:, 2], -1, 1)))  # off the face z = 1's normal
    assert err(robust).mean() < 0.3 * err(plain).mean(), (err(plain).mean(), err(robust).mean())


def test_extract_features_finds_a_cube_edges():
    n = 30
    g = -1 + 2 * (np.arange(n) + 0.5) / n
    u, v = [a.ravel() for a in np.meshgrid(g, g)]
    pts, nrm = [], []
    for axis in range(3):
        for side in (-1.0, 1.0):
            p = np.zeros((n * n, 3)); p[:, axis] = side
            p[:, (axis + 1) % 3], p[:, (axis + 2) % 3] = u, v
            q = np.zeros_like(p); q[:, axis] = side
            pts.append(p), nrm.append(q)
    cube = linesurf.Model(points=np.concatenate(pts).astype(np.float32), normals=np.concatenate(nrm).astype(np.float32))
    r = linesurf.extract_features(cube)
    seg = r.model.segments
    assert r.stats["segments"] == len(seg) > 0
    mid = (seg[:, 0] + seg[:, 1]) / 2  # (S, 2, 3) endpoints
    # On an edge two coordinates are +-1: the midpoints lie within 2 spacings of one.
    near_edge = np.sort(np.abs(np.abs(mid) - 1), axis=1)[:, 1] < 2 * (2 / n)
    assert near_edge.all()
    assert 0.8 * 24 < r.stats["length"] < 1.1 * 24  # twelve edges of length 2
    with pytest.raises(ValueError):
        linesurf.extract_features(cube, angle=1)
