"""Every error class on bad files and bad parameters, with the CLI's message; bad input never
crashes the interpreter."""
import numpy as np
import pytest

import linesurf
from conftest import DATA


def bad_files(tmp_path):
    (tmp_path / "truncated.ply").write_bytes(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nproperty float y\n"
        b"property float z\nend_header\n" + b"\0" * 17)
    (tmp_path / "garbage.ply").write_bytes(b"not a ply file at all\n")
    (tmp_path / "nan.xyz").write_text("0 0 0\n1 nan 2\n")
    return [tmp_path / "truncated.ply", tmp_path / "garbage.ply", tmp_path / "missing.ply"]


def test_bad_files_raise_oserror_with_the_cli_message(cli, tmp_path):
    for path in bad_files(tmp_path):
        with pytest.raises(OSError) as e:
            linesurf.read(str(path))
        r = cli("normals", path, "-o", tmp_path / "out.ply")
        assert r.returncode == 2, r.stderr
        assert str(e.value) == r.stderr.strip()
        assert "\n" not in str(e.value)
    with pytest.raises(linesurf.FileFormatError):
        linesurf.read(str(tmp_path / "garbage.ply"))
    with pytest.raises(OSError):
        linesurf.read_image(str(tmp_path / "garbage.ply"))
    with pytest.raises(OSError):
        linesurf.read_mesh(str(tmp_path / "truncated.ply"))


# (Python call, CLI arguments, CLI flag) for one bad value each: same message, named as typed.
PARAMS = [
    (lambda m: linesurf.render(m, fov=200), ["render", "{model}", "--fov", "200"], "--fov", "fov"),
    (lambda m: linesurf.render(m, z_threshold=float("nan")), ["render", "{model}", "--z-threshold", "nan"],
     "--z-threshold", "z_threshold"),
    (lambda m: linesurf.render(m, prefilter_variance=-1), ["render", "{model}", "--prefilter-variance", "-1"],
     "--prefilter-variance", "prefilter_variance"),
    (lambda m: linesurf.render(m, alpha_override=2), ["render", "{model}", "--alpha-override", "2"],
     "--alpha-override", "alpha_override"),
    (lambda m: linesurf.render(m, coverage_gain=-1), ["render", "{model}", "--coverage-gain", "-1"],
     "--coverage-gain", "coverage_gain"),
    (lambda m: linesurf.render(m, tail_coverage=-1), ["render", "{model}", "--tail-coverage", "-1"],
     "--tail-coverage", "tail_coverage"),
    (lambda m: linesurf.render(m, coverage_reach=17), ["render", "{model}", "--coverage-reach", "17"],
     "--coverage-reach", "coverage_reach"),
    (lambda m: linesurf.render(m, zoom=float("nan")), ["render", "{model}", "--zoom", "nan"], "--zoom", "zoom"),
    (lambda m: linesurf.render(m, size=(0, 10)), ["render", "{model}", "--size", "0x10"], "--size", "size"),
    (lambda m: linesurf.render(m, up_axis="w"), ["render", "{model}", "--up-axis", "w"], "--up-axis", "up_axis"),
    (lambda m: linesurf.render(m, radius_scale=float("inf")), ["render", "{model}", "--radius-scale", "inf"],
     "--radius-scale", "radius_scale"),
    (lambda m: linesurf.extract_eps_delta(m, delta=float("nan")), ["extract", "eps-delta", "{model}", "--delta", "nan"],
     "--delta", "delta"),
    (lambda m: linesurf.extract_eps_delta(m, k=2), ["extract", "eps-delta", "{model}", "-k", "2"], "--k", "k"),
    (lambda m: linesurf.extract_shape_approx(m, delta_n=3), ["extract", "shape-approx", "{model}", "--delta-n", "3"],
     "--delta-n", "delta_n"),
    (lambda m: linesurf.extract_shape_approx(m, min_cluster_size=1),
     ["extract", "shape-approx", "{model}", "--min-cluster-size", "1"], "--min-cluster-size", "min_cluster_size"),
    (lambda m: linesurf.normals(m, orientation_penalty=float("nan")),
     ["normals", "{model}", "--orientation-penalty", "nan"], "--orientation-penalty", "orientation_penalty"),
]


