"""Counts behind the code-structure review (one name per concept, one place per rule), printed as a table.

Usage: ``python tools/code_metrics.py [SRC]`` (default ``src/skyscatter``). Everything is read from the syntax
trees; nothing is imported. What each line counts:

* numba decorator flag sets: distinct keyword sets of ``numba.njit(...)`` / ``njit(...)`` calls written out in
  the source (a call of a decorator made elsewhere, e.g. ``@kernel``, is not a new flag set), and the modules that
  write such a call;
* jitted functions with 12 or more positional parameters;
* ``_check_*`` helper definitions and the bool-or-int idiom (``isinstance(x, bool)`` written out);
* lazy-import mechanisms: modules defining a module-level ``__getattr__`` by hand or through a helper;
* function-level imports (an ``import`` inside a ``def``) and those with no comment on the line or the line
  above saying why;
* modules writing full references out (a DOI; those of Preetham et al. 1999 and Bruneton & Neyret 2008 apart) and
  mentions of issue numbers;
* parameter names of the atmosphere (annotated ``AtmosphereParameters``) and of the tables (annotated
  ``PrecomputedAtmosphere``), and functions whose ``wavelengths`` parameter accepts a string (a table mode).
"""

from __future__ import annotations

import ast
import collections
import re
import sys
from pathlib import Path

#: DOIs of the two most cited papers: a module holding one writes the full reference out.
DOIS = {"Preetham 1999": "10.1145/311535.311545", "Bruneton 2008": "10.1111/j.1467-8659.2008.01245.x"}


def _is_njit(call: ast.Call) -> bool:
    f = call.func
    return (isinstance(f, ast.Attribute) and f.attr in {"njit", "jit"} and isinstance(f.value, ast.Name)
            and f.value.id == "numba") or (isinstance(f, ast.Name) and f.id == "njit")


def _flags(call: ast.Call) -> str:
    parts = []
    for kw in sorted(call.keywords, key=lambda k: k.arg or ""):
        parts.append(f"{kw.arg}={ast.unparse(kw.value)}")
    return ", ".join(parts)


def main(argv: list[str]) -> int:
    src = Path(argv[1] if len(argv) > 1 else "src/skyscatter")
    flag_sets: collections.Counter[str] = collections.Counter()
    jit_modules: set[str] = set()
    long_sigs: list[str] = []
    checks = bool_int = 0
    lazy: list[str] = []
    fn_imports = uncommented = 0
    refs = collections.Counter()
    issue_mentions = doi_modules = 0
    all_dois: set[str] = set()
    atm_names: collections.Counter[str] = collections.Counter()
    table_names: collections.Counter[str] = collections.Counter()
    wl_str: list[str] = []
    for path in sorted(src.rglob("*.py")):
        text = path.read_text()
        lines = text.splitlines()
        rel = str(path.relative_to(src))
        tree = ast.parse(text)
        for key, doi in DOIS.items():
            refs[key] += doi in text
        all_dois.update(re.findall(r"10\.\d{4,}/[^\s,;)\]\"']+", text))
        doi_modules += bool(re.search(r"10\.\d{4,}/", text))
        issue_mentions += len(re.findall(r"\bissues? \d+", text, flags=re.IGNORECASE))
        bool_int += len(re.findall(r"isinstance\([^()]*, bool\)", text))
        for node in tree.body:
            if isinstance(node, ast.FunctionDef) and node.name == "__getattr__":
                lazy.append(rel)
            if isinstance(node, ast.Assign) and any(isinstance(t, ast.Tuple) and any(
                    isinstance(e, ast.Name) and e.id == "__getattr__" for e in t.elts) for t in node.targets):
                lazy.append(rel)
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and _is_njit(node):
                flag_sets[_flags(node)] += 1
                jit_modules.add(rel)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                if node.name.startswith("_check_") or node.name.startswith("check_"):
                    checks += node.name.startswith("_check_")
                jitted = any(
                    (isinstance(d, ast.Call) and _is_njit(d)) or (isinstance(d, ast.Name) and "jit" in d.id)
                    or (isinstance(d, ast.Attribute) and "jit" in d.attr)
                    or (isinstance(d, ast.Call) and isinstance(d.func, (ast.Name, ast.Attribute))
                        and "jit" in ast.unparse(d.func))
                    or (isinstance(d, ast.Name) and d.id in {"kernel", "helper", "inline", "device"})
                    or (isinstance(d, ast.Attribute) and ast.unparse(d).startswith("jit."))
                    for d in node.decorator_list)
                n_pos = len(node.args.posonlyargs) + len(node.args.args)
                if jitted and n_pos >= 12:
                    long_sigs.append(f"{rel}:{node.name}({n_pos})")
                for a in [*node.args.posonlyargs, *node.args.args, *node.args.kwonlyargs]:
                    ann = ast.unparse(a.annotation) if a.annotation is not None else ""
                    if "AtmosphereParameters" in ann and "PrecomputedAtmosphere" not in ann:
                        atm_names[a.arg] += 1
                    elif "PrecomputedAtmosphere" in ann:
                        table_names[a.arg] += 1
                    if a.arg == "wavelengths" and "str" in ann:
                        wl_str.append(f"{rel}:{node.name}")
                for sub in ast.walk(node):
                    if isinstance(sub, (ast.Import, ast.ImportFrom)) and sub is not node:
                        if isinstance(sub, ast.ImportFrom) and sub.module == "__future__":
                            continue
                        fn_imports += 1
                        here = lines[sub.lineno - 1]
                        above = lines[sub.lineno - 2].strip() if sub.lineno > 1 else ""
                        if "#" not in here and not above.startswith("#"):
                            uncommented += 1
    rows = [
        ("numba flag sets written out", len(flag_sets)),
        ("modules writing numba.njit(...)", len(jit_modules)),
        ("jitted functions with >= 12 positional parameters", len(long_sigs)),
        ("_check_* helpers", checks),
        ("isinstance(x, bool) written out", bool_int),
        ("lazy-import mechanisms (module __getattr__)", len(lazy)),
        ("function-level imports", fn_imports),
        ("  of which without a comment", uncommented),
        *((f"modules writing the {k} DOI", refs[k]) for k in DOIS),
        ("modules writing any DOI", doi_modules),
        ("issue numbers mentioned in src", issue_mentions),
        ("parameter names of AtmosphereParameters", dict(atm_names)),
        ("parameter names of PrecomputedAtmosphere", dict(table_names)),
        ("functions taking wavelengths as a str mode", len(wl_str)),
    ]
    for name, value in rows:
        print(f"{name:<55s} {value}")
    if "-v" in argv:
        print("\nflag sets:")
        for fs, n in flag_sets.most_common():
            print(f"  {n:3d}  {fs}")
        print("lazy:", ", ".join(lazy))
        print("long signatures:", ", ".join(long_sigs))
        print("wavelengths as str:", ", ".join(wl_str))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
