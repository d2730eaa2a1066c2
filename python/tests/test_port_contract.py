"""The Dr.Jit port's contract with the runtime (issue 42): every Rust name
that a docstring of python/twoscale/drjit/ cites (`Type::method`,
`module::function`, `Type`) exists in runtime/src, and every Rust item whose
doc comment says "Mirrored in python/twoscale/drjit/<module>.py" is cited by
a function of that module. Text only: no extension, no Mitsuba."""

import ast
import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
RUNTIME = ROOT / "runtime" / "src"
PORT = ROOT / "python" / "twoscale" / "drjit"

#: A Rust path in backticks: `a::b`, ``Type::method``.
CITATION = re.compile(r"`+([A-Za-z_]\w*(?:::[A-Za-z_]\w*)+)`+")
#: The marker on the Rust side.
MIRRORED = re.compile(r"[Mm]irrored in ((?:python/twoscale/drjit/\w+\.py(?:,\s*|\s+and\s+)?)+)")
IMPL = re.compile(r"^impl(?:<[^{]*?>)?\s+([\w:<>, ']+?\s+for\s+)?([A-Za-z_]\w*)")
FN = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:const\s+)?(?:unsafe\s+)?fn\s+(\w+)")
TYPE = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:struct|enum|trait|type|const|static)\s+(\w+)")


def _module_path(path):
    """The module path of a runtime source file: bake/halo.rs → (bake, halo)."""
    parts = list(path.relative_to(RUNTIME).with_suffix("").parts)
    if parts[-1] in ("mod", "lib"):
        parts.pop()
    return tuple(parts)


def rust_items():
    """Every fn, type and const of runtime/src: (file, line, name, the type
    of the enclosing impl block or None, the file's module path, whether the
    impl is a trait's)."""
    items = []
    for path in sorted(RUNTIME.rglob("*.rs")):
        module, impl, of_trait = _module_path(path), None, False
        for number, line in enumerate(path.read_text().splitlines()):
            if line.startswith("impl"):
                match = IMPL.match(line)
                impl, of_trait = (match.group(2), bool(match.group(1))) if match else (None, False)
            elif line.startswith("}"):
                impl, of_trait = None, False
            for pattern in (FN, TYPE):
                match = pattern.match(line)
                if match:
                    items.append((path, number, match.group(1), impl, module, of_trait))
    return items


def _contains(outer, inner):
    """Whether `inner` is a contiguous run of `outer`."""
    n = len(inner)
    return any(outer[k:k + n] == inner for k in range(len(outer) - n + 1))


def resolve(citation, items):
    """The items a citation names: the last component, in an impl of the
    last CamelCase component before it (if any), in a file whose module path
    holds the lowercase components (if any); an inherent method rather
    than a trait impl's that forwards to it."""
    parts = citation.split("::")
    if parts[0] == "crate":
        parts = parts[1:]
    name, qualifiers = parts[-1], parts[:-1]
    types = [q for q in qualifiers if q[0].isupper()]
    modules = tuple(q for q in qualifiers if not q[0].isupper())
    owner = types[-1] if types else None
    found = [
        item for item in items
        if item[2] == name
        and (owner is None or item[3] == owner)
        and _contains(item[4], modules)
    ]
    inherent = [item for item in found if not item[5]]
    return inherent or found


def port_citations():
    """(module file name, function or class name or None for the module,
    whether it is a function, citation) for every citation in a docstring of
    the port."""
    out = []
    for path in sorted(PORT.glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef)):
                continue
            for citation in CITATION.findall(ast.get_docstring(node) or ""):
                out.append((path.name, getattr(node, "name", None),
                            isinstance(node, ast.FunctionDef), citation))
    return out


def mirrored_items(items):
    """(item, the port modules its doc comment names) for every Rust item
    whose doc comment says it is mirrored."""
    out = []
    by_line = {(item[0], item[1]): item for item in items}
    for path in sorted(RUNTIME.rglob("*.rs")):
        lines = path.read_text().splitlines()
        for number, line in enumerate(lines):
            match = MIRRORED.search(line) if line.lstrip().startswith("///") else None
            if not match:
                continue
            # The item below the doc comment (past the doc and attributes).
            below = number + 1
            while below < len(lines) and lines[below].lstrip().startswith(("///", "#[")):
                below += 1
            item = by_line.get((path, below))
            modules = re.findall(r"python/twoscale/drjit/(\w+\.py)", match.group(1))
            out.append((path, number, item, modules))
    return out


ITEMS = rust_items()


def test_the_port_cites_names():
    # Guards the test itself: the parsers find what they look for.
    citations = port_citations()
    assert len(citations) > 50
    assert any(c[3] == "TwoScale::lobes" for c in citations)


@pytest.mark.parametrize("module,name,is_function,citation", port_citations())
def test_each_cited_rust_name_exists(module, name, is_function, citation):
    assert resolve(citation, ITEMS), (
        f"python/twoscale/drjit/{module} ({name or 'module docstring'}) cites `{citation}`, "
        "which runtime/src no longer has: update the port's docstring (and the port)")


def test_each_mirrored_rust_item_is_cited_by_its_module():
    marked = mirrored_items(ITEMS)
    assert len(marked) > 40, "the runtime's mirrored functions lost their marker"
    cited = {}
    for module, _, is_function, citation in port_citations():
        if is_function:
            for item in resolve(citation, ITEMS):
                cited.setdefault((item[0], item[1]), set()).add(module)
    for path, number, item, modules in marked:
        where = f"{path.relative_to(ROOT)}:{number + 1}"
        assert item is not None, f"{where}: a 'mirrored in' line not on an item's doc comment"
        for module in modules:
            assert (PORT / module).exists(), f"{where}: names {module}, which does not exist"
            assert module in cited.get((item[0], item[1]), set()), (
                f"{where}: `{item[2]}` says it is mirrored in python/twoscale/drjit/{module}, "
                "but no function there cites it")


def test_each_rust_function_the_port_mirrors_says_so():
    marked = {(path, item[1]): set(modules) for path, _, item, modules in mirrored_items(ITEMS)
              if item is not None}
    for module, name, is_function, citation in port_citations():
        if not is_function:
            continue
        for item in resolve(citation, ITEMS):
            if FN.match(item[0].read_text().splitlines()[item[1]]):
                assert module in marked.get((item[0], item[1]), set()), (
                    f"python/twoscale/drjit/{module} ({name}) mirrors `{citation}` "
                    f"({item[0].relative_to(ROOT)}:{item[1] + 1}), whose doc comment does not "
                    f"say 'Mirrored in python/twoscale/drjit/{module}'")
