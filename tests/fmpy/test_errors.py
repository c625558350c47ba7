"""Bad input gets a clear error and loses nothing: a broken scene fails
instantiation with the reason logged, NaN inputs are refused with the state
kept, calls out of order are fmi2Error with a logged reason."""

import json
import math
import pathlib
import shutil

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_helpers import Instance

FMI2_ERROR = 3


def copy_fmu(unzipped, name, tmp_path):
    d = tmp_path / name
    shutil.copytree(unzipped(name), d)
    return d


def failed_instantiation(d, name):
    """Instantiate, expecting fmi2Instantiate to return NULL; the log lines."""
    inst = Instance.__new__(Instance)
    with pytest.raises(Exception, match="Failed to instantiate"):
        Instance.__init__(inst, d, name)
    return inst.log.lines


def test_bad_scene_fails_instantiation_with_the_logged_reason(unzipped, tmp_path):
    d = copy_fmu(unzipped, "square", tmp_path)
    scene_file = d / "resources" / "scene.json"
    scene = json.loads(scene_file.read_text())
    scene["mesh"]["triangles"][1][2] = 42  # out-of-range vertex index
    scene_file.write_text(json.dumps(scene))
    lines = failed_instantiation(d, "bad-scene")
    assert len(lines) == 1
    status, category, message = lines[0]
    assert status == FMI2_ERROR and category == "logStatusError"
    assert "invalid scene" in message
    assert "face 1 refers to vertex 42" in message


def test_other_scene_with_this_description_is_a_guid_mismatch(unzipped, tmp_path):
    d = copy_fmu(unzipped, "square", tmp_path)
    shutil.copy(pathlib.Path(unzipped("miura")) / "resources" / "scene.json", d / "resources" / "scene.json")
    lines = failed_instantiation(d, "wrong-guid")
    assert "GUID mismatch" in lines[0][2]


def test_nan_input_is_an_error_and_the_state_is_kept(unzipped):
    d = unzipped("square")
    ref = Instance(d, "reference").initialize()
    inst = Instance(d, "nan").initialize()
    try:
        for i in (ref, inst):
            i.step(0.01, {"fold": 0.2})
        before = inst.get()
        fold = inst.vr["fold"]
        for bad in (math.nan, math.inf, -math.inf):
            with pytest.raises(FMICallException) as e:
                inst.slave.setReal([fold], [bad])
            assert e.value.status == FMI2_ERROR
            assert "not a finite number" in inst.log.messages()[-1]
        assert inst.slave.getReal([fold]) == [0.2]
        assert inst.get().tobytes() == before.tobytes()
        # stepping goes on exactly as without the rejected calls
        for i in (ref, inst):
            i.step(0.01, {"fold": 0.4})
        assert inst.get().tobytes() == ref.get().tobytes()
    finally:
        ref.close()
        inst.close()


def test_nan_parameter_is_an_error(unzipped):
    inst = Instance(unzipped("square"), "nan-parameter")
    try:
        vr = inst.vr["material.thickness"]
        with pytest.raises(FMICallException):
            inst.slave.setReal([vr], [math.nan])
        assert inst.slave.getReal([vr]) == [1e-4]
    finally:
        inst.slave.freeInstance()


def test_calls_out_of_order_are_errors_with_a_reason(unzipped):
    inst = Instance(unzipped("square"), "order")
    try:
        with pytest.raises(FMICallException) as e:
            inst.slave.doStep(currentCommunicationPoint=0.0, communicationStepSize=0.01)
        assert e.value.status == FMI2_ERROR
        assert "fmi2DoStep is not allowed in state 'instantiated'" in inst.log.messages()[-1]

        inst.initialize()
        vr = inst.vr["material.youngs_modulus"]
        with pytest.raises(FMICallException):
            inst.slave.setReal([vr], [1e9])
        assert "fixed parameter" in inst.log.messages()[-1]
        with pytest.raises(FMICallException):
            inst.slave.enterInitializationMode()
        # a communication point that is not the FMU's time
        with pytest.raises(FMICallException):
            inst.slave.doStep(currentCommunicationPoint=1.0, communicationStepSize=0.01)
        assert "does not match the FMU's time" in inst.log.messages()[-1]
        # the instance is still usable
        inst.step(0.01)
        assert np.all(np.isfinite(inst.get()))
    finally:
        inst.close()
