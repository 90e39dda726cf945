"""The package is a stack: every import points down or sideways, never up, and none closes a
cycle. Parsed from the source (no import runs), top-level and function-level imports alike."""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "sh_lighting"

# Layer of each part, bottom to top. A module may import its own part and any part below.
LAYERS = {
    "choices": 0,
    "core": 0,
    "formats": 1,
    "blender.data": 2,
    "blender.world": 3,
    "blender.shading": 4,
    # the features: each a package on the layers below, none importing another's upward
    "blender.design": 5,
    "blender.transfer": 5,
    "blender.photo": 5,
    "blender.presets": 5,
    "blender.luminaire": 5,
    "blender.world_edit": 5,
    "blender.ui": 6,
    "blender": 6,  # blender/__init__.py registers ui's modules
    "api": 7,
    "cli": 8,
    "__main__": 9,
    "": 9,  # sh_lighting/__init__.py registers blender and cli.command
}
# What the command line may use: the façade and the bpy-free parts, never blender.* itself.
CLI_MAY_IMPORT = ("api", "choices", "core", "formats", "cli")


def part_of(module):
    """The LAYERS key a dotted module name (without "sh_lighting.") belongs to."""
    parts = module.split(".")
    for length in range(len(parts), -1, -1):
        key = ".".join(parts[:length])
        if key in LAYERS:
            return key
    raise KeyError(module)


def modules():
    """{dotted name without "sh_lighting.": path} of every module in the package."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def imports(name, path, known):
    """The package's modules that ``name`` imports (resolved against ``known``)."""
    is_package = path.name == "__init__.py"
    package = name.split(".") if is_package else name.split(".")[:-1]
    if name == "":
        package = []
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)]
                target = base + (node.module.split(".") if node.module else [])
            elif node.module and node.module.split(".")[0] == "sh_lighting":
                target = node.module.split(".")[1:]
            else:
                continue
            dotted = ".".join(target)
            for alias in node.names:
                child = f"{dotted}.{alias.name}" if dotted else alias.name
                found.add(child if child in known else dotted)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "sh_lighting":
                    found.add(".".join(alias.name.split(".")[1:]))
    found.discard(name)
    return {module for module in found if module in known}


@pytest.fixture(scope="module")
def graph():
    known = modules()
    return {name: imports(name, path, known) for name, path in known.items()}


def test_every_module_has_a_layer(graph):
    for name in graph:
        part_of(name)


def test_no_import_points_up(graph):
    upward = [f"{name} -> {target}" for name, targets in graph.items() for target in targets
              if LAYERS[part_of(target)] > LAYERS[part_of(name)]]
    assert upward == []


def test_the_command_line_uses_only_the_api(graph):
    reaching = [f"{name} -> {target}" for name, targets in graph.items()
                if part_of(name) == "cli" for target in targets
                if part_of(target).split(".")[0] not in CLI_MAY_IMPORT]
    assert reaching == []


def find_cycle(graph):
    """One import cycle of ``graph`` as a list of modules (first == last), or None."""
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == "open":
                return stack[stack.index(target):] + [target]
            if target not in state:
                found = visit(target)
                if found:
                    return found
        stack.pop()
        state[node] = "done"
        return None

    for node in sorted(graph):
        if node not in state:
            found = visit(node)
            if found:
                return found
    return None


def test_no_cycle(graph):
    assert find_cycle(graph) is None


def test_the_checks_can_fail():
    """A made-up graph with a cycle and an upward arrow is caught by both checks."""
    made_up = {"core.a": {"formats.b"}, "formats.b": {"core.a"}}
    assert find_cycle(made_up) == ["core.a", "formats.b", "core.a"]
    assert LAYERS[part_of("formats.b")] > LAYERS[part_of("core.a")]
