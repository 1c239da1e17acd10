"""The module gives what the CLI gives: extraction counts, the certificate, rendered pixels
(byte for byte against the CLI's PNG) and image metrics."""
import json
import math

import numpy as np
import pytest

import linesurf
from conftest import DATA


@pytest.fixture(scope="module")
def santa():
    return linesurf.read(str(DATA / "santa_points.ply"))


def test_eps_delta_counts_and_model_equal_cli(cli, tmp_path, santa):
    out = tmp_path / "ed.ply"
    r = cli("-q", "extract", "eps-delta", DATA / "santa_points.ply", "-o", out, "--delta", "0.01")
    assert r.returncode == 0, r.stderr
    ref = linesurf.read(str(out))
    got = linesurf.extract_eps_delta(santa, delta=0.01)
    assert got.stats["segments"] == len(ref.segments) > 0
    assert got.stats["kept_points"] == len(ref.points)
    np.testing.assert_array_equal(got.model.segments, ref.segments)
    np.testing.assert_array_equal(got.model.points, ref.points)


@pytest.mark.parametrize("method", ["greedy", "hierarchical"])
def test_shape_approx_counts_equal_cli(cli, tmp_path, santa, method):
    out = tmp_path / "sa.ply"
    r = cli("-q", "extract", "shape-approx", DATA / "santa_points.ply", "-o", out, "--method", method)
    assert r.returncode == 0, r.stderr
    ref = linesurf.read(str(out))
    got = linesurf.extract_shape_approx(santa, method=method)
    assert got.stats["segments"] == len(ref.segments) > 0
    assert got.stats["points_kept"] == len(ref.points)
    np.testing.assert_array_equal(got.model.segments, ref.segments)
    assert got.labels.shape == (len(santa.points),) and got.labels.max() + 1 == got.stats["clusters"]


def test_curvature_lines_equal_cli(cli, tmp_path, santa):
    out = tmp_path / "cl.ply"
    r = cli("-q", "extract", "curvature-lines", DATA / "santa_points.ply", "-o", out, "--family", "max")
    assert r.returncode == 0, r.stderr
    ref = linesurf.read(str(out))
    got = linesurf.extract_curvature_lines(santa, family="max")
    assert got.stats["segments"] == len(ref.segments) > 0
    assert got.stats["kept_points"] == len(ref.points)
    assert got.stats["lines"] > 0 and 0 < got.stats["data_reduction"] < got.stats["chain_data_reduction"]
    np.testing.assert_array_equal(got.model.segments, ref.segments)
    np.testing.assert_array_equal(got.model.points, ref.points)


def test_contour_counts_equal_cli(cli, tmp_path):
    out = tmp_path / "c.ply"
    r = cli("-q", "extract", "contour", DATA / "al_mesh.ply", "-o", out, "--points-below", "0.01")
    assert r.returncode == 0, r.stderr
    ref = linesurf.read(str(out))
    got = linesurf.extract_contour(linesurf.read_mesh(str(DATA / "al_mesh.ply")), points_below=0.01)
    assert got.stats["segments"] == len(ref.segments) > 0 and got.stats["points"] == len(ref.points)
    np.testing.assert_array_equal(got.model.segments, ref.segments)
    # the points' masses (docs/decisions.md "Point masses") are the CLI's too, and off on request on
    # both routes
    np.testing.assert_array_equal(got.model.point_masses, ref.point_masses)
    assert got.model.point_properties.keys() == {"mass"}
    r = cli("-q", "extract", "contour", DATA / "al_mesh.ply", "-o", out, "--points-below", "0.01", "--no-point-masses")
    assert r.returncode == 0, r.stderr
    unit = linesurf.extract_contour(linesurf.read_mesh(str(DATA / "al_mesh.ply")), points_below=0.01,
                                    point_masses=False)
    assert linesurf.read(str(out)).point_masses is None and unit.model.point_masses is None


def test_contour_diagonal_cap_equals_cli(cli, tmp_path):
    # Al is coarse (mean edge = diagonal / 52): the default d is the diagonal / 200; without the
    # cap (0) it is the mean edge, ~3.9x larger, and both routes agree on either.
    mesh = linesurf.read_mesh(str(DATA / "al_mesh.ply"))
    capped = linesurf.extract_contour(mesh)
    edge = linesurf.extract_contour(mesh, diagonal_divisions=0)
    assert capped.stats["spacing_from_diagonal"] and not edge.stats["spacing_from_diagonal"]
    assert edge.stats["spacing"] == pytest.approx(edge.stats["mean_edge_length"])
    assert 3.5 < edge.stats["spacing"] / capped.stats["spacing"] < 4.2
    out = tmp_path / "c0.ply"
    assert cli("-q", "extract", "contour", DATA / "al_mesh.ply", "-o", out, "--diagonal-divisions", "0").returncode == 0
    np.testing.assert_array_equal(edge.model.segments, linesurf.read(str(out)).segments)


