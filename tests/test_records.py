"""compiled.records: a record defined once, built by name, read by name in compiled code."""
import numpy as np
import pytest
from numba import njit

from compiled import records
from ebrl.steps import AGENT_FIELDS, AgentRecord
from tasks.kernels.thrusters import ThrustersRecord
from tasks.kernels.stream import Stream, stream_state


def test_a_record_is_built_by_name_and_refuses_a_missing_or_unknown_name():
    st = Stream.build(gauss=0.25, cursor=3, has_gauss=1, buffer=np.arange(4.0))
    assert stream_state(st) == (3, 1, 0.25)  # each value went to its own field
    with pytest.raises(TypeError, match=r"Stream.build: missing gauss"):
        Stream.build(buffer=np.zeros(1), cursor=0, has_gauss=0)
    with pytest.raises(TypeError, match=r"Stream.build: unknown colour"):
        Stream.build(buffer=np.zeros(1), cursor=0, has_gauss=0, gauss=0.0, colour=1)
    with pytest.raises(TypeError, match=r"Stream takes 4 values \(buffer, cursor, has_gauss, gauss\), got 2"):
        Stream(np.zeros(1), 0)


def test_each_record_keeps_its_fields_in_order_under_its_registered_type():
    assert AgentRecord.FIELDS == AGENT_FIELDS
    assert ThrustersRecord.FIELDS[0] == "m" and "restitution" in ThrustersRecord.FIELDS
    import tasks.kernels.thrusters as module
    assert module.ThrustersRecordType is ThrustersRecord.numba_type  # numba's cache finds it by name
    with pytest.raises(ValueError, match="repeat"):
        records.record("a", "a")


@records.record("x", "y")
class _Pair(records.Record):
    """A record of the test's own."""


@njit
def _new_pair(*values):
    return _Pair(*values)


_Pair.constructor = _new_pair


@njit
def _swap(p):
    p.x, p.y = p.y, p.x
    return p.x - p.y


def test_compiled_code_reads_and_writes_the_fields_by_name():
    p = _Pair.build(y=5.0, x=2.0)
    assert _swap(p) == 3.0 and _swap(p) == -3.0


@njit
def _scaled_swap(p, scale, out):
    p.x, p.y = p.y, p.x
    out[:] = scale * (p.x - p.y)
    return p.x


def test_direct_is_the_version_the_dispatcher_runs_for_those_types():
    p, q = _Pair.build(x=2.0, y=5.0), _Pair.build(x=2.0, y=5.0)
    call = records.direct(_scaled_swap, p, 0.0, np.zeros(2))
    assert len(_scaled_swap.signatures) == 1  # compiled once, for the probes' types
    by_direct, by_dispatcher, got = np.zeros(2), np.zeros(2), []
    for scale in (1.5, -2.0, 0.25):
        got.append(call(p, scale, by_direct))
        assert got[-1] == _scaled_swap(q, scale, by_dispatcher)
        assert np.array_equal(by_direct, by_dispatcher)
        assert by_direct[0] == scale * (got[-1] - (7.0 - got[-1]))  # x - y, by hand
    assert got == [5.0, 2.0, 5.0]  # each call swapped the record's own fields
    assert len(_scaled_swap.signatures) == 1  # the dispatcher found the same version
