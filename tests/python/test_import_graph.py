"""No module of the add-on imports itself back, however indirectly (issue
25): the graph of addon/penumbra's imports, read with `ast` (no bpy), has
no cycle. Every import statement counts, the ones inside functions too
(they hide a cycle until the function runs, they do not remove it), and
relative ones (`from . import x`, `from .x import y`, `from .. import z`).

An edge goes to the module an import names: `from .x import y` to x.y when
y is a module of the package, else to x. The parent packages Python imports
on the way are not edges: every package's __init__ imports its own modules,
so counting them would make each module a cycle with its package."""

import ast
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ADDON = os.path.join(ROOT, "addon", "penumbra")


def modules(package_dir):
    """{dotted name: path} of every .py file under package_dir, the package
    named after its folder (penumbra)."""
    top = os.path.basename(os.path.normpath(package_dir))
    found = {}
    for folder, dirs, files in os.walk(package_dir):
        dirs[:] = sorted(d for d in dirs if d != "__pycache__")
        parts = [top] + os.path.relpath(folder, package_dir).split(os.sep)
        parts = [p for p in parts if p != "."]
        for name in files:
            if name.endswith(".py"):
                dotted = parts if name == "__init__.py" else parts + [name[:-3]]
                found[".".join(dotted)] = os.path.join(folder, name)
    return found


def _base(module, path, level):
    """The package a relative import of `level` dots starts from."""
    package = module if path.endswith("__init__.py") else module.rpartition(".")[0]
    for _ in range(level - 1):
        package = package.rpartition(".")[0]
    return package


def imports(module, path, known):
    """The modules of `known` that `module` (its source at `path`) imports."""
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), path)
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names if alias.name in known)
        elif isinstance(node, ast.ImportFrom):
            source = node.module or ""
            if node.level:
                base = _base(module, path, node.level)
                source = f"{base}.{source}" if source else base
            for alias in node.names:
                if f"{source}.{alias.name}" in known:
                    found.add(f"{source}.{alias.name}")
                elif source in known:
                    found.add(source)
    found.discard(module)
    return found


def graph(package_dir):
    known = modules(package_dir)
    return {module: imports(module, path, known) for module, path in known.items()}


def cycles(edges):
    """One cycle per strongly connected component of more than one module
    (Tarjan), each as a list of modules that starts and ends at the same one."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.add(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(_cycle_in(edges, component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def _cycle_in(edges, component):
    """The shortest cycle through the component's first module (breadth-first)."""
    start = min(component)
    came_from = {start: None}
    queue = [start]
    while queue:
        v = queue.pop(0)
        for w in sorted(edges[v] & component):
            if w == start:
                path = [v]
                while came_from[path[-1]] is not None:
                    path.append(came_from[path[-1]])
                return path[::-1] + [start]
            if w not in came_from:
                came_from[w] = v
                queue.append(w)
    raise AssertionError(f"no cycle through {start} in {sorted(component)}")


def describe(found):
    return "\n".join(" -> ".join(cycle) for cycle in found)


# ---- the add-on -----------------------------------------------------------------

def test_the_addon_has_no_import_cycle():
    edges = graph(ADDON)
    assert "penumbra.colormap.operators" in edges and len(edges) > 40
    found = cycles(edges)
    assert not found, "import cycles in addon/penumbra:\n" + describe(found)


# ---- the check finds what it is for ------------------------------------------------

def write(folder, files):
    for name, text in files.items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_a_cycle_through_a_function_level_relative_import_is_named(tmp_path):
    package = tmp_path / "pkg"
    write(package, {
        "__init__.py": "from . import a, tools\n",
        "a.py": "from .tools import b\n",
        "tools/__init__.py": "",
        "tools/b.py": "from .. import c\n",
        "c.py": "def late():\n    from .a import thing\n    return thing\n",
        "d.py": "import os\nfrom . import a\n",
    })
    found = cycles(graph(str(package)))
    assert describe(found) == "pkg.a -> pkg.tools.b -> pkg.c -> pkg.a"


def test_an_import_of_a_name_from_a_package_is_an_edge_to_its_init(tmp_path):
    package = tmp_path / "pkg"
    write(package, {
        "__init__.py": "from .a import f\nVALUE = 1\n",
        "a.py": "def f():\n    from . import VALUE\n    return VALUE\n",
    })
    assert describe(cycles(graph(str(package)))) == "pkg -> pkg.a -> pkg"


def test_a_package_importing_its_own_modules_is_no_cycle(tmp_path):
    package = tmp_path / "pkg"
    write(package, {
        "__init__.py": "from . import a, b\n",
        "a.py": "from . import b\nfrom .b import g\n",
        "b.py": "import json\ndef g():\n    return json\n",
    })
    edges = graph(str(package))
    assert edges == {"pkg": {"pkg.a", "pkg.b"}, "pkg.a": {"pkg.b"}, "pkg.b": set()}
    assert cycles(edges) == []
