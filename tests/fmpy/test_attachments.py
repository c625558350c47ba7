"""Rigid attachments through fmpy's FMU2Slave, the way a multibody master
uses them: tests/fmpy/scenes/bridge.json is a 0.2 x 0.05 m strip (0.5 mm
paper, crease across the middle) clamped to a support at its left end, its
right end held by the frame `mount`, under gravity, with the reaction
outputs."""

import numpy as np
import pytest

from fmu_helpers import Instance

G = 9.81
MASS = 800 * 5e-4 * 0.2 * 0.05  # density * thickness * area, kg


def vec(inst, prefix):
    return inst.get([inst.vr[f"{prefix}.{c}"] for c in "xyz"])


def test_the_support_and_the_mount_carry_the_weight(unzipped):
    """Held still for 1 s (held inputs, no derivatives), the sheet settles:
    the forces it exerts on the support and on the mount add up to its
    weight, within 1e-6."""
    inst = Instance(unzipped("bridge"), "weight").initialize()
    try:
        for _ in range(100):
            inst.step(0.01)
        total = vec(inst, "support[0].force") + vec(inst, "mount.force")
        assert total == pytest.approx([0.0, 0.0, -MASS * G], abs=1e-6 * MASS * G)
        # Each end carries about half.
        assert vec(inst, "mount.force")[2] == pytest.approx(-MASS * G / 2, rel=0.2)
    finally:
        inst.close()


def test_the_mount_follows_its_pose_with_first_and_second_derivatives(unzipped):
    """The master raises the mount along z(t) = z0 + a t^2 / 2, handing the
    position, velocity and acceleration before each 5 ms step
    (fmi2SetRealInputDerivatives orders 1 and 2): the held vertices 4 and 9
    are on that parabola at every step end, to round-off, and the mount
    reads a finite wrench."""
    inst = Instance(unzipped("bridge"), "parabola").initialize()
    try:
        vz = inst.vr["mount.z"]
        z0 = inst.slave.getReal([vz])[0]
        a, h = 2.0, 5e-3
        for k in range(40):
            t = k * h
            inst.slave.setReal([vz], [z0 + 0.5 * a * t * t])
            inst.slave.setRealInputDerivatives([vz, vz], [1, 2], [a * t, a])
            inst.step(h)
            want = z0 + 0.5 * a * inst.time**2
            for v in (4, 9):
                assert inst.get([inst.vr[f"vertex[{v}].z"]])[0] == pytest.approx(want, abs=1e-12)
        assert np.all(np.isfinite(vec(inst, "mount.moment")))
    finally:
        inst.close()


def test_an_attached_state_restores_bit_for_bit(unzipped):
    """fmi2GetFMUstate / fmi2SetFMUstate with a moving mount: the second run
    from the saved state reads the same wrench, bit for bit."""
    inst = Instance(unzipped("bridge"), "state").initialize()
    try:
        inst.step(0.02, {"mount.x": 0.201}, {"mount.rz": 0.5})
        saved = inst.slave.getFMUstate()
        t = inst.time

        def run():
            for _ in range(3):
                inst.step(0.01, None, {"mount.z": 0.05})
            return inst.get()

        first = run()
        inst.slave.setFMUstate(saved)
        inst.time = t
        second = run()
        assert np.array_equal(first, second)
        inst.slave.freeFMUstate(saved)
    finally:
        inst.close()
