#!/usr/bin/env python3
"""Module graph of volcache, read from the code's own `use` paths.

Prints a Mermaid graph: the layers as nodes (folders of src/, and the files of
src/pipeline/ one by one, since they are the method), an arrow A --> B when code in A
names `crate::B` (or `volcache::B` from the binary, `super::B` within a folder).
`python3 scripts/module_graph.py --write` replaces the graph between the markers in
ARCHITECTURE.md, so the picture stays what the code says.
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SRC = ROOT / "src"
DETAILED = {"pipeline"}  # folders drawn file by file
BEGIN, END = "<!-- module graph: begin -->", "<!-- module graph: end -->"


def node_of(path: pathlib.Path) -> str:
    rel = path.relative_to(SRC).with_suffix("")
    parts = rel.parts
    if parts == ("main",):
        return "cli"
    if parts[0] in DETAILED and len(parts) > 1 and parts[1] != "mod":
        return f"{parts[0]}/{parts[1]}"
    return parts[0]


def code_only(text: str) -> str:
    """The text without comments (doc comments name modules in prose)."""
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


def edges() -> set:
    out = set()
    for f in SRC.rglob("*.rs"):
        src = node_of(f)
        text = code_only(f.read_text())
        inside = src.split("/")[0]
        for top, sub in re.findall(r"\b(?:crate|volcache)::([a-z_0-9]+)(?:::([a-z_0-9]+))?", text):
            # File by file within a detailed folder; the folder as a whole from outside.
            dst = f"{top}/{sub}" if top in DETAILED and sub and top == inside else top
            known = (SRC / top).exists() or (SRC / f"{top}.rs").exists()
            if known and dst != src and dst != inside:
                out.add((src, dst))
        if src.startswith(tuple(f"{d}/" for d in DETAILED)):
            folder = src.split("/")[0]
            for sub in re.findall(r"\bsuper::([a-z_0-9]+)", text):
                dst = f"{folder}/{sub}"
                if dst != src and (SRC / folder / f"{sub}.rs").exists():
                    out.add((src, dst))
    return out


def mermaid() -> str:
    es = sorted(edges())
    nodes = sorted({n for e in es for n in e})
    lines = ["```mermaid", "graph BT"]
    detailed = [n for n in nodes if "/" in n]
    for folder in sorted({n.split("/")[0] for n in detailed}):
        lines.append(f"  subgraph {folder}[src/{folder}: the method, generic over the dimension]")
        lines += [f"    {n.replace('/', '_')}[{n.split('/')[1]}]" for n in detailed if n.startswith(folder + "/")]
        lines.append("  end")
    lines += [f"  {a.replace('/', '_')} --> {b.replace('/', '_')}" for a, b in es]
    lines.append("```")
    return "\n".join(lines)


def main():
    graph = mermaid()
    if "--write" in sys.argv:
        doc = ROOT / "ARCHITECTURE.md"
        text = doc.read_text()
        head, rest = text.split(BEGIN, 1)
        _, tail = rest.split(END, 1)
        doc.write_text(f"{head}{BEGIN}\n{graph}\n{END}{tail}")
    else:
        print(graph)


if __name__ == "__main__":
    main()