def test_certificate_check_agrees_with_cli(cli, tmp_path, santa):
    out = tmp_path / "p.ply"
    assert cli("-q", "extract", "eps-delta", DATA / "santa_points.ply", "-o", out, "--provenance").returncode == 0
    assert cli("-q", "verify-extraction", DATA / "santa_points.ply", out).returncode == 0
    report = linesurf.verify(santa, linesurf.read(str(out)))
    assert report["ok"] and report["segments"] > 0 and report["missing"] == 0
    # The surface error line: the same figures as surface_error() on the oriented cloud.
    text = cli("verify-extraction", DATA / "santa_points.ply", out).stdout
    line = next(l for l in text.splitlines() if l.startswith("surface"))
    surface = report["surface_error"]
    assert f"= {surface['rms_eps_ref']:.3g} / {surface['p99_eps_ref']:.3g} / {surface['max_eps_ref']:.3g} x eps_ref" in line
    assert surface["failures"] == 0 and surface["rms_eps_ref"] < 1.0
    assert linesurf.verify(santa, linesurf.read(str(out)), surface_error=False)["surface_error"] is None
    # A tampered model fails in both.
    bad = linesurf.read(str(out))
    seg = bad.segments
    seg[0] += 10 * report["epsilon"] * np.array([0, 0, 1.0])
    bad.segments = seg
    linesurf.write(str(tmp_path / "bad.ply"), bad)
    assert not linesurf.verify(santa, bad)["ok"]
    assert cli("-q", "verify-extraction", DATA / "santa_points.ply", tmp_path / "bad.ply").returncode == 3


CAMERAS = [
    (["--size", "160x120", "--azimuth", "40", "--elevation", "10"], dict(size=(160, 120), azimuth=40, elevation=10)),
    (["--size", "96x128", "--eye", "0", "0", "2", "--target", "0", "0", "0", "--fov", "40", "--background", "transparent",
      "--up-axis", "z"],
     dict(size=(96, 128), eye=(0, 0, 2), target=(0, 0, 0), fov=40, background="transparent", up_axis="z")),
    (["--size", "128x128", "--z-threshold-mode", "fixed", "--layers", "2", "--per-pixel-lighting", "--zoom", "1.5"],
     dict(size=(128, 128), z_threshold_mode="fixed", layers=2, per_pixel_lighting=True, zoom=1.5)),
    (["--size", "128x96", "--coverage-gain", "1.5", "--prefilter", "1"], dict(size=(128, 96), coverage_gain=1.5, prefilter_variance=1)),
    (["--size", "128x96", "--coverage-gain", "1.5", "--coverage-reach", "0"], dict(size=(128, 96), coverage_gain=1.5, coverage_reach=0)),
    (["--size", "128x96", "--tail-coverage", "1"], dict(size=(128, 96), tail_coverage=1)),
]


@pytest.mark.parametrize("args,kwargs", CAMERAS)
def test_render_byte_equal_to_cli_png(cli, tmp_path, santa, args, kwargs):
    png = tmp_path / "r.png"
    r = cli("-q", "render", DATA / "santa_points.ply", "-o", png, *args)
    assert r.returncode == 0, r.stderr
    ref = linesurf.read_image(str(png))  # RGB PNGs read back with alpha 255
    got = linesurf.render(santa, **kwargs)
    assert got.dtype == np.uint8 and got.shape == ref.shape
    assert np.array_equal(got, ref)


def test_render_buffers_match_cli(cli, tmp_path, santa):
    png, alpha = tmp_path / "r.png", tmp_path / "a.png"
    assert cli("-q", "render", DATA / "santa_points.ply", "-o", png, "--size", "64x48", "--alpha-out", alpha).returncode == 0
    got = linesurf.render(santa, size=(64, 48), alpha=True, depth=True, normal=True)
    assert np.array_equal(got["color"], linesurf.read_image(str(png)))
    a8 = np.round(np.clip(got["alpha"], 0, 1) * 255).astype(np.uint8)
    assert np.array_equal(a8, linesurf.read_image(str(alpha))[..., 0])
    assert got["depth"].shape == (48, 64) and got["normal"].shape == (48, 64, 3)
    covered = got["alpha"] > 0.5
    assert np.all(got["depth"][covered] > 0)


def test_compare_equals_cli(cli, tmp_path, santa):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert cli("-q", "render", DATA / "santa_points.ply", "-o", a, "--size", "100x100").returncode == 0
    assert cli("-q", "render", DATA / "santa_points.ply", "-o", b, "--size", "100x100", "--azimuth", "33").returncode == 0
    r = cli("compare", a, b, "--json")
    assert r.returncode == 0, r.stderr
    ref = json.loads(r.stdout)
    for got in (linesurf.compare(str(a), str(b)),
                linesurf.compare(linesurf.read_image(str(a)), linesurf.read_image(str(b))),
                linesurf.compare(linesurf.render(santa, size=(100, 100)), linesurf.render(santa, size=(100, 100), azimuth=33))):
        for key in ("mse", "psnr", "nccm", "ssim", "mean_abs_diff", "std_abs_diff", "max_abs_diff", "differing_pixels"):
            assert got[key] == ref[key], key
        assert got["holes"] == ref["holes"]["pixels"] and got["extra_pixels"] == ref["holes"]["extra_pixels"]
    same = linesurf.compare(str(a), str(a))
    assert math.isinf(same["psnr"]) and same["mse"] == 0