@pytest.mark.parametrize("call,args,flag,keyword", PARAMS, ids=[p[3] for p in PARAMS])
def test_bad_parameters_raise_valueerror_with_the_cli_message(cli, tmp_path, call, args, flag, keyword):
    model = str(DATA / "santa_points.ply")
    with pytest.raises(ValueError) as e:
        call(linesurf.read(model))
    r = cli(*[a.format(model=model) for a in args], "-o", tmp_path / "o.ply")
    assert r.returncode == 1, r.stderr
    line = r.stderr.strip()
    assert line.startswith(flag + ": "), line
    assert str(e.value) == keyword + line[len(flag):]


def test_contour_bad_parameter_message(cli, tmp_path):
    mesh = linesurf.read_mesh(str(DATA / "al_mesh.ply"))
    with pytest.raises(ValueError) as e:
        linesurf.extract_contour(mesh, family_switch_sine=2)
    r = cli("extract", "contour", DATA / "al_mesh.ply", "-o", tmp_path / "c.ply", "--family-switch-sine", "2")
    assert r.returncode == 1 and r.stderr.strip() == "--family-switch-sine" + str(e.value)[len("family_switch_sine"):]


GOOD = np.random.default_rng(0).normal(size=(100, 3))


@pytest.mark.parametrize("bad,exc", [
    (np.array([["a", "b", "c"]]), TypeError),                 # strings
    (np.array([[1 + 2j, 0, 0]]), TypeError),                  # complex
    (np.array([[object(), 1, 2]], dtype=object), TypeError),  # objects
    (np.zeros((5, 2)), ValueError),                           # wrong shape
    (np.zeros((5, 3, 1)), ValueError),
    (np.zeros(3), ValueError),
    (np.array([[0, 0, np.nan]] * 5), ValueError),             # NaN
    (np.array([[0, 0, np.inf]] * 5), ValueError),
    ("not an array", TypeError),
    (None, TypeError),
])
def test_bad_arrays_raise(bad, exc):
    calls = [linesurf.normals, linesurf.render, lambda a: linesurf.extract_eps_delta(a)]
    if bad is not None:  # Model(points=None) is an empty model
        calls.append(lambda a: linesurf.Model(points=a))
    for f in calls:
        with pytest.raises(exc):
            f(bad)


def test_bad_attribute_arrays_raise():
    m = linesurf.Model(points=GOOD)
    with pytest.raises(ValueError, match="normals: has 99 rows for 100 points"):
        m.normals = GOOD[:99]
    with pytest.raises(ValueError):
        m.colors = np.zeros((100, 5))
    with pytest.raises(ValueError):
        m.radii = np.full(100, np.nan)
    with pytest.raises(ValueError):
        linesurf.Mesh(GOOD[:3], [[0, 1, 5]])
    with pytest.raises(ValueError):
        linesurf.Mesh(GOOD[:3], [[0, 1]])


def test_empty_inputs_never_crash():
    empty = np.zeros((0, 3))
    for f in (lambda: linesurf.normals(empty), lambda: linesurf.geometry(empty),
              lambda: linesurf.extract_eps_delta(empty), lambda: linesurf.extract_shape_approx(empty),
              lambda: linesurf.spacing(empty)):
        try:
            f()
        except ValueError:
            pass
    with pytest.raises(ValueError, match="model: holds no points and no segments"):
        linesurf.render(empty)
    with pytest.raises(ValueError):
        linesurf.compare(np.zeros((0, 0, 3), np.uint8), np.zeros((0, 0, 3), np.uint8))
    m = linesurf.Model()
    assert len(m) == 0 and m.points.shape == (0, 3) and m.segments.shape == (0, 2, 3)


def test_huge_sizes_raise():
    with pytest.raises(ValueError):
        linesurf.render(GOOD, size=(100000, 100000))
    with pytest.raises(ValueError, match="^size: "):  # a bad parameter, named, not an overflow
        linesurf.render(GOOD, size=(2 ** 40, 1))
    with pytest.raises(ValueError):
        linesurf.normals(GOOD, k=10 ** 9)
    with pytest.raises((ValueError, TypeError, OverflowError)):
        linesurf.normals(GOOD, k=2 ** 40)
    with pytest.raises(ValueError):
        linesurf.set_threads(10 ** 6)
    with pytest.raises(ValueError):
        linesurf.compare(np.zeros((2, 2, 3), np.uint8), np.zeros((3, 2, 3), np.uint8))
    with pytest.raises(ValueError):
        linesurf.render(GOOD, z_threshold_mode="bogus")
