"""linesurf: surface modelling and rendering with line segments, from Python.

numpy arrays in and out; keyword options named after the library's option structs
(``zThreshold`` -> ``z_threshold``); errors are ``ValueError`` (bad parameters) or
``FileFormatError`` / ``OSError`` (bad files) carrying the CLI's one-line message; long calls
release the GIL.

    import linesurf
    cloud = linesurf.read("data/igea_points.ply")
    cloud.normals = linesurf.normals(cloud, k=12)
    hybrid = linesurf.extract_eps_delta(cloud, delta=0.004).model
    image = linesurf.render(hybrid, size=(512, 512), azimuth=30, elevation=20)   # (512, 512, 4) uint8
    print(linesurf.compare(image, linesurf.render(cloud))["psnr"])
"""
from ._linesurf import (  # noqa: F401
    FileFormatError,
    Mesh,
    Model,
    compare,
    difference_heatmap,
    extract_contour,
    extract_eps_delta,
    extract_shape_approx,
    geometry,
    normals,
    prepare,
    read,
    read_image,
    read_mesh,
    render,
    set_threads,
    thread_count,
    verify,
    write,
    write_png,
)

__version__ = "0.1.0"


def neighbours(points, k=12):
    """The k nearest neighbours of every point (thesis §6.1 stage 1): (indices (N, k) int64,
    nearest first, -1 padded; distances (N, k) float32)."""
    g = geometry(points, k=k, orient_normals=False)
    return g.neighbours, g.neighbour_distances


def curvature(points, k=12, curvature_fit="taubin", **options):
    """Principal curvatures (thesis §6.1.2): (k_min (N,), k_max (N,), min direction (N, 3),
    max direction (N, 3)); positive where the surface bends away from its normal."""
    g = geometry(points, k=k, curvature=True, curvature_fit=curvature_fit, **options)
    return g.k_min, g.k_max, g.min_curvature_dir, g.max_curvature_dir


def spacing(points, k=12):
    """Mean distance of every point to its k nearest neighbours (N,) and its average over the
    cloud (thesis §6.1 stage 5)."""
    g = geometry(points, k=k, orient_normals=False)
    return g.spacing, g.average_spacing
