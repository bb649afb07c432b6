"""Scenario YAML parsing: PyYAML's safe loader without its two traps for hand-written files.

PyYAML keeps the last of two equal mapping keys without a word, and its composer recurses
once per nesting level, so a file nested a few thousand levels deep ends in a
``RecursionError``. :func:`load_yaml` rejects both with a clear message.
"""

from __future__ import annotations

from typing import Any

import yaml

#: Deepest nesting of mappings and lists a scenario may have (the schema needs 5).
MAX_YAML_DEPTH = 32


class _UniqueKeyLoader(yaml.SafeLoader):
    """A SafeLoader that rejects a mapping key given twice (PyYAML keeps the last one)."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: set = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if isinstance(key, (str, int, float, bool)) or key is None:
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        "while constructing a mapping",
                        node.start_mark,
                        f"found duplicate key {key!r}",
                        key_node.start_mark,
                    )
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _depth_ok(text: str) -> None:
    """Refuse nesting deeper than :data:`MAX_YAML_DEPTH` before the recursive parser sees it."""
    depth = 0
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            depth += 1
            if depth > MAX_YAML_DEPTH:
                raise ValueError(f"nested deeper than {MAX_YAML_DEPTH} levels")
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            depth -= 1


def load_yaml(text: str) -> Any:
    """Parse scenario YAML safely: no duplicate keys, bounded nesting.

    Raises
    ------
    yaml.YAMLError
        Malformed YAML or a duplicate key.
    ValueError
        Nesting deeper than :data:`MAX_YAML_DEPTH`.
    """
    _depth_ok(text)
    return yaml.load(text, Loader=_UniqueKeyLoader)  # a SafeLoader subclass: no objects
