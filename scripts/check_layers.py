#!/usr/bin/env python3
"""The house rules that a compiler does not check (docs/architecture.md), run by `make test` (ctest: layers):

1. Layers depend one way. Every `#include "FOLDER/..."` in src/, include/nimbus/ and apps/ is an edge of the
   folder-level include graph; the graph must have no cycle, and a folder may include only the folders
   below it:
       api (include/nimbus) <- core <- media <- transport <- scene <- integrators <- {io, render} <- apps
   io (scene JSON, volume files, images) and render (the driver, the film) sit side by side: neither
   includes the other. The public API includes nothing but itself, so it stands alone.
2. Short files and functions: no file in src/ over 600 lines and no function in src/integrators/*.cpp or
   src/transport/*.cpp over 60 lines, unless the file says why in a comment that starts with
   `long-file:` or `long-function: NAME` (NAME: the function) in its first 40 lines.

    scripts/check_layers.py [--graph]    # --graph: print the folder graph as edges "a -> b (n includes)"
Exit status 1 with one line per violation.
"""
import glob, os, re, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ORDER = ["api", "core", "media", "transport", "scene", "integrators", "io", "render", "apps"]
RANK = {"api": 0, "core": 1, "media": 2, "transport": 3, "scene": 4, "integrators": 5, "io": 6, "render": 6,
        "apps": 7}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')
MAX_FILE_LINES, MAX_FUNCTION_LINES = 600, 60


def folder_of(path):
    """The layer of a repository file, or None."""
    rel = os.path.relpath(path, ROOT).split(os.sep)
    if rel[0] == "include" and len(rel) > 1 and rel[1] == "nimbus":
        return "api"
    if rel[0] == "src" and len(rel) > 2:
        return rel[1]
    if rel[0] == "apps":
        return "apps"
    return None


def target_of(include):
    head = include.split("/")[0]
    if head == "nimbus":
        return "api"
    return head if head in RANK else None


def sources():
    for top in ("src", "include", "apps"):
        for dirpath, _, files in os.walk(os.path.join(ROOT, top)):
            for f in sorted(files):
                if f.endswith((".h", ".cpp")):
                    yield os.path.join(dirpath, f)


def find_cycle(edges):
    graph = {}
    for (a, b) in edges:
        graph.setdefault(a, set()).add(b)
    state = {}

    def visit(n, stack):
        state[n] = 1
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                return stack + [n, m]
            if state.get(m) is None:
                c = visit(m, stack + [n])
                if c:
                    return c
        state[n] = 2
        return None

    for n in sorted(graph):
        if state.get(n) is None:
            c = visit(n, [])
            if c:
                return c
    return None


def strip_code(line, in_comment):
    """The line without comments, string and character literals; and whether a /* comment continues."""
    out, i = [], 0
    while i < len(line):
        if in_comment:
            j = line.find("*/", i)
            if j < 0:
                return "".join(out), True
            i, in_comment = j + 2, False
        elif line.startswith("//", i):
            break
        elif line.startswith("/*", i):
            in_comment, i = True, i + 2
        elif line[i] in "\"'":
            q, i = line[i], i + 1
            while i < len(line) and line[i] != q:
                i += 2 if line[i] == "\\" else 1
            i += 1
        else:
            out.append(line[i])
            i += 1
    return "".join(out), in_comment


def long_functions(path, lines):
    """(name, first line, length) of each top-level brace block in a .cpp file longer than the limit."""
    found, depth, ns_depth, start, name, in_comment, sig = [], 0, 0, None, "", False, ""
    for n, raw in enumerate(lines, 1):
        code, in_comment = strip_code(raw, in_comment)
        for ch in code:
            if depth == ns_depth and ch not in "{}":
                sig += ch
            if ch == "{":
                # namespaces, classes and structs: their members are the functions
                if depth == ns_depth and re.search(r"\b(namespace|class|struct|union)\b[^;{}()]*$", sig):
                    ns_depth += 1
                elif depth == ns_depth and start is None:
                    start = n
                    m = re.findall(r"([\w:~]+)\s*\(", sig)
                    name = m[0] if m else "?"
                depth += 1
            elif ch == "}":
                depth -= 1
                if depth < ns_depth:
                    ns_depth = depth
                elif depth == ns_depth and start is not None:
                    if n - start + 1 > MAX_FUNCTION_LINES:
                        found.append((name, start, n - start + 1))
                    start = None
                sig = ""
            elif ch == ";" and depth == ns_depth:
                sig = ""
        if depth == ns_depth:
            sig += " "
    return found


