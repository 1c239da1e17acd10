"""linesurf.mesh: the MLS surface as (vertices, faces), as `linesurf mesh` writes it."""
import numpy as np
import pytest

import linesurf
from conftest import fibonacci_sphere


def test_mesh_of_a_sphere_is_closed_and_on_it():
    pts = fibonacci_sphere(4000, radius=1.0).astype(np.float32)
    vertices, faces = linesurf.mesh(linesurf.Model(points=pts, normals=pts))
    assert vertices.dtype == np.float32 and vertices.shape[1] == 3
    assert faces.dtype == np.int64 and faces.shape[1] == 3 and faces.max() < len(vertices)
    assert np.abs(np.linalg.norm(vertices, axis=1) - 1).max() < 0.01
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert np.all(counts == 2)  # closed and manifold
    assert len(vertices) - len(counts) + len(faces) == 2  # Euler characteristic of a sphere
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    assert np.all(np.sum(np.cross(b - a, c - a) * (a + b + c), axis=1) > 0)  # outward


def test_mesh_refuses_bad_input_and_budget():
    pts = fibonacci_sphere(1000).astype(np.float32)
    model = linesurf.Model(points=pts, normals=pts)
    with pytest.raises(ValueError, match="max_mb"):
        linesurf.mesh(model, max_mb=0.01)
    with pytest.raises(ValueError, match="cell_scale"):
        linesurf.mesh(model, cell_scale=0.1)
    with pytest.raises(ValueError, match="normals"):
        linesurf.mesh(linesurf.Model(points=pts))
    with pytest.raises(TypeError):
        linesurf.mesh(model, no_such_option=1)


def test_surface_error_reads_an_offset_and_a_mesh():
    """linesurf.surface_error: a sphere against itself moved out by d reads d, both ways."""
    pts = fibonacci_sphere(8000).astype(np.float32)
    cloud = linesurf.Model(points=pts, normals=pts)
    spacing = np.sqrt(4 * np.pi / 8000)
    d = 0.25 * spacing
    moved = linesurf.Model(points=pts * np.float32(1 + d), normals=pts)
    e = linesurf.surface_error(cloud, moved, samples=2000)
    assert e["reference"] == "cloud" and e["failures"] == 0
    assert e["from_reference"]["samples"] == 2000 and e["from_model"]["samples"] == 2000
    assert e["rms"] == pytest.approx(d, rel=0.03)
    assert e["rms_eps_ref"] == pytest.approx(e["rms"] / e["eps_ref"])
    assert e["eps_ref"] == pytest.approx(0.05 * e["reference_spacing"])
    # Against a mesh: the sphere's own mesh from its MLS surface, and its vertices as the model.
    vertices, faces = linesurf.mesh(cloud)
    mesh = linesurf.Mesh(vertices, faces)
    m = linesurf.surface_error(mesh, cloud)
    assert m["reference"] == "mesh" and m["failures"] == 0 and m["rms_eps_ref"] < 1.0
    with pytest.raises(ValueError, match="normals"):
        linesurf.surface_error(linesurf.Model(points=pts), moved)
    with pytest.raises(ValueError, match="samples"):
        linesurf.surface_error(cloud, moved, samples=10)
    with pytest.raises(TypeError):
        linesurf.surface_error(cloud, moved, no_such_option=1)
