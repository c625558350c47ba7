"""FMU state: save, advance, restore, advance again gives bit-identical
outputs, also through serialization into a fresh instance."""

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_helpers import Instance, run_ramp

FMI2_ERROR = 3


def test_get_set_and_serialized_states_continue_bit_identically(unzipped):
    d = unzipped("square")
    a = Instance(d, "original").initialize()
    b = Instance(d, "restored").initialize()
    try:
        run_ramp(a, [0.002] * 10, ramp_time=0.1)
        state = a.slave.getFMUstate()
        t0 = a.time
        first = run_ramp(a, [0.002] * 10, ramp_time=0.1)

        a.slave.setFMUstate(state)
        a.time = t0
        second = run_ramp(a, [0.002] * 10, ramp_time=0.1)
        assert first.tobytes() == second.tobytes()

        blob = a.slave.serializeFMUstate(state)
        restored = b.slave.deSerializeFMUstate(blob)
        b.slave.setFMUstate(restored)
        b.time = t0
        third = run_ramp(b, [0.002] * 10, ramp_time=0.1)
        assert first.tobytes() == third.tobytes()

        a.slave.freeFMUstate(state)
        b.slave.freeFMUstate(restored)
        assert np.all(np.isfinite(first))
    finally:
        a.close()
        b.close()


def test_changed_truncated_and_foreign_states_are_refused(unzipped):
    """Issue 38: a serialized state is a checksummed container bound to its
    FMU: a flipped bit, a cut or a state of another scene is an error with a
    reason, and the instance is left as it was. (fmpy's logger proxy is
    global: the instance made last gets every message, so the other scene's
    instance comes last.)"""
    a = Instance(unzipped("square"), "state-owner").initialize()
    other = None
    try:
        run_ramp(a, [0.002] * 3, ramp_time=0.1)
        state = a.slave.getFMUstate()
        blob = a.slave.serializeFMUstate(state)
        before = a.get()
        flipped = bytearray(blob)
        flipped[len(blob) // 2] ^= 0x04
        for bad, reason in [(bytes(flipped), "checksum"), (blob[:-1], "truncated"),
                            (blob[: len(blob) // 3], "truncated")]:
            with pytest.raises(FMICallException) as e:
                a.slave.deSerializeFMUstate(bad)
            assert e.value.status == FMI2_ERROR
            assert reason in a.log.messages()[-1]
        assert a.get().tobytes() == before.tobytes()
        restored = a.slave.deSerializeFMUstate(blob)
        a.slave.setFMUstate(restored)
        a.slave.freeFMUstate(restored)
        a.slave.freeFMUstate(state)
        other = Instance(unzipped("miura"), "other-scene").initialize()
        with pytest.raises(FMICallException):
            other.slave.deSerializeFMUstate(blob)
        assert "belongs to the FMU with GUID" in other.log.messages()[-1]
    finally:
        a.close()
        if other is not None:
            other.close()
