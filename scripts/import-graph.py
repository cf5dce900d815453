#!/usr/bin/env python3
"""The crate's file-level import graph: which file uses which, its cycles,
and the arrows between the folders of src/.

    scripts/import-graph.py            # cycles and folder arrows
    scripts/import-graph.py --tests    # counting #[cfg(test)] modules too
    scripts/import-graph.py --edges    # every file arrow as well

An arrow A -> B means A names an item defined in B (by `use` or by an
inline `crate::`/`super::` path). A `pub use` in a mod.rs or lib.rs is a
facade, not a dependency: names reached through it are followed to the file
that defines them, so a module re-exporting its children does not make a
cycle with each child that uses its parent. Exits non-zero if any cycle
between files, or between the folders of src/, is found
(tests/architecture.rs runs it).
"""

import re
import sys
from collections import defaultdict
from pathlib import Path

SRC = Path(__file__).resolve().parent.parent / "src"


def module_path(file):
    """The module path of a source file, as a tuple of names."""
    rel = file.relative_to(SRC)
    if rel.parts[0] == "bin":
        return ("bin", rel.stem)
    parts = list(rel.with_suffix("").parts)
    if parts[-1] in ("mod", "lib"):
        parts.pop()
    return tuple(parts)


def strip(text, with_tests):
    """Source without comments, string literals, or (unless asked) test modules."""
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'r#*"(?:.|\n)*?"#*', '""', text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    if not with_tests:
        text = drop_test_modules(text)
    return text


