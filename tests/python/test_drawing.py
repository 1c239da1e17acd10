"""render(style=...): the model's segments drawn as ink strokes (thesis §9.4, §9.5), as the CLI's
`render --style`; the default style keeps the splat image."""
import numpy as np
import pytest

import linesurf
from conftest import DATA


@pytest.fixture(scope="module")
def al_lines():
    return linesurf.extract_contour(linesurf.read_mesh(str(DATA / "al_mesh.ply"))).model


def test_hatch_draws_ink_on_paper_and_splat_stays_the_default(al_lines):
    splat = linesurf.render(al_lines, size=(96, 96))
    assert np.array_equal(splat, linesurf.render(al_lines, size=(96, 96), style="splat", stroke_width=3))
    hatch = linesurf.render(al_lines, size=(96, 96), style="hatch", paper="#ffffff", ink=(0.1, 0.1, 0.3))
    assert hatch.shape == (96, 96, 4)
    rgb = hatch[..., :3].astype(int)
    assert (rgb.min(axis=2) > 250).mean() > 0.5  # mostly paper
    assert (rgb[..., 2] - rgb[..., 0] > 20).sum() > 100  # the blue ink
    assert not np.array_equal(hatch, splat)


def test_drawing_keywords_are_checked(al_lines):
    for bad in (0, -1, float("nan"), 1e9):
        with pytest.raises(ValueError, match="stroke_width"):
            linesurf.render(al_lines, size=(32, 32), style="lines", stroke_width=bad)
    with pytest.raises(ValueError, match="style"):
        linesurf.render(al_lines, style="sketch")
    cloud = linesurf.read(str(DATA / "santa_points.ply"))
    with pytest.raises(ValueError, match="style"):
        linesurf.render(cloud, size=(32, 32), style="hatch", silhouettes=False)
