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
