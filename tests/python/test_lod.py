"""Level-of-detail hierarchies from Python: lod_build and render(path, budget=) against the CLI and
against the plain model."""
import json
import re
import struct
import warnings

import numpy as np
import pytest

import linesurf


@pytest.fixture(scope="module")
def hybrid(igea):
    cloud = linesurf.prepare(igea)
    return linesurf.extract_eps_delta(cloud, delta=0.004).model


def test_full_budget_draws_the_model_and_half_stays_close(hybrid, tmp_path):
    path = tmp_path / "igea.lod"
    rep = linesurf.lod_build(hybrid, str(path))
    assert rep["primitives"] == len(hybrid)
    assert rep["nodes"] >= rep["leaves"] >= 1 and path.stat().st_size == rep["bytes"]
    plain = linesurf.render(hybrid, size=(256, 256))
    full = linesurf.render(path, size=(256, 256))  # a PathLike; no budget: every leaf
    assert np.array_equal(full, plain)
    assert np.array_equal(linesurf.render(str(path), size=(256, 256), budget=len(hybrid)), plain)
    half = linesurf.render(str(path), size=(256, 256), budget=len(hybrid) // 2)
    assert linesurf.compare(plain, half)["ssim"] >= 0.95
    assert not np.array_equal(half, plain)


def test_same_bytes_as_the_cli(hybrid, tmp_path, cli):
    model = tmp_path / "h.ply"
    linesurf.write(str(model), hybrid)
    assert cli("lod", "build", str(model), "-o", str(tmp_path / "cli.lod")).returncode == 0
    linesurf.lod_build(linesurf.read(str(model)), str(tmp_path / "py.lod"))
    assert (tmp_path / "cli.lod").read_bytes() == (tmp_path / "py.lod").read_bytes()


def test_bad_arguments(hybrid, tmp_path):
    with pytest.raises(ValueError, match="budget"):
        linesurf.render(hybrid, budget=1000)  # a budget needs a hierarchy
    with pytest.raises(ValueError, match="leaf"):
        linesurf.lod_build(hybrid, str(tmp_path / "x.lod"), leaf_size=1)
    assert not (tmp_path / "x.lod").exists()
    plain = tmp_path / "plain.lod"
    linesurf.write(str(tmp_path / "plain.ply"), hybrid)
    plain.write_bytes((tmp_path / "plain.ply").read_bytes())  # a PLY named .lod
    with pytest.raises(linesurf.FileFormatError, match="level-of-detail"):
        linesurf.render(str(plain))


def test_a_truncated_hierarchy_draws_the_rest_and_warns(hybrid, tmp_path):
    path = tmp_path / "t.lod"
    linesurf.lod_build(hybrid, str(path), leaf_size=1024)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) - 4096])  # the last blocks (the coarsest nodes, the root last) are cut
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        img = linesurf.render(str(path), size=(128, 128), budget=1000)  # the coarse nodes are drawn
    assert any("node" in str(w.message) for w in caught)
    assert img.shape == (128, 128, 4)


def test_meaningless_budgets_raise_value_error(hybrid, tmp_path):
    path = str(tmp_path / "m.lod")
    linesurf.lod_build(hybrid, path)
    for bad in [1.5, True, -1, 0, 2 ** 64, "10"]:
        with pytest.raises(ValueError, match="budget"):
            linesurf.render(path, size=(64, 64), budget=bad)


def _lie(data, kind):
    """The hierarchy's bytes with one lie told (the layout: docs/file-format.md)."""
    d = bytearray(data)
    (jb,) = struct.unpack_from("<I", d, 12)
    (n,) = struct.unpack_from("<Q", d, 24)
    t = 32 + jb

    def rec(i):
        return t + 88 * i

    if kind == "count_root_2e26":  # its block size to match: more representatives than its children hold
        (segs,) = struct.unpack_from("<I", d, rec(0) + 76)
        struct.pack_into("<I", d, rec(0) + 72, 1 << 26)
        struct.pack_into("<Q", d, rec(0) + 16, 32 + 64 * (1 << 26) + 100 * segs)
        return d
    if kind == "links_dag":  # a later inner node of the same level given the first one's children
        inner = [i for i in range(n) if not d[rec(i) + 86]]
        a, b = next((a, b) for a in inner for b in inner if b > a and d[rec(a) + 85] == d[rec(b) + 85])
        struct.pack_into("<I", d, rec(b) + 80, struct.unpack_from("<I", d, rec(a) + 80)[0])
        d[rec(b) + 84] = d[rec(a) + 84]
        return d
    header = json.loads(bytes(d[32:t]))
    if kind == "header_radius_0":
        header["sphere"]["radius"] = 0
    elif kind == "header_frame_scale_0":
        header["frame"]["scale"] = 0
    js = json.dumps(header, separators=(",", ":")).encode()
    js += b" " * (-(32 + len(js)) % 8)
    out = bytearray(d[:32]) + js + d[t:]
    struct.pack_into("<I", out, 12, len(js))
    for i in range(n):
        at = 32 + len(js) + 88 * i + 8
        struct.pack_into("<Q", out, at, struct.unpack_from("<Q", out, at)[0] + len(js) - jb)
    return out


@pytest.mark.parametrize("kind", ["count_root_2e26", "links_dag", "header_radius_0", "header_frame_scale_0"])
def test_a_damaged_hierarchy_is_refused_naming_the_file(hybrid, tmp_path, kind):
    good = tmp_path / "good.lod"
    linesurf.lod_build(hybrid, str(good), leaf_size=256)
    path = tmp_path / f"{kind}.lod"
    path.write_bytes(_lie(good.read_bytes(), kind))
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # refused, not drawn with warnings
        with pytest.raises(linesurf.FileFormatError, match=re.escape(str(path))) as e:
            linesurf.render(str(path), size=(32, 32), budget=5000)
    assert "\n" not in str(e.value)
