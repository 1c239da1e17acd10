"""Runs the README's Python snippet as a reader would (from a folder holding the bundled `data`)
and checks what it prints: the hybrid's default render lines up with its cloud's, PSNR >= 35 dB.
Usage: python_snippet_test.py SOURCE_DIR (with the module on PYTHONPATH)."""
import contextlib
import io
import os
import re
import sys
import tempfile


def main(source_dir):
    text = open(os.path.join(source_dir, "README.md"), encoding="utf-8").read()
    blocks = re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)
    if len(blocks) != 1:
        print(f"README.md: expected one ```python block, found {len(blocks)}", file=sys.stderr)
        return 1
    out = io.StringIO()
    with tempfile.TemporaryDirectory() as work:
        os.symlink(os.path.join(source_dir, "data"), os.path.join(work, "data"))
        cwd = os.getcwd()
        os.chdir(work)
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(blocks[0], "README.md (python block)", "exec"), {"__name__": "__main__"})
        finally:
            os.chdir(cwd)
    printed = out.getvalue()
    print(printed, end="")
    m = re.search(r"psnr ([0-9.]+) dB", printed)
    if not m:
        print("the snippet did not print 'psnr X dB'", file=sys.stderr)
        return 1
    if float(m.group(1)) < 35:
        print(f"the hybrid's default render is {m.group(1)} dB from its cloud's (need >= 35): "
              "do they share the default camera?", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