def drop_test_modules(text):
    out, i = [], 0
    for m in re.finditer(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{", text):
        if m.start() < i:
            continue
        out.append(text[i : m.start()])
        depth, j = 1, m.end()
        while j < len(text) and depth:
            depth += {"{": 1, "}": -1}.get(text[j], 0)
            j += 1
        i = j
    out.append(text[i:])
    return "".join(out)


def expand_tree(tree):
    """`a::{b, c::{d as e, *}}` -> [(['a','b'], 'b'), (['a','c','d'], 'e'), (['a','c','*'], '*')]."""
    tree = re.sub(r"\s+", " ", tree)
    tree = re.sub(r"\s*(::|,|\{|\})\s*", r"\1", tree).strip()

    def parse(s, prefix):
        items, depth, start = [], 0, 0
        for k, ch in enumerate(s):
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            elif ch == "," and depth == 0:
                items.append(s[start:k])
                start = k + 1
        items.append(s[start:])
        result = []
        for item in filter(None, items):
            brace = item.find("{")
            if brace >= 0:
                head = [p for p in item[:brace].split("::") if p]
                result += parse(item[brace + 1 : item.rfind("}")], prefix + head)
            else:
                path, _, alias = item.partition(" as ")
                path = path.split("::")
                if path == ["self"]:
                    result.append((prefix, alias or (prefix[-1] if prefix else "self")))
                else:
                    result.append((prefix + path, alias or path[-1]))
        return result

    return parse(tree, [])


class Crate:
    def __init__(self, with_tests):
        self.files = {}  # module path -> file
        self.text = {}
        raw = {f: f.read_text() for f in sorted(SRC.rglob("*.rs"))}
        if not with_tests:
            # A test module in its own file (`#[cfg(test)] mod tests;`) is
            # left out as an inline one is.
            tests = {
                module_path(f) + (m.group(1),)
                for f, text in raw.items()
                for m in re.finditer(
                    r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+(\w+)\s*;", strip(text, True)
                )
            }
            raw = {f: t for f, t in raw.items() if not any(module_path(f)[: len(p)] == p for p in tests)}
        for f, text in raw.items():
            self.files[module_path(f)] = f
            self.text[f] = strip(text, with_tests)
        self.reexports = {f: self.pub_uses(f) for f in self.text}

    def is_facade(self, f):
        return f.name in ("mod.rs", "lib.rs")

    def uses(self, f):
        """(path, name, is_pub) of every `use` in file f, paths absolute."""
        out = []
        for m in re.finditer(r"(?:^|[;{}\s])(pub(?:\([^)]*\))?\s+)?use\s+([^;]+);", self.text[f]):
            for path, name in expand_tree(m.group(2)):
                absolute = self.absolute(f, path)
                if absolute is not None:
                    out.append((absolute, name, bool(m.group(1))))
        return out

    def pub_uses(self, f):
        return [(p, n) for p, n, public in self.uses(f) if public]

    def absolute(self, f, path):
        """Path segments from the crate root, or None for other crates."""
        here = list(module_path(f))
        if here[:1] == ["bin"]:
            if path[:1] == ["bpm"]:
                return path[1:]
            return None
        if path[:1] == ["crate"]:
            return path[1:]
        if path[:1] == ["self"]:
            return here + path[1:]
        if path[:1] == ["super"]:
            base = here
            while path[:1] == ["super"]:
                base = base[:-1]
                path = path[1:]
            return base + path
        # A child module named without `self::` (2018 paths).
        if tuple(here + path[:1]) in self.files:
            return here + path
        return None

    def resolve(self, path, seen=None):
        """The files defining what `path` names (several for a glob)."""
        seen = seen or set()
        for k in range(len(path), -1, -1):
            f = self.files.get(tuple(path[:k]))
            if f is None:
                continue
            rest = path[k:]
            if not rest:
                return {f}
            name = rest[0]
            if (f, name) in seen:
                return {f}
            seen.add((f, name))
            targets = set()
            for target, alias in self.reexports[f]:
                if alias == name:
                    targets |= self.resolve(target + rest[1:], seen)
                elif alias == "*" and name != "*":
                    found = self.resolve(target[:-1] + rest, seen)
                    if found and found != {self.files.get(tuple(target[:-1]))} or self.defines(
                        self.files.get(tuple(target[:-1])), name
                    ):
                        targets |= found
            return targets or {f}
        return set()

    def defines(self, f, name):
        if f is None:
            return False
        return re.search(
            r"\b(?:fn|struct|enum|trait|type|const|static|mod|macro_rules!)\s+" + re.escape(name) + r"\b",
            self.text[f],
        ) is not None

    def inline_paths(self, f):
        text = re.sub(r"(?:^|[;{}\s])(pub(?:\([^)]*\))?\s+)?use\s+[^;]+;", " ", self.text[f])
        prefix = r"(?:crate|super(?:::super)*|bpm)" if module_path(f)[:1] == ("bin",) else r"(?:crate|super(?:::super)*)"
        for m in re.finditer(r"\b(" + prefix + r"(?:::[A-Za-z_][A-Za-z0-9_]*)+)", text):
            path = m.group(1).split("::")
            absolute = self.absolute(f, path)
            if absolute is not None:
                yield absolute

    def edges(self):
        graph = defaultdict(set)
        for f in self.text:
            paths = [p for p, _, public in self.uses(f) if not (public and self.is_facade(f))]
            paths += list(self.inline_paths(f))
            for p in paths:
                for target in self.resolve(p):
                    if target != f:
                        graph[f].add(target)
        return graph


def sccs(graph, nodes):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

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
            out.append(comp)

    sys.setrecursionlimit(10000)
    for v in nodes:
        if v not in index:
            visit(v)
    return [c for c in out if len(c) > 1]


def a_cycle(graph, comp):
    """One shortest cycle through the component's first node."""
    members = set(comp)
    start = sorted(comp)[0]
    paths = {start: [start]}
    queue = [start]
    while queue:
        v = queue.pop(0)
        for w in sorted(graph.get(v, ())):
            if w == start:
                return paths[v] + [start]
            if w in members and w not in paths:
                paths[w] = paths[v] + [w]
                queue.append(w)
    return comp


def folder(f):
    rel = f.relative_to(SRC)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


def main():
    crate = Crate(with_tests="--tests" in sys.argv)
    graph = crate.edges()
    name = lambda f: str(f.relative_to(SRC))
    if "--edges" in sys.argv:
        for f in sorted(graph):
            for t in sorted(graph[f]):
                print(f"{name(f)} -> {name(t)}")
        print()

    cycles = sccs(graph, sorted(crate.text))
    print(f"file cycles: {len(cycles)}")
    for comp in cycles:
        cycle = a_cycle(graph, comp)
        print(f"  {len(comp)} files: " + " -> ".join(name(f) for f in cycle))
        rest = sorted(set(comp) - set(cycle))
        if rest:
            print("    also in the same tangle: " + ", ".join(name(f) for f in rest))

    arrows = defaultdict(int)
    for f, targets in graph.items():
        for t in targets:
            if folder(f) != folder(t):
                arrows[(folder(f), folder(t))] += 1
    print("\nfolder arrows (file arrows behind each):")
    for src in sorted({a for a, _ in arrows}):
        targets = sorted(t for s, t in arrows if s == src)
        print(f"  {src} -> " + ", ".join(f"{t} ({arrows[(src, t)]})" for t in targets))
    folder_graph = defaultdict(set)
    for s, t in arrows:
        folder_graph[s].add(t)
    folder_cycles = sccs(folder_graph, sorted({x for pair in arrows for x in pair}))
    print(f"\nfolder cycles: {len(folder_cycles)}")
    for comp in folder_cycles:
        print("  " + " -> ".join(a_cycle(folder_graph, comp)))
    return 1 if cycles or folder_cycles else 0


if __name__ == "__main__":
    sys.exit(main())
