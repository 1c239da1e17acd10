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
import inspect as _inspect

from . import _linesurf
from ._linesurf import (  # noqa: F401
    FileFormatError,
    Mesh,
    Model,
    compare,
    difference_heatmap,
    estimate_noise,
    geometry,
    normals,
    read,
    read_image,
    read_mesh,
    set_threads,
    thread_count,
    lod_build,
    mls_project,
    verify,
    write,
    write_png,
)


def _keyword_function(name, positional, extras=()):
    """A Python function over the native ``_NAME(positional..., options, extras...)`` whose
    keyword-only parameters are the option tables' fields (``_NAME_options()``: keyword, default
    from the library's default instance, help), so that ``inspect.signature`` shows every option
    with its default and an unknown keyword is a TypeError. Only the keywords given are passed on:
    the library starts from its own defaults."""
    native = getattr(_linesurf, "_" + name)
    specs = getattr(_linesurf, "_" + name + "_options")()
    P = _inspect.Parameter
    params = [P(p, P.POSITIONAL_OR_KEYWORD) for p in positional]
    params += [P(s["keyword"], P.KEYWORD_ONLY, default=s["default"]) for s in specs]
    params += [P(k, P.KEYWORD_ONLY, default=v) for k, v in extras]
    signature = _inspect.Signature(params)
    option_names = {s["keyword"] for s in specs}

    def function(*args, **kwargs):
        given = signature.bind(*args, **kwargs).arguments
        options = {k: v for k, v in given.items() if k in option_names}
        rest = {k: v for k, v in given.items() if k not in option_names}
        return native(options=options, **rest)

    function.__name__ = function.__qualname__ = name
    function.__module__ = __name__
    function.__signature__ = signature
    doc = (native.__doc__ or "").strip()
    if doc.startswith("_" + name + "("):  # pybind11's own signature line
        doc = doc.split("\n", 1)[-1].strip()
    function.__doc__ = doc + "\n\nKeywords:\n" + "\n".join(
        "    {} = {!r}: {}".format(s["keyword"], s["default"], s["help"]) for s in specs)
    function.options = specs
    return function


render = _keyword_function("render", ["model"], [("depth", False), ("alpha", False), ("normal", False), ("budget", None)])
prepare = _keyword_function("prepare", ["model"])
extract_eps_delta = _keyword_function("extract_eps_delta", ["cloud"])
extract_shape_approx = _keyword_function("extract_shape_approx", ["cloud"])
extract_curvature_lines = _keyword_function("extract_curvature_lines", ["cloud"])
extract_features = _keyword_function("extract_features", ["cloud"])
extract_contour = _keyword_function("extract_contour", ["mesh"])
mesh = _keyword_function("mesh", ["model"], [("max_mb", 4096.0)])
surface_error = _keyword_function("surface_error", ["reference", "model"])

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
