"""Named records for compiled code: numba structrefs defined once, built by name.

A record is a mutable struct that compiled functions take as it is (numba's
``structref``): the agent's state (ebrl.steps.AgentRecord), a fallback's
(ebrl.intrinsic.FallbackRecord), a realisation's (tasks.realisations.REALISATIONS),
the task's random stream (tasks.kernels.stream.Stream), the compiled loop's
(experiments.running.fused.Sensing). Each is
declared as

    @records.record("buffer", "cursor", "has_gauss", "gauss")
    class Stream(records.Record):
        '''What it holds.'''

    Stream.constructor = njit(cache=True)(lambda *values: Stream(*values))

and built by name, ``Stream.build(buffer=..., cursor=0, has_gauss=0, gauss=0.0)``: a
missing or unknown name is a TypeError naming it. Fields are read by name in compiled
code (``st.cursor``) and, from Python, through small compiled getters.

A function called with records step after step from Python (ebrl.Agent's act and learn)
is called through `direct`: numba's dispatcher types every argument at every call, and a
record's type is found in Python (about 0.75 us a record, where an array costs 0.1;
docs/speed.md), while the compiled version's own entry point only unboxes it.

Why each record states its own constructor, a line in its own module: numba's own
(StructRefProxy's ``__new__``) compiles anew in every process (about 0.3 s a record, in
every worker), while an ``@njit(cache=True)`` function is loaded from the on-disk cache;
and numba keys that cache on the function's module, name and line, so one constructor
made here for every record would share one cache entry among records whose field types
match.
"""
import sys

import numba
from numba import types
from numba.experimental import structref


class RecordType(types.StructRef):
    """The numba type of a record: its fields' types without literal values (so one
    compiled version serves every value)."""

    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class Record(structref.StructRefProxy):
    """A record's Python proxy; subclasses are declared with `record`."""

    #: The fields, in the constructor's order (set by `record`).
    FIELDS = ()
    #: The record's cached compiled constructor (set after the class, see the module).
    constructor = None

    def __new__(cls, *values):
        if len(values) != len(cls.FIELDS):
            raise TypeError(f"{cls.__name__} takes {len(cls.FIELDS)} values "
                            f"({', '.join(cls.FIELDS)}), got {len(values)}")
        return cls.constructor(*values)

    @classmethod
    def build(cls, **values):
        """The record of these field values, by name; TypeError naming a missing or an
        unknown field."""
        missing = [f for f in cls.FIELDS if f not in values]
        unknown = sorted(set(values) - set(cls.FIELDS))
        if missing or unknown:
            what = (f"missing {', '.join(missing)}" if missing else "") + \
                   ("; " if missing and unknown else "") + \
                   (f"unknown {', '.join(unknown)}" if unknown else "")
            raise TypeError(f"{cls.__name__}.build: {what}")
        return cls(*(values[f] for f in cls.FIELDS))


def record(*fields):
    """Class decorator: the Record subclass becomes a numba record with these fields, in
    this order. Its numba type is registered as ``<Name>Type`` in the class's module
    (where numba's cache finds it again by name)."""
    if len(set(fields)) != len(fields):
        raise ValueError(f"a record's fields repeat: {fields}")

    def define(cls):
        name = cls.__name__ + "Type"
        typ = type(name, (RecordType,), {"__module__": cls.__module__, "__qualname__": name})
        structref.register(typ)
        setattr(sys.modules[cls.__module__], name, typ)
        structref.define_proxy(cls, typ, list(fields))
        cls.FIELDS = tuple(fields)
        cls.numba_type = typ
        return cls

    return define


def direct(function, *args):
    """`function` (an ``@njit`` dispatcher) compiled for the types of `args`, as a callable
    that skips numba's per-call typing of its arguments; the version is loaded from the
    cache or compiled, as a first call would. The caller must pass arguments of exactly
    these types from then on: nothing checks them again (an array of another dtype,
    layout or dimension would be read as one of these). numba's public
    ``Dispatcher.compile(signature)`` loads or compiles the version and returns its entry
    point, which a call through the dispatcher runs after typing the arguments."""
    return function.compile(tuple(numba.typeof(a) for a in args))
