"""The data-flow tables of docs/architecture.md, parsed, and the checks run
on them: statically by tests/python/test_architecture_doc.py (paths, C++
definitions, add-on functions, operators, `_penumbra` names) and by
running each tool by tests/blender/test_architecture_calls.py (every
`_penumbra` name of a tool's `step` table is called). No bpy here.

A table is recognised by its header, `| step | operator | add-on |
_penumbra | core |` (a tool's main flow) or the same with `also` first
(other entry points, checked statically only), under a heading that names
its tool in backticks. The cell format is documented in the doc itself."""

import ast
import os
import re
import sys
import types
from dataclasses import dataclass, field

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "architecture.md")
COLUMNS = ("operator", "add-on", "_penumbra", "core")
KINDS = ("step", "also")
NONE = "—"


@dataclass
class Row:
    tool: str
    kind: str                 # "step": the tool's main flow; "also": other entry points
    line: int                 # 1-based, in the doc
    step: str
    operators: list = field(default_factory=list)   # "penumbra.x" or "bpy.app.handlers.x"
    addon: list = field(default_factory=list)       # (path under addon/penumbra, "name" or "Class.method")
    penumbra: list = field(default_factory=list)    # "_penumbra.sub.name", ".Class.method" or ".Class"
    core: list = field(default_factory=list)        # ("core/....cpp", "name" or "Class::method")

    def where(self):
        return f"docs/architecture.md:{self.line} ({self.tool}, {self.step})"


# ---- parsing ---------------------------------------------------------------

_OPERATOR = re.compile(r"^(penumbra\.[a-z_]+|bpy\.app\.handlers\.[a-z_]+)$")
_PENUMBRA = re.compile(r"^_penumbra(\.[A-Za-z_][A-Za-z0-9_]*)+$")
_FILE_NAMES = re.compile(r"^(?P<path>[\w./-]+\.(?P<ext>py|cpp|hpp)):(?P<names>.+)$")
_PY_NAME = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)?$")
_CPP_NAME = re.compile(r"^(~?[A-Za-z_]\w*::)*~?[A-Za-z_]\w*$")


def _cells(line):
    return [c.strip() for c in line.strip().strip("|").split("|")]


def _items(cell):
    """The backticked items of a cell, or None when anything but commas and
    spaces stands outside the backticks."""
    if cell == NONE:
        return []
    items = re.findall(r"`([^`]+)`", cell)
    rest = re.sub(r"`[^`]+`", "", cell)
    if not items or rest.strip(", "):
        return None
    return items


def _file_names(item, ext, column, problems, where):
    m = _FILE_NAMES.match(item)
    if not m or m["ext"] not in ext:
        problems.append(f"{where}: {column} cell item `{item}` is not `path:name[, name]`")
        return []
    names = [n.strip() for n in m["names"].split(",")]
    pattern = _PY_NAME if m["ext"] == "py" else _CPP_NAME
    bad = [n for n in names if not pattern.match(n)]
    if bad:
        problems.append(f"{where}: {column} cell item `{item}`: not a function name: {bad}")
    return [(m["path"], n) for n in names if pattern.match(n)]


def _parse_row(row, cells, problems):
    where = row.where()
    items = {}
    for column, cell in zip(COLUMNS, cells[1:]):
        found = _items(cell)
        if found is None:
            problems.append(f"{where}: the {column} cell is neither {NONE} nor backticked names: {cell!r}")
            found = []
        items[column] = found
    for item in items["operator"]:
        if _OPERATOR.match(item):
            row.operators.append(item)
        else:
            problems.append(f"{where}: `{item}` is neither penumbra.<operator> nor bpy.app.handlers.<list>")
    for item in items["_penumbra"]:
        if _PENUMBRA.match(item):
            row.penumbra.append(item)
        else:
            problems.append(f"{where}: `{item}` is not a dotted _penumbra name")
    for item in items["add-on"]:
        row.addon += _file_names(item, ("py",), "add-on", problems, where)
    for item in items["core"]:
        if not item.startswith("core/"):
            problems.append(f"{where}: core cell item `{item}` is not under core/")
        row.core += _file_names(item, ("cpp", "hpp"), "core", problems, where)


def parse(text):
    """(rows, problems) of every data-flow table in the doc's text."""
    rows, problems = [], []
    tool, kind = None, None
    for number, line in enumerate(text.splitlines(), 1):
        heading = re.match(r"^#+\s", line)
        if heading:
            named = re.search(r"`([a-z_]+)`", line)
            tool, kind = (named.group(1) if named else None), None
            continue
        if not line.startswith("|"):
            kind = None
            continue
        cells = _cells(line)
        if len(cells) == 5 and cells[0] in KINDS and tuple(c.strip("`") for c in cells[1:]) == COLUMNS:
            kind = cells[0]
            if tool is None:
                problems.append(f"docs/architecture.md:{number}: a data-flow table under a heading without a tool")
            continue
        if kind is None or set(line) <= set("|-: "):
            continue
        row = Row(tool, kind, number, cells[0])
        if len(cells) != 5:
            problems.append(f"{row.where()}: {len(cells)} cells, not 5")
            continue
        _parse_row(row, cells, problems)
        rows.append(row)
    return rows, problems


