"""One codec for the study's records: a record's plain ``params()`` from its fields, and back.

A record is a frozen dataclass that derives from :class:`Record`; each field says once
how it is written, in its ``metadata`` (made by the functions below), and
:meth:`Record.params` and :meth:`Record.from_params` follow those declarations. The
params are what a rule passes to its job (Snakemake compares their ``repr``, so the
keys come in the order of the fields) and what a file stores and a key hashes, in
the configuration's units::

    @dataclass(frozen=True)
    class Cell(Record):
        sigma: float = si(UM, "sigma_um")           # [m], written in um
        size: tuple = si_pair(MM, "size_mm")        # (Lx, Ly) [m]; a scalar reads square
        grid: tuple[int, int] = grid()              # (nx, ny), a list
        method: Generator = enum(Generator)         # an Enum, its value
        geometry: Geometry = record(Geometry)       # a record, its params()
        geometry_key: str = key_of("geometry")      # written, not stored
        cap: float | None = si(MPA, "cap_MPa", omit=DEFAULT)   # left out at its default

A field without metadata is written as it is and read with the cast its annotation
names (``float``, ``int``, ``str``, ``bool``, optionally ``| None``, or a ``tuple`` of
one of them). A key that is absent reads as the field's default, so a key left out at
its default keeps the params (and the keys hashed from them) of the records from
before it. The unit conversions are :func:`in_unit` (SI to a unit, to 12 significant
digits: a value read from the configuration comes back as written) and
:func:`from_unit`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from enum import Enum
from types import SimpleNamespace

from roughcontact.units import MM

__all__ = ["DEFAULT", "Record", "as_pair", "constant", "enum", "field", "from_unit",
           "grid", "grid_pair", "in_unit", "in_units", "key_of", "pairs", "record", "si",
           "si_pair", "si_tuple", "unwritten"]


def in_unit(value: float, unit: float) -> float:
    """``value`` [SI] in ``unit`` (e.g. :data:`~roughcontact.units.MM`), to 12 significant
    digits.

    The form of a value for people and files (parameters, keys, labels,
    table columns): a value read from the configuration comes back as it was
    written, free of the rounding of the conversion.
    """
    return float(f"{value / unit:.12g}")


def in_units(values, unit: float = MM) -> list[float] | None:
    """SI values as a list in ``unit`` (:func:`in_unit`; None stays None)."""
    return None if values is None else [in_unit(v, unit) for v in values]


def from_unit(values, unit: float = MM) -> tuple[float, ...] | None:
    """Values written in ``unit`` (the configuration's) as a tuple in SI units (None stays
    None)."""
    return None if values is None else tuple(float(v) * unit for v in values)


def as_pair(value) -> tuple:
    """``(a, b)`` of a pair, or ``(value, value)`` of a scalar (the configuration allows both)."""
    if isinstance(value, list | tuple):
        return (value[0], value[1])
    return (value, value)


def grid_pair(value) -> tuple[int, int]:
    """A grid (nx, ny) of a pair or of a scalar (square)."""
    return tuple(int(v) for v in as_pair(value))


# ---------------------------------------------------------------------------
# How a field is written


#: ``omit=DEFAULT``: a field left out of the params where it holds its default.
DEFAULT = "default"


@dataclasses.dataclass(frozen=True)
class _Spec:
    """How a field is written: under ``key`` (None: the field's name; in the sub-dict
    ``group``), ``write`` its value to a plain one and ``read`` it back (None: the cast
    of its annotation); ``flatten``: ``write`` gives entries merged into the params and
    ``read`` takes the whole params; ``omit(value)``: left out; ``when(record)``: written
    and read only where true (of the fields before it, when read); ``derived(record)``:
    a value written, not stored."""

    key: str | None = None
    write: Callable | None = None
    read: Callable | None = None
    flatten: bool = False
    group: str | None = None
    omit: Callable | None = None
    when: Callable | None = None
    derived: Callable | None = None


_PLAIN = _Spec()


def field(*, key: str | None = None, write: Callable | None = None,
          read: Callable | None = None, flatten: bool = False, group: str | None = None,
          omit=None, when: Callable | None = None, **kwargs):
    """A dataclass field written as declared (:class:`_Spec`); ``omit``: a predicate of
    the value, or :data:`DEFAULT` (left out at the field's default); ``kwargs``:
    :func:`dataclasses.field`'s (``default``, ``compare``, ...)."""
    if omit == DEFAULT:
        default = kwargs["default"]

        def omit(value):
            return value == default

    spec = _Spec(key, write, read, flatten, group, omit, when)
    return dataclasses.field(metadata={"codec": spec}, **kwargs)


def _optional(convert: Callable) -> Callable:
    return lambda value: None if value is None else convert(value)


def si(unit: float, key: str, **kwargs):
    """A value [SI] written in ``unit`` under ``key`` (``sigma_um``); None stays None."""
    return field(key=key, write=_optional(lambda v: in_unit(v, unit)),
                 read=_optional(lambda v: float(v) * unit), **kwargs)


def si_pair(unit: float, key: str, **kwargs):
    """A pair (x, y) [SI] written as a list in ``unit``; read from a pair or a scalar."""
    return field(key=key, write=_optional(lambda v: in_units(v, unit)),
                 read=_optional(lambda v: from_unit(as_pair(v), unit)), **kwargs)


def si_tuple(unit: float, key: str, **kwargs):
    """A tuple of values [SI] written as a list in ``unit``."""
    return field(key=key, write=_optional(lambda v: in_units(v, unit)),
                 read=_optional(lambda v: from_unit(v, unit)), **kwargs)


def grid(**kwargs):
    """A grid (nx, ny) written as a list; read from a pair or a scalar (square)."""
    return field(write=_optional(list), read=_optional(grid_pair), **kwargs)


def enum(kind: type[Enum], **kwargs):
    """An :class:`~enum.Enum` of ``kind`` written as its value."""
    return field(write=lambda v: v.value, read=kind, **kwargs)


def pairs(cast: Callable | None = None, sort: bool = False, **kwargs):
    """``((name, value), ...)`` written as a dict; read with each value ``cast`` (None
    stays None), in the dict's order or ``sort``-ed by name; None stays None."""
    value = _optional(cast) if cast is not None else (lambda v: v)

    def read(written):
        items = tuple((name, value(v)) for name, v in written.items())
        return tuple(sorted(items)) if sort else items

    return field(write=_optional(dict), read=_optional(read), **kwargs)


def constant(value, **kwargs):
    """A value every record of its type has (not an argument): written, never read."""
    write = (lambda v: v.value) if isinstance(value, Enum) else None
    return field(write=write, init=False, default=value, **kwargs)


def unwritten(**kwargs):
    """A field that is no parameter: neither written nor read (its default on reading)."""
    return field(when=lambda record: False, **kwargs)


def key_of(name: str):
    """The file key of the record in the field ``name`` (its ``key``): written where it
    is declared, not stored (an attribute it is not)."""
    spec = _Spec(derived=lambda r: getattr(r, name).key)
    return dataclasses.field(init=False, repr=False, compare=False, metadata={"codec": spec})


def record(kind, *, null=None, flatten: bool = False, **kwargs):
    """A record written as its ``params()``, read by ``kind`` (a :class:`Record` type, or a
    function of the params); ``null``: the record's null object, written as None (each of
    ``kind``'s keys None, flattened); ``flatten``: its params merged into the parent's."""
    decode = kind.from_params if isinstance(kind, type) else kind
    if flatten:
        keys = param_keys(kind)

        def write(value):
            return dict.fromkeys(keys) if value is null and null is not None else value.params()

        def read(params):
            return null if null is not None and params[keys[0]] is None else decode(params)
    else:
        def write(value):
            return None if value is None or value is null else value.params()

        def read(params):
            return null if params is None else decode(params)
    return field(write=write, read=read, flatten=flatten, **kwargs)


# ---------------------------------------------------------------------------
# Writing and reading


def _spec(f: dataclasses.Field) -> _Spec:
    return f.metadata.get("codec", _PLAIN)


def _written(spec: _Spec, f: dataclasses.Field) -> str:
    return spec.key or f.name


def param_keys(kind: type) -> list[str]:
    """The keys of a record type's params, in their order (a flattened field's, its
    record's)."""
    return [_written(_spec(f), f) for f in dataclasses.fields(kind) if not _spec(f).flatten]


def encode(record) -> dict:
    """The plain params of ``record`` (a dataclass of declared fields), in field order."""
    params = {}
    for f in dataclasses.fields(record):
        spec = _spec(f)
        value = spec.derived(record) if spec.derived else getattr(record, f.name)
        if (spec.when and not spec.when(record)) or (spec.omit and spec.omit(value)):
            continue
        target = params.setdefault(spec.group, {}) if spec.group else params
        written = spec.write(value) if spec.write else _plain(value)
        if spec.flatten:
            target.update(written)
        else:
            target[_written(spec, f)] = written
    return params


def decode(kind: type, params):
    """The record of type ``kind`` of its plain ``params`` (:func:`encode`'s; a key absent:
    the field's default; keys of no field are ignored)."""
    values = SimpleNamespace()
    for f in dataclasses.fields(kind):
        spec = _spec(f)
        if not f.init:
            continue
        source = params[spec.group] if spec.group else params
        key = _written(spec, f)
        if spec.when and not spec.when(values):
            value = f.default
        elif spec.flatten:
            value = spec.read(source)
        elif key in source:
            value = (spec.read or _cast(f.type))(source[key])
        elif f.default is not dataclasses.MISSING:
            value = f.default
        else:
            raise KeyError(key)
        setattr(values, f.name, value)
    return kind(**vars(values))


def _plain(value):
    """A value without a declared conversion as params hold it (a tuple as a list)."""
    return list(value) if isinstance(value, tuple) else value


_CASTS = {"float": float, "int": int, "str": str, "bool": bool}


def _cast(annotation: str) -> Callable:
    """The cast a field's annotation names (module docstring); none for other types."""
    text = annotation.removesuffix(" | None")
    optional = text != annotation
    if text.startswith("tuple[") and text.endswith("]"):
        inner = {part.strip() for part in text[6:-1].split(",")} - {"..."}
        item = _CASTS.get(inner.pop()) if len(inner) == 1 else None
        cast = (lambda v: tuple(v)) if item is None else (lambda v: tuple(item(x) for x in v))
    else:
        cast = _CASTS.get(text, lambda v: v)
    return _optional(cast) if optional else cast


class Record:
    """A record whose params are its declared fields' (:func:`encode`, :func:`decode`)."""

    def params(self) -> dict:
        """The record as its rule passes it and its file stores it (configuration units)."""
        return encode(self)

    @classmethod
    def from_params(cls, params):
        """The record of its :meth:`params` (or of a validated configuration section)."""
        return decode(cls, params)

    #: A settings record reads its validated configuration section alike.
    from_section = from_params