# The test suites are unity builds (eight files to a translation unit), so two test files must not define
# the same name at namespace scope: helpers shared by several files go to tests/support/, the others get
# a name of their own. A line-based look at definitions that start in column 0.
TEST_DEFINITION = [
    re.compile(r"^(?:static\s+|inline\s+|constexpr\s+|const\s+)*[\w:<>,\s&*\[\]]+?[\s&*](\w+)\s*\([^;]*$"),
    re.compile(r"^(?:struct|class|enum(?:\s+class)?)\s+(\w+)\s*[{:]"),
    re.compile(r"^(?:static\s+)?(?:constexpr|const)\s+[\w:<>]+(?:\s*[*&]\s*|\s+)(?:const\s+)?(\w+)\s*(?:=|\[|\{)"),
    re.compile(r"^using\s+(\w+)\s*="),
    re.compile(r"^#define\s+(\w+)"),
]


def test_name_clashes():
    bad = []
    for suffix in ("_test.cpp", "_slowtest.cpp"):
        where = {}
        for path in sorted(glob.glob(os.path.join(ROOT, "tests", "**", "*" + suffix), recursive=True)):
            rel = os.path.relpath(path, ROOT)
            with open(path, encoding="utf-8") as f:
                for n, line in enumerate(f, 1):
                    if line.startswith(("TEST", " ", "}", "//", "namespace", "return")):
                        continue
                    for pattern in TEST_DEFINITION:
                        m = pattern.match(line)
                        if m and m.group(1) not in ("main", "if", "for", "while", "switch"):
                            where.setdefault(m.group(1), []).append(f"{rel}:{n}")
                            break
        for name, places in sorted(where.items()):
            files = {p.rsplit(":", 1)[0] for p in places}
            if len(files) > 1:
                bad.append(f"{name} is defined at namespace scope in {len(files)} test files ({', '.join(places)}): "
                           "the unity build compiles them together; share it in tests/support/ or rename it")
    return bad


def main():
    edges, bad = {}, []
    for path in sources():
        src = folder_of(path)
        rel = os.path.relpath(path, ROOT)
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
        for n, line in enumerate(lines, 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            dst = target_of(m.group(1))
            if src is None or dst is None or dst == src:
                continue
            edges[(src, dst)] = edges.get((src, dst), 0) + 1
            if RANK[dst] >= RANK[src]:
                bad.append(f"{rel}:{n}: {src} includes {m.group(1)} ({dst} is not below {src})")
        head = "\n".join(lines[:40])
        if rel.startswith("src") and len(lines) > MAX_FILE_LINES and "long-file:" not in head:
            bad.append(f"{rel}: {len(lines)} lines (over {MAX_FILE_LINES}, and no 'long-file:' reason at its top)")
        if rel.startswith(("src/integrators", "src/transport")) and rel.endswith(".cpp"):
            for name, start, length in long_functions(path, lines):
                if f"long-function: {name.split('::')[-1]}" not in head and f"long-function: {name}" not in head:
                    bad.append(f"{rel}:{start}: {name} is {length} lines (over {MAX_FUNCTION_LINES}, and no "
                               f"'long-function: {name.split('::')[-1]}' reason at the file's top)")
    bad += test_name_clashes()
    cycle = find_cycle(edges)
    if cycle:
        bad.append("include cycle between folders: " + " -> ".join(cycle))
    if "--graph" in sys.argv:
        for (a, b), count in sorted(edges.items(), key=lambda e: (ORDER.index(e[0][0]), ORDER.index(e[0][1]))):
            print(f"{a} -> {b} ({count} includes)")
    for line in bad:
        print(line)
    print(f"check_layers: {len(edges)} folder edges, {len(bad)} violations")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
