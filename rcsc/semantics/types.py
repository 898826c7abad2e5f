"""The types of the RCS language and the rules that relate them.

Types are immutable values; the built-in ones are module-level singletons.
`ERROR` is the type of an expression that already produced a diagnostic: it
is compatible with everything so that one mistake is reported once.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rcsc.front.source import Span


@dataclass(frozen=True)
class Type:
    name: str

    def __str__(self) -> str:
        return self.name

    @property
    def is_numeric(self) -> bool:
        return isinstance(self, (IntType, FloatType))

    @property
    def is_int(self) -> bool:
        return isinstance(self, IntType)


@dataclass(frozen=True)
class BoolType(Type):
    pass


@dataclass(frozen=True)
class IntType(Type):
    bits: int
    signed: bool

    @property
    def min(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def max(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1


@dataclass(frozen=True)
class FloatType(Type):
    pass


@dataclass(frozen=True)
class DurationType(Type):
    """A time span, held as whole nanoseconds (i64 in generated code)."""


@dataclass(frozen=True)
class ErrorType(Type):
    pass


@dataclass(frozen=True, eq=False)
class EnumType(Type):
    members: tuple[str, ...] = ()
    span: Span | None = field(default=None, compare=False)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, EnumType) and other.name == self.name

    def __hash__(self) -> int:
        return hash(("enum", self.name))


@dataclass(frozen=True, eq=False)
class RecordType(Type):
    fields: tuple[tuple[str, Type], ...] = ()
    span: Span | None = field(default=None, compare=False)
    # Declared field ranges (`rpm: f64 in 0.0..3000.0`), field name -> Range;
    # filled once the design's constants are known (they may bound a range).
    ranges: dict = field(default_factory=dict, compare=False)

    def field_range(self, name: str):
        return self.ranges.get(name)

    def field_type(self, name: str) -> Type | None:
        for fname, ftype in self.fields:
            if fname == name:
                return ftype
        return None

    def __eq__(self, other: object) -> bool:
        return isinstance(other, RecordType) and other.name == self.name

    def __hash__(self) -> int:
        return hash(("record", self.name))


@dataclass(frozen=True)
class ArrayType(Type):
    """`[elem; size]`: a fixed number (at least 1) of values of one type.

    Values are Python lists; indexing outside 0..size-1 reads the element
    type's zero value and a write there is ignored (docs/language.md §4)."""

    elem: Type = None  # type: ignore[assignment]
    size: int = 1


def array_of(elem: Type, size: int) -> ArrayType:
    return ArrayType(f"[{elem}; {size}]", elem, size)


BOOL = BoolType("bool")
I32 = IntType("i32", 32, True)
I64 = IntType("i64", 64, True)
U32 = IntType("u32", 32, False)
F64 = FloatType("f64")
DURATION = DurationType("duration")
ERROR = ErrorType("{error}")

BUILTIN_TYPES: dict[str, Type] = {t.name: t for t in (BOOL, I32, I64, U32, F64, DURATION)}
INT_TYPES = {"i32": I32, "i64": I64, "u32": U32}


def compatible(expected: Type, actual: Type) -> bool:
    """Whether a value of `actual` may stand where `expected` is required."""
    if expected is actual:  # the usual case: types are mostly singletons
        return True
    if isinstance(expected, ErrorType) or isinstance(actual, ErrorType):
        return True
    return expected == actual
