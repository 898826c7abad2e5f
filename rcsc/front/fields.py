"""Field-wise equality and a readable repr, written once for the syntax tree and the model.

The node classes of `rcsc.front.ast` and `rcsc.semantics.model` are
dataclasses.  A dataclass writes the source of its `__init__`, `__repr__`
and `__eq__` and compiles each when its module is imported: for the 85
node classes, 24 ms of every `rcsc` command that reads a design, a tenth
of a re-check after an edit.  So the classes let the dataclass write only
their `__init__` (`@node`, or `@dataclass(repr=False, eq=False)`) and take
equality and repr from `Fields`, which behave as the generated ones do:

- `a == b` when both are of the same class and the tuples of their compared
  fields are equal (a tuple compares an element with itself as equal first,
  so a NaN constant equals itself, as before); another class gives
  NotImplemented;
- the classes stay unhashable (defining `__eq__` without `__hash__` does that);
- `repr` shows the class and each field shown by the dataclass, and `...`
  for a node inside itself.
"""

from __future__ import annotations

import dataclasses
import reprlib
from operator import attrgetter


def node(cls):
    """`@dataclass(slots=True)` for a `Fields` class: only `__init__` is generated."""
    return dataclasses.dataclass(cls, slots=True, repr=False, eq=False)


# Per class: the getter of the tuple of its compared fields, and the names of its shown fields.
_compared: dict[type, object] = {}
_shown: dict[type, tuple[str, ...]] = {}


def _getter(cls: type):
    names = tuple(f.name for f in dataclasses.fields(cls) if f.compare)
    if len(names) == 1:
        one = attrgetter(names[0])
        get = lambda x: (one(x),)  # noqa: E731  (attrgetter of one name gives the bare value)
    elif names:
        get = attrgetter(*names)
    else:
        get = lambda x: ()  # noqa: E731
    _compared[cls] = get
    return get


class Fields:
    """The equality and repr of a dataclass, for dataclasses made with `eq=False, repr=False`."""

    __slots__ = ()

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        get = _compared.get(self.__class__) or _getter(self.__class__)
        return get(self) == get(other)  # type: ignore[operator]

    @reprlib.recursive_repr()
    def __repr__(self) -> str:
        cls = self.__class__
        names = _shown.get(cls)
        if names is None:
            names = _shown[cls] = tuple(f.name for f in dataclasses.fields(cls) if f.repr)
        return f"{cls.__qualname__}(" + ", ".join(f"{n}={getattr(self, n)!r}" for n in names) + ")"
