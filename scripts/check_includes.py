#!/usr/bin/env python3
"""Checks the include structure of linesurf and reports its largest functions (docs/architecture.md).

Over src/, include/ and apps/ (or the tree given with --root):
  - include cycles between files, and between rooms (a room: a module's header and source of one
    name, e.g. src/render/coverage.cpp + src/render/coverage.h; simd_rows-inl.h is simd_rows's);
  - pairs of rooms that include each other;
  - includes from a lower module to a higher one (MODULE_ORDER, lowest first; apps is the top);
  - public headers (include/linesurf/...) that nothing but the tests includes;
  - the render core's size limits: no source file over MAX_RENDER_FILE_LINES lines and no function
    over MAX_RENDER_FUNCTION_LINES lines under src/render and include/linesurf/render;
and prints the counts, the longest functions of the library (src/, include/) and the render core's
file sizes. Exit status 1 when a rule above is broken, else 0.

Functions are found by a light scan (comments and strings removed, braces matched): a body is a
brace block after ')' (or after const/noexcept/override/final/mutable/a trailing return type)
whose parenthesis does not belong to if/for/while/switch/catch; lambdas count in the function that
holds them. A function's length is its line count from the line of its name to its closing brace.
"""
import argparse
import os
import re
import sys
from collections import defaultdict

MODULE_ORDER = ["core", "io", "geometry", "surface", "extract", "ooc", "render", "lod", "pipeline", "view", "eval", "apps"]
MAX_RENDER_FILE_LINES = 700
MAX_RENDER_FUNCTION_LINES = 150
SOURCE_EXT = (".h", ".hpp", ".cpp", ".cc")
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def source_files(root, tops):
    for top in tops:
        for dirpath, _, names in os.walk(os.path.join(root, top)):
            for n in sorted(names):
                if n.endswith(SOURCE_EXT):
                    yield os.path.relpath(os.path.join(dirpath, n), root)


def module_of(path):
    parts = path.split(os.sep)
    if parts[0] == "apps":
        return "apps"
    if parts[0] == "include" and len(parts) > 3:
        return parts[2]
    if parts[0] == "src" and len(parts) > 2:
        return parts[1]
    return parts[0]


def room_of(path):
    stem = os.path.basename(path)
    stem = stem[: stem.rfind(".")]
    if stem.endswith("-inl"):
        stem = stem[:-4]
    return module_of(path) + "/" + stem


def resolve(root, including, name, search):
    for base in [os.path.dirname(including)] + search:
        p = os.path.normpath(os.path.join(base, name))
        if os.path.isfile(os.path.join(root, p)):
            return p
    return None


