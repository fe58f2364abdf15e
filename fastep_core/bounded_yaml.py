"""YAML loading with bounds: PyYAML's safe loader, but a document is checked as a node graph before it is built.

``yaml.safe_load`` never runs code, but it builds whatever the text describes: a 500-byte "billion laughs"
file (nine aliases of nine aliases of ...) describes 10^9 list items; they are shared while loading, so the
harm comes later, from anything that walks or prints the value (an error message with its ``repr`` hung every
tool, or ended in MemoryError). 1000 nested brackets overflow the composer's recursion (RecursionError), a
5000-digit integer exceeds Python's int conversion limit (ValueError), and explicit tags such as ``!!int abc``
or a date like ``2001-02-30`` raise plain Python exceptions. Here the text is composed into PyYAML's node graph
(nesting checked as it is composed), the graph is measured as if every alias were expanded (aliases, nodes,
depth, cycles) and only then constructed; every refusal is a ``yaml.YAMLError`` with the line and column.

YAML 1.1 numbers that do not mean what their digits say are not turned into numbers either: ``045`` is octal
37, ``50:00`` is base 60 (3000), and ``08`` is text. They become :class:`MisreadNumber`, a ``str`` carrying
the advice, so every place that expects a number refuses them and can say why. A leading zero that changes
nothing (``05``, ``00``) loads as the number, as before.
"""

from __future__ import annotations

import re
from typing import Any

import yaml
from yaml.constructor import ConstructorError
from yaml.error import Mark
from yaml.nodes import MappingNode, Node, ScalarNode, SequenceNode

__all__ = ['MAX_ALIASES', 'MAX_BYTES', 'MAX_DEPTH', 'MAX_INTEGER_DIGITS', 'MAX_NODES', 'LimitError',
           'MisreadNumber', 'load']

MAX_BYTES = 1024 * 1024
"""Largest document (bytes): 12,000-20,000 obstacles, ten times what the planners are measured with. Pure-Python
PyYAML reads 0.07-0.13 MB/s on a loaded 2-core machine (1 MB: 8-15 s), time in which a node cannot be stopped
(rclpy holds SIGINT), so the bound is also on that. The densest such file has ~500,000 nodes: within MAX_NODES,
which therefore only aliases can reach."""
MAX_DEPTH = 64
"""Deepest nesting of collections, counted through aliases (a scenario needs 7: obstacles[i].motion.waypoints[j])."""
MAX_ALIASES = 10_000
"""Most aliases (``*name``) in one document."""
MAX_NODES = 1_000_000
"""Most nodes (scalars, keys, lists, mappings) the document holds with every alias expanded."""
MAX_INTEGER_DIGITS = 4300
"""Longest integer (digits): Python's own limit for converting text to int (sys.get_int_max_str_digits)."""

_INT_TAG = 'tag:yaml.org,2002:int'
_FLOAT_TAG = 'tag:yaml.org,2002:float'
_STR_TAG = 'tag:yaml.org,2002:str'
_LEADING_ZERO = re.compile(r'[-+]?0[0-9_]+')   # 045 (octal in YAML 1.1), 08 (text in YAML 1.1)
# Exceptions PyYAML's constructors let through for bad scalars: '!!int abc', '!!bool maybe', '2001-02-30',
# '!!timestamp x', '!!int ""'.
_CONSTRUCTOR_SLIPS = (ValueError, TypeError, KeyError, IndexError, AttributeError, OverflowError)


class LimitError(yaml.MarkedYAMLError):
    """The document is beyond one of the limits above (or describes a cycle)."""


class MisreadNumber(str):
    """A plain scalar YAML 1.1 reads as another number than its digits say (045, 50:00) or as text (08).

    It is kept as its text, so anything that needs a number refuses it, and can say why: ``reading`` is what
    YAML 1.1 makes of it ('the octal number 37'), ``fix`` what to write instead.
    """

    reading: str
    fix: str

    def __new__(cls, text: str, reading: str, fix: str) -> MisreadNumber:
        self = super().__new__(cls, text)
        self.reading, self.fix = reading, fix
        return self

    def __reduce__(self) -> tuple[type[MisreadNumber], tuple[str, str, str]]:   # copy and pickle keep both
        return MisreadNumber, (str(self), self.reading, self.fix)

    @property
    def advice(self) -> str:
        """'YAML 1.1 reads 045 as the octal number 37: write 45 without the leading zero'."""
        return f'YAML 1.1 reads {self} as {self.reading}: {self.fix}'


def _digits_of(text: str) -> str:
    """The digits of an integer scalar: no sign, no underscores, no 0x/0b prefix."""
    body = text.replace('_', '').lstrip('+-')
    return body[2:] if body[:2] in ('0x', '0b') else body


def _without_leading_zero(text: str) -> str:
    """045 -> 45, -0_45 -> -45: the decimal number a reader sees in digits with a leading zero."""
    digits = text.replace('_', '').lstrip('+-').lstrip('0') or '0'
    return f'-{digits}' if text.startswith('-') else digits


class BoundedLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses documents beyond the limits before it builds any Python value."""

    def __init__(self, stream: str | bytes) -> None:
        super().__init__(stream)
        self._depth = 0      # collections open around the node being composed
        self._aliases = 0

    # -- composing: nesting and alias count, checked while the node graph is built (the composer recurses)

    def compose_node(self, parent: Node | None, index: int) -> Node | None:
        event = self.peek_event()  # type: ignore[no-untyped-call]  # PyYAML's stub leaves it untyped
        mark = event.start_mark if isinstance(event.start_mark, Mark) else None   # always one: pure Python
        if isinstance(event, yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise LimitError(None, None, f'more than {MAX_ALIASES} aliases (*name)', mark)
        if not isinstance(event, yaml.CollectionStartEvent):
            return super().compose_node(parent, index)
        if self._depth >= MAX_DEPTH:
            raise LimitError(None, None, f'collections nested deeper than {MAX_DEPTH} levels', mark)
        self._depth += 1
        try:
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    # -- constructing: numbers YAML 1.1 misreads, integers too long, exceptions PyYAML lets through

    def construct_object(self, node: Node, deep: bool = False) -> Any:
        try:
            return super().construct_object(node, deep)
        except _CONSTRUCTOR_SLIPS as exc:
            text = str(node.value) if isinstance(node, ScalarNode) else ''
            shown = text if len(text) <= 40 else text[:37] + '...'
            raise ConstructorError(None, None, f'cannot read {shown!r} as {node.tag} '
                                   f'({type(exc).__name__}: {str(exc)[:100]})', node.start_mark) from None

    def construct_bounded_int(self, node: ScalarNode) -> int | MisreadNumber:
        text = self.construct_scalar(node)
        digits = _digits_of(text)
        if len(digits) > MAX_INTEGER_DIGITS:
            raise LimitError(None, None, f'an integer of {len(digits)} digits (at most {MAX_INTEGER_DIGITS})',
                             node.start_mark)
        value = self.construct_yaml_int(node)
        if ':' in text:
            return MisreadNumber(text, f'{value} (base 60, like a clock time)', 'write the number itself')
        if _LEADING_ZERO.fullmatch(text) and value != int(_without_leading_zero(text)):
            return MisreadNumber(text, f'the octal number {value}',
                                 f'write {_without_leading_zero(text)} without the leading zero')
        return value

    def construct_bounded_float(self, node: ScalarNode) -> float | MisreadNumber:
        value = self.construct_yaml_float(node)
        text = self.construct_scalar(node)
        if ':' in text:
            return MisreadNumber(text, f'{value:g} (base 60, like a clock time)', 'write the number itself')
        return value

    def construct_bounded_str(self, node: ScalarNode) -> str:
        text = self.construct_scalar(node)
        if node.style is None and _LEADING_ZERO.fullmatch(text):   # plain 08, 09: not octal, so text
            return MisreadNumber(text, 'text (a leading zero means octal, and it is not octal)',
                                 f'write {_without_leading_zero(text)} without the leading zero')
        return text


BoundedLoader.add_constructor(_INT_TAG, BoundedLoader.construct_bounded_int)
BoundedLoader.add_constructor(_FLOAT_TAG, BoundedLoader.construct_bounded_float)
BoundedLoader.add_constructor(_STR_TAG, BoundedLoader.construct_bounded_str)


def _children(node: Node) -> list[Node]:
    if isinstance(node, SequenceNode):
        return list(node.value)
    if isinstance(node, MappingNode):
        return [item for pair in node.value for item in pair]
    return []


def check_expanded(root: Node) -> None:
    """Refuse a node graph that, with every alias expanded, holds more than MAX_NODES nodes, nests deeper than
    MAX_DEPTH, or contains itself (``&a [*a]``). Iterative and memoised: a shared node is measured once."""
    done: dict[int, tuple[int, int]] = {}    # id(node) -> (nodes, depth) with aliases expanded, capped
    open_: set[int] = set()                   # on the current path: meeting one again is a cycle
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if children_done:
            open_.discard(key)
            measured = [done[id(child)] for child in _children(node)]
            nodes = min(MAX_NODES + 1, 1 + sum(n for n, _ in measured))
            depth = 1 + max((d for _, d in measured), default=0) if not isinstance(node, ScalarNode) else 0
            if nodes > MAX_NODES:
                raise LimitError(None, None, f'more than {MAX_NODES} nodes once its aliases are expanded',
                                 node.start_mark)
            if depth > MAX_DEPTH:
                raise LimitError(None, None, f'collections nested deeper than {MAX_DEPTH} levels once its aliases '
                                 'are expanded', node.start_mark)
            done[key] = (nodes, depth)
            continue
        if key in done:
            continue
        if key in open_:
            raise LimitError(None, None, 'an alias refers to a collection that contains it', node.start_mark)
        open_.add(key)
        stack.append((node, True))
        stack.extend((child, False) for child in _children(node) if id(child) not in done)


def load(text: bytes | str) -> Any:
    """The one document in ``text`` (None when empty), or a ``yaml.YAMLError`` saying why not (with a mark)."""
    if len(text) > MAX_BYTES:
        raise LimitError(None, None, f'{len(text)} bytes, more than {MAX_BYTES} ({MAX_BYTES // 2 ** 20} MiB)', None)
    loader = BoundedLoader(text)
    try:
        root = loader.get_single_node()
        if root is None:
            return None
        check_expanded(root)
        return loader.construct_document(root)
    finally:
        loader.dispose()
