"""No import circle inside `softevo.core`, between modules or between its packages, with no
exception: grimp (which import-linter installs) reads the tree as it installs, staged as
`scripts/lint.sh` stages it, in a child process so this one's `softevo` stays as it is."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

_CYCLES = r"""
import json, sys
import grimp

graph = grimp.build_graph("softevo", include_external_packages=False)
modules = sorted(m for m in graph.modules if m.startswith("softevo.core"))
edges = {m: {n for n in graph.find_modules_directly_imported_by(m) if n.startswith("softevo.core")}
         for m in modules}
# packages too: a module's package imports what the module imports (outside that package)
packages = {m.rsplit(".", 1)[0] for m in modules} - {"softevo"}
package_edges = {p: set() for p in packages}
for m, targets in edges.items():
    for n in targets:
        for p in packages:
            if (m == p or m.startswith(p + ".")) and not (n == p or n.startswith(p + ".")):
                package_edges[p].update(q for q in packages if n == q or n.startswith(q + "."))

def circles(graph):
    found, order, low, stack, on = [], {}, {}, [], set()
    def visit(v):
        order[v] = low[v] = len(order); stack.append(v); on.add(v)
        for w in sorted(graph[v]):
            if w not in order:
                visit(w); low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], order[w])
        if low[v] == order[v]:
            part = []
            while True:
                w = stack.pop(); on.discard(w); part.append(w)
                if w == v:
                    break
            if len(part) > 1 or v in graph[v]:
                found.append(sorted(part))
    sys.setrecursionlimit(10_000)
    for v in sorted(graph):
        if v not in order:
            visit(v)
    return found

# a package's own __init__ importing its modules is no circle: only other packages count
for p in package_edges:
    package_edges[p].discard(p)
print(json.dumps({"modules": len(modules), "module_circles": circles(edges),
                  "package_circles": circles(package_edges)}))
"""


def test_softevo_core_has_no_import_circle(tmp_path: Path) -> None:
    stage = tmp_path / "softevo"
    stage.mkdir()
    (stage / "__init__.py").write_text("")
    shutil.copytree(ROOT / "core", stage / "core", ignore=shutil.ignore_patterns("__pycache__"))
    done = subprocess.run(
        [sys.executable, "-c", _CYCLES],
        cwd=tmp_path,
        env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        check=True,
    )
    found = json.loads(done.stdout)
    assert found["modules"] > 50  # the graph was read (a wrong stage finds nothing to circle)
    assert found["module_circles"] == []
    assert found["package_circles"] == []