def strip_code(text):
    """Comments, strings and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = text.find(")" + m.group(1) + '"', i)
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum():
                out.append(" ")  # digit separator 1'000
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(n, j + 1)
            out.append(" " * (j - i))
            i = j
        elif c == "#" and (i == 0 or text[i - 1] == "\n"):  # preprocessor line (with continuations)
            j = i
            while True:
                k = text.find("\n", j)
                if k < 0:
                    k = n
                    break
                if text[k - 1] != "\\":
                    break
                j = k + 1
            out.append(re.sub(r"[^\n]", " ", text[i:k]))
            i = k
        else:
            out.append(c)
            i += 1
    return "".join(out)


CONTROL = {"if", "for", "while", "switch", "catch", "return", "sizeof", "alignof", "decltype_", "static_assert"}
TRAILING = {"const", "noexcept", "override", "final", "mutable", "HWY_ATTR"}


def before_body(code, i, open_of):
    """The index of the ')' closing the parameter list of a body opening at code[i], or -1: trailing
    qualifiers, __attribute__((...)) and a trailing return type are skipped."""
    k = i - 1
    for _ in range(16):
        while k >= 0 and code[k].isspace():
            k -= 1
        if k < 0:
            return -1
        m = re.search(r"([A-Za-z_][A-Za-z_0-9]*)$", code[max(0, k - 64): k + 1])
        if m and m.group(1) in TRAILING:
            k -= len(m.group(1))
            continue
        if code[k] == ")" and k in open_of:
            o = open_of[k]
            if o > 0 and code[o - 1] == "(" and (o - 1) in open_of.values():
                o2 = o - 1
                m2 = re.search(r"__attribute__\s*$", code[max(0, o2 - 40): o2])
                if m2:
                    k = o2 - len(m2.group(0)) - 1
                    continue
            return k
        m = re.search(r"->\s*[A-Za-z_0-9:<>,\s\*&]+$", code[max(0, k - 200): k + 1])
        if m:
            k -= len(m.group(0))
            continue
        return -1
    return -1


def functions(text):
    """(name, first line, last line) of the outermost function bodies of C++ source `text`."""
    code = strip_code(text)
    line_at = [0] * (len(code) + 1)
    ln = 1
    for i, ch in enumerate(code):
        line_at[i] = ln
        if ch == "\n":
            ln += 1
    line_at[len(code)] = ln
    # matching parentheses and braces
    close_of, open_of, stack = {}, {}, []
    for i, ch in enumerate(code):
        if ch in "({":
            stack.append(i)
        elif ch in ")}" and stack:
            j = stack.pop()
            close_of[j], open_of[i] = i, j
    found, i = [], 0
    while i < len(code):
        if code[i] != "{" or i not in close_of:
            i += 1
            continue
        k = before_body(code, i, open_of)
        if k < 0:
            i += 1
            continue
        p = open_of[k]
        q = p - 1
        while q >= 0 and code[q].isspace():
            q -= 1
        m = re.search(r"([A-Za-z_~][A-Za-z_0-9:~<>]*|operator\s*\S+|\])$", code[: q + 1])
        name = m.group(1) if m else ""
        if name in CONTROL or name == "" or name.endswith("decltype"):
            i += 1
            continue
        if name == "]":
            name = "(lambda)"
        # the line where the declaration starts: the name's line
        first = line_at[q]
        last = line_at[close_of[i]]
        found.append((name, first, last))
        i = close_of[i] + 1  # nested bodies (lambdas, local classes) belong to this one
    return found


def sccs(graph):
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    sys.setrecursionlimit(100000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--top", type=int, default=5, help="how many of the longest functions to list")
    args = ap.parse_args()
    root = os.path.normpath(args.root)
    files = list(source_files(root, ["src", "include", "apps"]))
    test_files = list(source_files(root, ["tests", "bench", "python"]))
    search = ["include", "src"]
    edges = defaultdict(set)
    for f in files + test_files:
        with open(os.path.join(root, f), encoding="utf-8") as fh:
            text = fh.read()
        for name in INCLUDE_RE.findall(text):
            t = resolve(root, f, name, search)
            if t:
                edges[f].add(t)
    lib = set(files)
    file_graph = {f: {t for t in edges[f] if t in lib} for f in files}
    room_graph = defaultdict(set)
    for f, ts in file_graph.items():
        for t in ts:
            if room_of(f) != room_of(t):
                room_graph[room_of(f)].add(room_of(t))
    for f in files:
        room_graph.setdefault(room_of(f), set())
    problems = 0

    file_cycles = sccs(file_graph)
    room_cycles = sccs(room_graph)
    pairs = sorted({tuple(sorted((a, b))) for a, bs in room_graph.items() for b in bs if a in room_graph.get(b, ())})
    rank = {m: i for i, m in enumerate(MODULE_ORDER)}
    upward = []
    for f, ts in file_graph.items():
        for t in ts:
            mf, mt = module_of(f), module_of(t)
            if mf in rank and mt in rank and rank[mt] > rank[mf]:
                upward.append((f, t))
    users = defaultdict(set)
    for f, ts in edges.items():
        for t in ts:
            users[t].add(f)
    test_only = []
    for f in files:
        if f.startswith("include" + os.sep):
            us = {u for u in users[f] if room_of(u) != room_of(f)}
            if us and all(u in test_files for u in us):
                test_only.append(f)

    print(f"files: {len(files)} (src, include, apps); rooms: {len(room_graph)}")
    print(f"include cycles between files: {len(file_cycles)}")
    for c in file_cycles:
        print("   ", " -> ".join(c))
    print(f"include cycles between rooms: {len(room_cycles)}")
    for c in room_cycles:
        print("   ", " <-> ".join(c))
    print(f"pairs of rooms including each other: {len(pairs)}")
    for a, b in pairs:
        print(f"    {a} <-> {b}")
    print(f"includes from a lower module to a higher one ({' < '.join(MODULE_ORDER)}): {len(upward)}")
    for f, t in sorted(upward):
        print(f"    {f} -> {t}")
    print(f"public headers only the tests include: {len(test_only)}")
    for f in test_only:
        print("   ", f)
    problems += len(file_cycles) + len(room_cycles) + len(pairs) + len(upward) + len(test_only)

    # function lengths
    funcs = []
    for f in files:
        with open(os.path.join(root, f), encoding="utf-8") as fh:
            text = fh.read()
        for name, a, b in functions(text):
            funcs.append((b - a + 1, f, a, name))
    funcs.sort(key=lambda x: (-x[0], x[1], x[2]))
    library = [x for x in funcs if module_of(x[1]) != "apps"]
    print(f"longest functions of the library (src, include), of {len(library)}:")
    for n, f, a, name in library[: args.top]:
        print(f"    {n:4d}  {f}:{a}  {name}")
    render = lambda f: module_of(f) == "render"
    long_render = [x for x in funcs if render(x[1]) and x[0] > MAX_RENDER_FUNCTION_LINES]
    print(f"render functions over {MAX_RENDER_FUNCTION_LINES} lines: {len(long_render)}")
    for n, f, a, name in long_render:
        print(f"    {n:4d}  {f}:{a}  {name}")
    sizes = []
    for f in files:
        if render(f):
            with open(os.path.join(root, f), encoding="utf-8") as fh:
                sizes.append((sum(1 for _ in fh), f))
    sizes.sort(reverse=True)
    big = [s for s in sizes if s[0] > MAX_RENDER_FILE_LINES]
    print(f"render files over {MAX_RENDER_FILE_LINES} lines: {len(big)}; render files by size:")
    for n, f in sizes:
        print(f"    {n:5d}  {f}")
    problems += len(long_render) + len(big)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