def load(path=DOC):
    with open(path, encoding="utf-8") as f:
        return parse(f.read())


# ---- static checks -----------------------------------------------------------

def missing_paths(rows, root=ROOT):
    problems = []
    for row in rows:
        for path, _ in row.addon:
            if not os.path.isfile(os.path.join(root, "addon", "penumbra", path)):
                problems.append(f"{row.where()}: no file addon/penumbra/{path}")
        for path, _ in row.core:
            if not os.path.isfile(os.path.join(root, path)):
                problems.append(f"{row.where()}: no file {path}")
    return problems


def _without_comments_and_strings(source):
    """C++ source with comments and string/char literals blanked (newlines kept)."""
    def blank(m):
        return re.sub(r"[^\n]", " ", m.group(0))
    return re.sub(r'//[^\n]*|/\*.*?\*/|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', blank, source, flags=re.S)


# What may stand after a definition's parameter list before its body:
# qualifiers, a trailing return type, a constructor's initializer list.
_AFTER_PARAMETERS = re.compile(r"\s*(?:(?:const|noexcept|override|final|mutable|&&|&)\s*)*(?:->\s*[^;{]+?)?\s*"
                               r"(?P<end>\{|:(?!:)|=\s*default\b|;|=)")
# What may stand before the name on its line: declaration specifiers and a
# return type (no '=', '(', '.', '->', 'return': those make it an expression).
_BEFORE_NAME = re.compile(r"^(?:template\s*<[^;{}]*>\s*)?(?:[A-Za-z_][\w:<>,*&\s]*?[\s*&>])?$")


def _closing_paren(text, start):
    depth = 0
    for i in range(start, len(text)):
        if text[i] == "(":
            depth += 1
        elif text[i] == ")":
            depth -= 1
            if depth == 0:
                return i
    return -1


def cpp_defines(source, name):
    """Whether C++ `source` defines function `name` (`f` or `Class::f`) at
    namespace scope with a body: the signature starts a line (no indent),
    and its parameter list is followed by a body, an initializer list or
    `= default`, not by `;` (a declaration)."""
    text = _without_comments_and_strings(source)
    for m in re.finditer(r"(?<![\w:])" + re.escape(name) + r"\s*\(", text):
        line_start = text.rfind("\n", 0, m.start()) + 1
        prefix = text[line_start:m.start()]
        if prefix[:1].isspace() or not _BEFORE_NAME.match(prefix):
            continue
        if re.search(r"\b(return|new|delete|throw)\b", prefix):
            continue
        close = _closing_paren(text, m.end() - 1)
        after = _AFTER_PARAMETERS.match(text, close + 1) if close >= 0 else None
        if after and after["end"] not in (";", "="):
            return True
    return False


def undefined_cpp(rows, root=ROOT):
    problems = []
    for row in rows:
        for path, name in row.core:
            full = os.path.join(root, path)
            if not os.path.isfile(full):
                continue  # missing_paths says so
            with open(full, encoding="utf-8") as f:
                if not cpp_defines(f.read(), name):
                    problems.append(f"{row.where()}: {name} is not defined in {path}")
    return problems


def python_defines(source, name):
    """Whether Python `source` defines `name` (a top-level function or class)
    or `Class.method` (a method of a top-level class)."""
    tree = ast.parse(source)
    outer, _, inner = name.partition(".")
    defs = (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)
    for node in tree.body:
        if isinstance(node, defs) and node.name == outer:
            if not inner:
                return True
            if isinstance(node, ast.ClassDef):
                return any(isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name == inner
                           for n in node.body)
    return False


def undefined_addon(rows, root=ROOT):
    problems = []
    for row in rows:
        for path, name in row.addon:
            full = os.path.join(root, "addon", "penumbra", path)
            if not os.path.isfile(full):
                continue
            with open(full, encoding="utf-8") as f:
                if not python_defines(f.read(), name):
                    problems.append(f"{row.where()}: {name} is not defined in addon/penumbra/{path}")
    return problems


def addon_operators_and_handlers(root=ROOT):
    """(bl_idnames of the add-on's operators, handler lists it appends to)."""
    operators, handlers = set(), set()
    for folder, _, files in os.walk(os.path.join(root, "addon", "penumbra")):
        for name in files:
            if not name.endswith(".py"):
                continue
            with open(os.path.join(folder, name), encoding="utf-8") as f:
                source = f.read()
            for node in ast.walk(ast.parse(source)):
                if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant) and \
                        any(isinstance(t, ast.Name) and t.id == "bl_idname" for t in node.targets):
                    operators.add(node.value.value)
            handlers |= set(re.findall(r"bpy\.app\.handlers\.(\w+)", source))
    return operators, handlers


