"""FMU state: save, advance, restore, advance again gives bit-identical
outputs, also through serialization into a fresh instance."""

import numpy as np

from fmu_helpers import Instance, run_ramp


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
