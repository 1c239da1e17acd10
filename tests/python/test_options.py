"""The Python keywords against the option tables' other front ends: every render option that
`linesurf render --help` lists is a keyword of linesurf.render() with the same default and vice
versa, the viewer page's defaults equal the keywords' defaults, and the type stub lists the same
keywords. (tests/options/option_table_test.cpp checks the CLI and the page against the structs.)"""
import ast
import inspect
import json
import os
import re
from pathlib import Path

import pytest

import linesurf

ROOT = Path(os.environ.get("LINESURF_SOURCE_DIR", Path(__file__).resolve().parents[2]))
DATA = ROOT / "data"
OUTPUTS = {"depth", "alpha", "normal"}  # what render() returns, not options
CLI_ONLY = {"--views"}  # the CLI writes N views; render() returns one image
BACKGROUNDS = {"white": [1, 1, 1, 1], "black": [0, 0, 0, 1], "transparent": [0, 0, 0, 0]}
AXES = {"x": [1, 0, 0], "y": [0, 1, 0], "z": [0, 0, 1], "-x": [-1, 0, 0], "-y": [0, -1, 0], "-z": [0, 0, -1]}


def help_options(cli, command):
    """{flag: (default text or None, section, whether the flag is the option's own spelling)} of the
    option lines of `command --help`."""
    r = cli(*command.split(), "--help")
    assert r.returncode == 0, r.stderr
    out, section = {}, ""
    for line in r.stdout.splitlines():
        g = re.match(r"\[Option Group: (.*)\]", line)
        if g:
            section = g.group(1)
            continue
        m = re.match(r"\s*(-[^ ,\n]+(?:,-[^ ,\n]+)*)(?: ([^=\n]*?)(?:=(.*))?)?$", line)
        if not m:
            continue
        default = None
        if m.group(3) is not None:  # "TYPE=DEFAULT  help": three numbers for X Y Z, else one token
            default = " ".join(m.group(3).split()[:3 if m.group(2) == "X Y Z" else 1])
        spellings = [f for f in m.group(1).split(",") if f.startswith("--")]
        for flag in spellings:  # the first long spelling is the option's own, the others aliases
            out.setdefault(flag, (default, section, flag == spellings[0]))
    return out


def keyword_options(function):
    return {n: p.default for n, p in inspect.signature(function).parameters.items() if p.kind == p.KEYWORD_ONLY}


def same_default(py, text, flag):
    if isinstance(py, bool):
        return True  # flags: checked by the --no- spelling below
    if isinstance(py, (int, float)):
        return float(text) == pytest.approx(float(py), rel=1e-6)
    if isinstance(py, tuple):
        numbers = text.replace(" x 3", "").replace("x", " ").split()
        return [float(x) for x in numbers] == pytest.approx([float(x) for x in py], rel=1e-6)
    return text == str(py)


@pytest.mark.parametrize("function,command,skip_sections", [
    (linesurf.render, "render", {"mesh"}),
    (linesurf.extract_contour, "extract contour", set()),
    (linesurf.extract_eps_delta, "extract eps-delta", set()),
    (linesurf.extract_shape_approx, "extract shape-approx", set()),
])
def test_python_keywords_and_cli_flags_agree(cli, function, command, skip_sections):
    cli_options = help_options(cli, command)
    keywords = {k: v for k, v in keyword_options(function).items() if k not in OUTPUTS}
    assert "tail_layers" in keywords or command != "render"
    for kw, default in keywords.items():
        flag = "--" + kw.replace("_", "-")
        assert flag in cli_options, f"{command}: Python has {kw}, --help lacks {flag}"
        text = cli_options[flag][0]
        if isinstance(default, bool):
            if default:
                assert "--no-" + flag[2:] in cli_options, f"{command} {flag}: on by default, no way to turn it off"
            continue
        if default is None:
            continue  # resolved later (z_threshold by its mode) or not set (look-at camera)
        assert text is not None and same_default(default, text, flag), \
            f"{command} {flag}: CLI default {text!r}, Python {default!r}"
    # every table flag of the command is a keyword (the CLI's own flags live outside the groups)
    for flag, (_, section, own) in cli_options.items():
        if not own or not section or section in skip_sections or flag in CLI_ONLY or flag.startswith("--no-"):
            continue
        assert flag[2:].replace("-", "_") in keywords, f"{command}: --help lists {flag}, Python lacks it"


def test_viewer_defaults_equal_python_defaults(cli, tmp_path):
    page = tmp_path / "v.html"
    r = cli("-q", "view", DATA / "santa_points.ply", "-o", page)
    assert r.returncode == 0, r.stderr
    text = page.read_text()
    meta = json.loads(re.search(r'<script id="linesurf-meta"[^>]*>(.*?)</script>', text, re.S).group(1))
    keywords = keyword_options(linesurf.render)
    assert meta["defaults"], "the page carries the option tables' viewer fields"
    for field, value in meta["defaults"].items():
        kw = re.sub(r"([A-Z])", lambda m: "_" + m.group(1).lower(), field)
        assert kw in keywords, f"the viewer has {field}, Python lacks {kw}"
        py = keywords[kw]
        if py is None:  # z_threshold: the page blends per primitive, whose default it carries
            continue
        if isinstance(py, str):
            py = BACKGROUNDS.get(py) or AXES.get(py)
        if isinstance(py, (list, tuple)):
            assert list(value)[:len(py)] == pytest.approx([float(x) for x in py], rel=1e-6), field
        else:
            assert value == pytest.approx(py, rel=1e-6), field


def test_type_stub_lists_the_same_keywords():
    tree = ast.parse((ROOT / "python" / "linesurf" / "__init__.pyi").read_text())
    stubs = {f.name: f for f in tree.body if isinstance(f, ast.FunctionDef)}
    for name in ("render", "prepare", "extract_eps_delta", "extract_shape_approx", "extract_contour"):
        stub = [a.arg for a in stubs[name].args.kwonlyargs]
        assert stub == list(keyword_options(getattr(linesurf, name))), name
        assert all(isinstance(d, ast.Constant) and d.value is Ellipsis for d in stubs[name].args.kw_defaults), \
            f"{name}: the stub restates a default"


def test_defaults_come_from_the_library_and_unknown_keywords_are_refused():
    kw = keyword_options(linesurf.render)
    assert kw["tail_coverage"] == 1.0 and kw["tail_layers"] is True  # the library's defaults
    assert kw["fov"] == 30.0 and kw["azimuth"] == 30.0 and kw["elevation"] == 20.0
    with pytest.raises(TypeError):
        linesurf.render(linesurf.Model(points=[[0, 0, 0]]), no_such_option=1)
    assert "tail_coverage = 1.0" in linesurf.render.__doc__