def unknown_operators(rows, root=ROOT):
    operators, handlers = addon_operators_and_handlers(root)
    problems = []
    for row in rows:
        for item in row.operators:
            known = item in operators if item.startswith("penumbra.") else item.rsplit(".", 1)[1] in handlers
            if not known:
                problems.append(f"{row.where()}: `{item}` is no operator or handler of the add-on")
    return problems


# A backticked repository path anywhere in the doc (no placeholders: `<tool>`).
_REPO_PATH = re.compile(r"`((?:addon|bench|core|docs|examples|plugin|scripts|tests)/[\w./-]*)`")


def missing_cited_paths(text, root=ROOT):
    """Backticked repository paths anywhere in the doc that do not exist."""
    problems = []
    for number, line in enumerate(text.splitlines(), 1):
        for path in _REPO_PATH.findall(line):
            if not os.path.exists(os.path.join(root, path)):
                problems.append(f"docs/architecture.md:{number}: no {path}")
    return problems


def _lookup(module, dotted):
    """The object a dotted `_penumbra` name stands for, as stored in its
    module or class (a class's own dict: staticmethod, pybind11's
    instancemethod), or None."""
    target = module
    for part in dotted.split(".")[1:]:
        if not isinstance(target, (type, types.ModuleType)):
            return None
        target = target.__dict__.get(part)
    return target


def resolve(module, dotted):
    """The builtin function behind a cited `_penumbra` name: a module function,
    a static or instance method, or for a class its constructor's `__init__`.
    None when the name does not exist."""
    target = _lookup(module, dotted)
    if isinstance(target, type):
        target = target.__dict__.get("__init__")
    target = getattr(target, "__func__", target)  # staticmethod, instancemethod
    return target if isinstance(target, types.BuiltinFunctionType) else None


def unknown_penumbra(rows, module):
    return [f"{row.where()}: {name} is not in the built _penumbra" for row in rows for name in row.penumbra
            if resolve(module, name) is None]


# ---- calls, recorded while a tool runs -----------------------------------------

def _pass_through(builtin):
    def __init__(self, *args, **kwargs):
        builtin(self, *args, **kwargs)  # called from Python: the profiler sees it
    return __init__


def called_names(module, called):
    """The dotted names of the recorded functions (for messages)."""
    names = []
    for sub_name, sub in [("", module)] + [(k, v) for k, v in vars(module).items()
                                           if isinstance(v, types.ModuleType)]:
        prefix = "_penumbra" + (f".{sub_name}" if sub_name else "")
        for name, value in vars(sub).items():
            members = [(name, value)]
            if isinstance(value, type):
                members = [(f"{name}.{k}", getattr(v, "__func__", v)) for k, v in value.__dict__.items()]
            names += [f"{prefix}.{n}" for n, v in members if isinstance(v, types.BuiltinFunctionType) and v in called]
    return sorted(set(names))


class CallRecorder:
    """Records every `_penumbra` builtin called on this thread while active
    (sys.setprofile 'c_call' events). A call of a class, which CPython's
    profiler does not see, is made visible by a pass-through `__init__` on
    each class in `classes` for as long as the recorder is active."""

    def __init__(self, module, classes=()):
        self.module = module
        # The add-on imports it as penumbra._penumbra (native.py), tests as _penumbra.
        self.prefix = module.__name__
        self.classes = classes
        self.called = set()
        self._saved = []

    def _hook(self, frame, event, arg):
        if event == "c_call" and type(arg) is types.BuiltinFunctionType:
            owner = arg.__module__
            if owner.__class__ is str and owner.startswith(self.prefix):
                self.called.add(arg)

    def __enter__(self):
        for cls in dict.fromkeys(self.classes):
            original = cls.__dict__.get("__init__")
            if isinstance(getattr(original, "__func__", None), types.BuiltinFunctionType):
                self._saved.append((cls, original))
                cls.__init__ = _pass_through(original.__func__)
        self._previous = sys.getprofile()
        sys.setprofile(self._hook)
        return self

    def __exit__(self, *exc):
        sys.setprofile(self._previous)
        for cls, original in self._saved:
            cls.__init__ = original
        self._saved = []
        return False


def cited_classes(rows, module):
    """The classes cited as constructors, for CallRecorder."""
    found = [_lookup(module, name) for row in rows for name in row.penumbra]
    return list(dict.fromkeys(c for c in found if isinstance(c, type)))


def uncalled(rows, module, called):
    """Every `_penumbra` name of the `step` rows whose function is not in `called`."""
    return [f"{row.where()}: {name} was not called" for row in rows if row.kind == "step"
            for name in row.penumbra if resolve(module, name) not in called]
