"""Rigid obstacles through fmpy's FMU2Slave, the way a master reads them:
tests/fmpy/scenes/ground.json is a 0.1 x 0.1 m square of 0.5 mm paper
(800 kg/m^3) under gravity, 2.5 mm above the ground `ground` (a half-space,
friction 0.3)."""

import numpy as np
import pytest

from fmu_helpers import Instance

G = 9.81
THICKNESS = 5e-4
GROUND = -0.0025
WEIGHT = 800 * THICKNESS * 0.1 * 0.1 * G  # N


def vec(inst, prefix):
    return inst.get([inst.vr[f"{prefix}.{c}"] for c in "xyz"])


def test_a_sheet_dropped_on_the_ground_rests_on_it_with_its_weight(unzipped):
    """Stepped at 10 ms for 0.5 s (no inputs): the sheet falls, lands and
    comes to rest; no vertex ever comes within half the thickness of the
    ground, at rest every vertex is half the thickness above it within the
    barrier width (a tenth of it), and the ground's force output is the
    weight pressing it down within 1e-3 relative, its moment about the
    plane's point (0, 0, -2.5 mm) the weight's at the square's centre."""
    inst = Instance(unzipped("ground"), "drop").initialize()
    try:
        zs = [inst.vr[f"vertex[{i}].z"] for i in range(4)]
        for _ in range(50):
            inst.step(0.01)
            height = np.array(inst.get(zs)) - GROUND
            assert np.all(height > THICKNESS / 2), height
        assert np.all(height - THICKNESS / 2 < 0.1 * THICKNESS / 2), height
        force = vec(inst, "ground.force")
        assert force == pytest.approx([0.0, 0.0, -WEIGHT], abs=1e-3 * WEIGHT)
        moment = vec(inst, "ground.moment")
        want = np.cross([0.05, 0.05, 0.0], [0.0, 0.0, -WEIGHT])
        assert moment == pytest.approx(want, abs=1e-3 * WEIGHT * 0.05)
        assert inst.get([inst.vr["energy.contact"]])[0] > 0.0
    finally:
        inst.close()
