#!/usr/bin/env python3
"""Lists functions whose body is longer than a limit (default 100 lines).

    scripts/check_function_length.py core            # C++ under core/
    scripts/check_function_length.py plugin addon    # C++ and Python
    scripts/check_function_length.py --limit 80 core/sh/pose_shading.cpp

Prints one line per offender, `path:line: name: N lines`, and exits 1 when
there is one (0 otherwise), so it can run in CI.

A body is the lines strictly between the line of its opening brace and the
line of its closing brace (C++), or from its first statement to its last
line, docstring included (Python). Lambdas and local classes count towards
the function that holds them; nested Python functions are checked on their
own and also count towards the function that holds them.

C++ is scanned, not parsed: comments, string and character literals and
preprocessor lines are blanked, then braces are matched. A brace opens a
function body when it is not already inside one and the text before it (back
to the previous `;`, `{` or `}`) looks like a function head: a name, a
parameter list and then only qualifiers (const, noexcept, override, ...), a
trailing return type or a constructor's initializer list. Braces that
initialize (`= {`, `return {`, `T{...}`, `x_{...}` in an initializer list)
are never bodies. Good enough for this code base; a head it misreads makes a
function invisible to it, never a false alarm on a short function.
"""
from __future__ import annotations

import argparse
import ast
import re
import sys
from dataclasses import dataclass
from pathlib import Path

CPP_SUFFIXES = {".cpp", ".cc", ".cxx", ".hpp", ".hh", ".h", ".inl"}
NOT_FUNCTIONS = {"if", "for", "while", "switch", "catch", "return", "sizeof", "decltype", "alignof", "alignas",
                 "static_assert", "noexcept", "requires", "throw", "co_return", "co_yield"}
TYPE_KEYWORDS = re.compile(r"^(template\s*<.*>\s*)?(namespace|class|struct|union|enum)\b", re.S)
QUALIFIERS = re.compile(r"^(\s|const\b|volatile\b|noexcept\b|override\b|final\b|mutable\b|constexpr\b|&&?)*$")


@dataclass
class Offender:
    path: Path
    line: int
    name: str
    length: int


def blank_cpp(text: str) -> str:
    """Comments, literals and preprocessor lines replaced by spaces (newlines kept)."""
    out = []
    i, n = 0, len(text)
    at_line_start = True
    while i < n:
        c = text[i]
        if at_line_start and c == "#":  # a preprocessor line, with its continuations
            j = i
            while j < n and not (text[j] == "\n" and text[j - 1] != "\\"):
                j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
            continue
        if c == "\n":
            at_line_start = True
            out.append(c)
            i += 1
            continue
        if not c.isspace():
            at_line_start = False
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
        elif c == "R" and text.startswith('"', i + 1) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c in "\"'":
            if c == "'" and i > 0 and text[i - 1].isalnum() and text[i - 1 : i + 2] != "u8'":
                out.append(c)  # a digit separator (1'000'000)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + c if j - i >= 2 else c)
            i = j
        else:
            out.append(c)
            i += 1
    return "".join(out)


def outside_parentheses(head: str) -> str:
    """The head with every (...) group's contents dropped, the parentheses kept."""
    out, depth = [], 0
    for c in head:
        if c == "(":
            if depth == 0:
                out.append("(")
            depth += 1
        elif c == ")":
            depth = max(0, depth - 1)
            if depth == 0:
                out.append(")")
        elif depth == 0:
            out.append(c)
    return "".join(out)


def function_name(head: str) -> str | None:
    """The function's name if `head` (text before a `{`, whitespace folded) is a function head, else None."""
    if "(" not in head:
        return None
    flat = outside_parentheses(head)
    first = flat.index("(")
    before, after = flat[:first], flat[first:]
    name = re.search(r"(~?[A-Za-z_][\w:]*|operator\s*[^\s\w]+|\])\s*(<[^()]*>)?\s*$", before)
    if not name:
        return None
    word = name.group(1).split("::")[-1]
    if word in NOT_FUNCTIONS:
        return None
    if word == "operator" and after.startswith("()"):
        after = after[2:]  # operator()(...)
    if "=" in before and "operator" not in before and word != "]":
        return None  # int x = f(...) {  is no head
    if ")" not in after:
        return None  # inside a call's arguments: f(x, {
    # After the parameter list: qualifiers, `-> type`, or `: member(init), ...`.
    rest = after[after.index(")") + 1 :]
    if QUALIFIERS.match(rest) or re.match(r"^[\s\w&]*->", rest) or \
            (re.match(r"^[\s\w]*:[^:]", rest) and rest.rstrip()[-1:] in (")", "}")):
        return "lambda" if word == "]" else name.group(1)
    return None


def classify(head: str) -> tuple[str, str]:
    """What a `{` opens outside any function: ("body", name), ("init", "") or ("scope", "")."""
    flat = " ".join(head.split())
    if not flat or TYPE_KEYWORDS.match(flat) or flat.startswith("extern"):
        return "scope", ""
    name = function_name(flat)
    if name:
        return "body", name
    if re.search(r"([=,(\[{<>]|\breturn|[\w\]])$", flat):
        return "init", ""  # = {..}, return {..}, T{..}, member_{..}
    return "scope", ""


def cpp_offenders(path: Path, limit: int) -> list[Offender]:
    text = blank_cpp(path.read_text(encoding="utf-8", errors="replace"))
    offenders = []
    # Open braces: (kind, line, name), kind "body", "init" or "scope". An
    # initializer's braces do not end the head they sit in (a constructor's
    # `x_{a}, y_{b} {`), every other brace does.
    stack: list[tuple[str, int, str]] = []
    head_start = 0
    line = 1
    in_body = 0
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == ";":
            head_start = i + 1
        elif c == "{":
            kind, name = ("scope", "") if in_body else classify(text[head_start:i])
            stack.append((kind, line, name))
            in_body += kind == "body"
            if kind != "init":
                head_start = i + 1
        elif c == "}" and stack:
            kind, start, name = stack.pop()
            if kind == "body":
                in_body -= 1
                length = line - start - 1
                if length > limit:
                    offenders.append(Offender(path, start, name, length))
            if kind != "init":
                head_start = i + 1
    return offenders


def python_offenders(path: Path, limit: int) -> list[Offender]:
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    offenders = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            length = node.end_lineno - node.body[0].lineno + 1
            if length > limit:
                offenders.append(Offender(path, node.lineno, node.name, length))
    return offenders


def files_under(paths: list[str]) -> list[Path]:
    found = []
    for p in map(Path, paths):
        candidates = [p] if p.is_file() else sorted(q for q in p.rglob("*") if q.is_file())
        found += [q for q in candidates if q.suffix in CPP_SUFFIXES or q.suffix == ".py"]
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="+", help="files or folders (C++ and Python files inside are checked)")
    parser.add_argument("--limit", type=int, default=100, help="longest body allowed, in lines (default 100)")
    args = parser.parse_args()
    offenders = []
    for path in files_under(args.paths):
        if "__pycache__" in path.parts:
            continue
        offenders += python_offenders(path, args.limit) if path.suffix == ".py" else cpp_offenders(path, args.limit)
    for o in sorted(offenders, key=lambda o: (str(o.path), o.line)):
        print(f"{o.path}:{o.line}: {o.name}: {o.length} lines")
    return 1 if offenders else 0


if __name__ == "__main__":
    sys.exit(main())
