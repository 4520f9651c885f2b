"""YAML as users write it: scientific notation is a number, a repeated key is an error.

PyYAML follows YAML 1.1, whose float pattern needs a dot: ``1e-6`` and ``1e300`` load as
strings. :class:`Loader` adds the YAML 1.2 / Python decimal forms (``1e-6``, ``1E5``, ``-2.5e+3``,
``1.e5``, ``1_000.5``); words such as ``inf`` and ``nan`` stay strings here (a scene's ``name``
may be any word) and the number validator reads them (:func:`bouncedisk.model.params.number`).
Every scene file, ``--set`` value and curve sidecar is read with :func:`load`.
"""

from __future__ import annotations

import re

import yaml

from .errors import InputError

_DIGITS = r"[0-9](?:_?[0-9])*"
#: Decimal floats with an exponent or a dot (integers stay integers).
FLOAT_RE = re.compile(
    rf"""^[-+]?(?:
        {_DIGITS}\.(?:{_DIGITS})?(?:[eE][-+]?{_DIGITS})?   # 1.  1.5  1.5e3  1.e3
      | \.{_DIGITS}(?:[eE][-+]?{_DIGITS})?                 # .5  .5e-3
      | {_DIGITS}[eE][-+]?{_DIGITS}                        # 1e-6  1E300
    )$""",
    re.X,
)


class Loader(yaml.SafeLoader):
    """Safe loader that reads every decimal float Python's ``float()`` reads."""


# resolvers are tried in order for a scalar's first character: put ours first
Loader.yaml_implicit_resolvers = {
    k: list(v) for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
for _ch in "-+0123456789.":
    Loader.yaml_implicit_resolvers.setdefault(_ch, []).insert(
        0, ("tag:yaml.org,2002:float", FLOAT_RE)
    )


def _construct_float(loader: yaml.SafeLoader, node: yaml.Node) -> float:
    text = loader.construct_scalar(node)
    if FLOAT_RE.match(text):
        return float(text)
    return loader.construct_yaml_float(node)


Loader.add_constructor("tag:yaml.org,2002:float", _construct_float)


#: Most values a document may hold once its aliases are expanded (a scene has about a hundred).
MAX_EXPANDED_NODES = 100_000


def _expanded_size(node: yaml.Node, source: str) -> int:
    """Number of values ``node`` holds with every alias expanded, counted without expanding.

    Aliases share one node object, so the count is memoized per node: linear in the file's size
    even for a "billion laughs" document (nested aliases, each repeating the one before).

    Raises
    ------
    InputError
        The expansion exceeds :data:`MAX_EXPANDED_NODES`.
    """
    sizes: dict[int, int] = {}
    stack: list[tuple[yaml.Node, bool]] = [(node, False)]
    while stack:
        n, done = stack.pop()
        if not done and id(n) in sizes:
            continue
        children = []
        if isinstance(n, yaml.MappingNode):
            children = [c for kv in n.value for c in kv]
        elif isinstance(n, yaml.SequenceNode):
            children = list(n.value)
        if not done:
            sizes[id(n)] = -1  # open: a child still open when n closes is an ancestor
            stack.append((n, True))
            stack.extend((c, False) for c in children if id(c) not in sizes)
            continue
        if any(sizes.get(id(c)) == -1 for c in children):  # a child still open: an ancestor
            raise InputError(
                source,
                "",
                "a YAML alias (*name) refers to a value that holds it (`a: &a [*a]`): a "
                "recursive structure is no scene; write the values out",
            )
        total = 1 + sum(sizes.get(id(c), 1) for c in children)
        sizes[id(n)] = total
        if total > MAX_EXPANDED_NODES:
            raise InputError(
                source,
                "",
                f"YAML aliases (*name) expand to more than {MAX_EXPANDED_NODES:,} values; a "
                "scene needs a few hundred: write the values out, or use fewer nested aliases",
            )
    return sizes[id(node)]


def _check_duplicates(node: yaml.Node, source: str, path: str) -> None:
    """Raise :class:`InputError` naming the first key given twice in one mapping."""
    if isinstance(node, yaml.MappingNode):
        seen: dict[str, int] = {}
        for key, value in node.value:
            if isinstance(key, yaml.ScalarNode) and key.tag != "tag:yaml.org,2002:merge":
                name = str(key.value)
                dotted = f"{path}.{name}" if path else name
                if name in seen:
                    raise InputError(
                        source,
                        dotted,
                        f"duplicate key (lines {seen[name]} and {key.start_mark.line + 1}); "
                        "give each key once",
                    )
                seen[name] = key.start_mark.line + 1
                _check_duplicates(value, source, dotted)
            else:
                _check_duplicates(value, source, path)
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _check_duplicates(item, source, f"{path}[{i}]")


def load(text: str, source: str = "<yaml>", path: str = ""):
    """Parse one YAML document with :class:`Loader`, refusing duplicate keys.

    Raises
    ------
    yaml.YAMLError
        Malformed YAML (the caller reports the line).
    InputError
        A key given twice in one mapping (names the dotted key), aliases that expand to more
        than :data:`MAX_EXPANDED_NODES` values or refer to a value that holds them, or nesting
        deeper than Python's recursion limit.
    """
    loader = Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _expanded_size(node, source)  # before any walk of the expanded document
        _check_duplicates(node, source, path)
        return loader.construct_document(node)
    except RecursionError:  # PyYAML composes and constructs recursively
        raise InputError(
            source, "", "YAML nested too deeply (a scene nests a few levels): malformed YAML"
        ) from None
    finally:
        loader.dispose()
