"""The Python example runs and writes its side-by-side picture."""
import importlib.util

import linesurf
from conftest import DATA, SOURCE_DIR


def test_python_example_writes_side_by_side(tmp_path, capsys):
    spec = importlib.util.spec_from_file_location("hybrid_example", SOURCE_DIR / "examples" / "python" / "hybrid_example.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    out = tmp_path / "side.png"
    example.main(str(DATA / "santa_points.ply"), str(out))
    img = linesurf.read_image(str(out))
    assert img.shape == (512, 3 * 512, 4)
    printed = capsys.readouterr().out
    assert "segments" in printed and "psnr" in printed
