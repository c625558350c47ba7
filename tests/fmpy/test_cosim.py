"""The co-simulation contract as standard masters meet it (FMI 2.0 sections
2.1.5, 2.1.6, 4.2.1-4.2.4): inputs set before fmi2DoStep(t, h) are the
inputs at t, held over the step (or interpolated with the derivatives a
master gives); a failed step terminates instead of being repeated for ever;
the stop time is enforced; damping parameters act; the controller example
settles."""

import math
import pathlib
import subprocess
import sys
import time

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException

from fmu_helpers import ROOT, Instance

FMI2_DISCARD, FMI2_ERROR = 2, 3


def crease_angle(inst, name="crease[1].angle"):
    return inst.get([inst.vr[name]])[0]


@pytest.mark.parametrize("h", [1e-2, 1e-3, 1e-4])
def test_a_step_set_before_dostep_is_held_from_its_start(unzipped, h):
    """scenes/single_crease.fold: the fold input jumps 0 -> 0.1 before
    fmi2DoStep(0.1, H) and stays. 10 ms later the crease angle is the same
    for H = 10, 1 and 0.1 ms (the held input in every case: a ramp or a
    one-step lag would differ by degrees), within the integrator's
    accuracy: tolerance 1e-8 here, agreement 1e-4 of the angle."""
    def run(big_h):
        inst = Instance(unzipped("single_crease"), f"step-{big_h}").initialize(
            {"solver.tolerance": 1e-8})
        try:
            inst.step(0.05, {"fold": 0.0})
            inst.step(0.05)
            inst.slave.setReal([inst.vr["fold"]], [0.1])
            for _ in range(int(round(0.01 / big_h))):
                inst.step(big_h)
            assert inst.time == pytest.approx(0.11, abs=1e-12)
            return crease_angle(inst)
        finally:
            inst.close()

    ref = run(1e-2)
    assert ref > 0.02, "the crease moved"
    assert run(h) == pytest.approx(ref, rel=1e-4)


def test_a_ramp_with_input_derivatives_does_not_depend_on_the_output_interval(unzipped):
    """A master that hands the input's slope with each value
    (fmi2SetRealInputDerivatives: the value at t and the slope of the
    segment ahead). A fold ramp 0 -> 1 over 0.6 s then gives the same
    crease angles at communication steps 1e-2 and 1e-3 within 0.1 deg at
    every common time: no lag. (fmpy's simulate_fmu(set_input_derivatives=
    True) cannot drive this FMU: in fmpy 0.3.32 its derivative buffer has a
    fixed length of 9 and the assignment fails for any other number of
    continuous inputs; its interpolation also gives slope 0 at the table's
    first time.)"""

    def signal(t):
        return (min(t / 0.6, 1.0), 1.0 / 0.6 if t < 0.6 - 1e-12 else 0.0)

    def run(dt):
        inst = Instance(unzipped("single_crease"), f"ramp-{dt}").initialize()
        try:
            angles = [crease_angle(inst)]
            for k in range(int(round(1.0 / dt))):
                t = k * dt
                v, d = signal(t)
                inst.slave.setReal([inst.vr["fold"]], [v])
                inst.slave.setRealInputDerivatives([inst.vr["fold"]], [1], [d])
                inst.step(dt)
                angles.append(crease_angle(inst))
            return np.array(angles)
        finally:
            inst.close()

    coarse, fine = run(1e-2), run(1e-3)
    diff = np.degrees(np.abs(fine[::10] - coarse))
    assert coarse[-1] > math.radians(80), "the crease folded"
    assert diff.max() < 0.1, f"largest difference {diff.max():.3f} deg"


def test_simulate_fmu_holds_inputs_over_each_step(fmu):
    """simulate_fmu without derivatives samples the input at each
    communication point and the FMU holds it: a fold ramp sampled every
    10 ms acts like the same ramp 5 ms late (half the interval, sample and
    hold), not a whole step late as before. Measured against 1 ms
    sampling: the coarse run stays closer to the fine run delayed by 5 ms
    than to the undelayed one while the ramp runs."""
    path = str(fmu("single_crease"))
    signal = np.array([(0.0, 0.0), (0.6, 1.0), (1.0, 1.0)],
                      dtype=[("time", float), ("fold", float)])
    runs = {dt: simulate_fmu(path, stop_time=0.6, output_interval=dt, input=signal,
                             output=["crease[1].angle"]) for dt in (1e-2, 1e-3)}
    coarse, fine = runs[1e-2]["crease[1].angle"], runs[1e-3]["crease[1].angle"]
    window = slice(10, 60)  # 0.1 s .. 0.6 s
    same_time = np.abs(coarse[window] - fine[::10][window]).mean()
    delayed = np.abs(coarse[window] - fine[5::10][window.start - 1:window.stop - 1]).mean()
    assert delayed < 0.5 * same_time, (delayed, same_time)


def test_the_scene_built_to_discard_ends_the_run_within_seconds(fmu, tmp_path):
    """A step that fails (solver.max_internal_steps = 2 against the ten
    1 ms internal steps of a 10 ms step; the same answer as a Newton
    failure at min_step) is fmi2Discard with fmi2Terminated true, so fmpy's
    simulate_fmu stops at fmi2LastSuccessfulTime instead of repeating the
    step for ever (it used to). Run in a subprocess with a time limit so a
    regression cannot hang the suite."""
    path = fmu("case_c_nocut")
    script = (
        "import sys, numpy as np\n"
        "from fmpy import simulate_fmu\n"
        "u = np.array([(0.0, 0.0), (0.05, 1e-2), (1.0, 1e-2)], dtype=[('time', float), ('torque', float)])\n"
        f"r = simulate_fmu({str(path)!r}, stop_time=1.0, output_interval=1e-2, input=u,\n"
        "                  start_values={'solver.max_internal_steps': 2})\n"
        "print('END', r['time'][-1])\n"
    )
    start = time.monotonic()
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    elapsed = time.monotonic() - start
    assert p.returncode == 0, p.stderr
    end = float(p.stdout.split("END")[1])
    assert end < 1.0, "the run ended early, at the last successful time"
    assert elapsed < 60


def test_after_a_discard_setreal_and_dostep_are_refused_until_a_restore(unzipped):
    """FMI 2.0 state machine (stepFailed): only getters, fmi2SetFMUstate,
    fmi2Terminate, fmi2Reset and fmi2FreeInstance. A master that restores
    the state saved before the step can retry with a smaller step."""
    inst = Instance(unzipped("case_c_nocut"), "discard").initialize(
        {"solver.max_internal_steps": 2})
    try:
        inst.step(2e-3, {"torque": 1e-4})
        saved = inst.slave.getFMUstate()
        with pytest.raises(FMICallException) as e:
            inst.step(1e-2, {"torque": 1e-4})
        assert e.value.status == FMI2_DISCARD
        failed_at = inst.time
        assert failed_at == pytest.approx(2e-3)
        from fmpy.fmi2 import fmi2Terminated
        assert inst.slave.getBooleanStatus(fmi2Terminated)
        with pytest.raises(FMICallException) as e:
            inst.slave.setReal([inst.vr["torque"]], [0.0])
        assert e.value.status == FMI2_ERROR
        with pytest.raises(FMICallException):
            inst.slave.doStep(currentCommunicationPoint=failed_at, communicationStepSize=1e-3)
        inst.slave.setFMUstate(saved)
        assert not inst.slave.getBooleanStatus(fmi2Terminated)
        inst.step(2e-3, {"torque": 1e-4})
    finally:
        inst.close()


def test_a_step_past_its_cpu_limit_is_discarded_with_the_state_before_it(unzipped):
    """Issue 52: solver.max_step_cpu caps the CPU of one fmi2DoStep. Past it
    the step is fmi2Discard (fmi2Terminated true), time and outputs are the
    ones from before the step, and the log names the limit; the same step
    under the default limit goes through from that same state."""
    held = {"torque": 1e-4}
    # (One instance at a time: fmpy's logger proxy is process-wide.)
    capped = Instance(unzipped("case_c_nocut"), "capped", logging_on=True).initialize(
        {"solver.max_step_cpu": 1e-6})
    try:
        before = capped.get()
        with pytest.raises(FMICallException) as e:
            capped.step(1e-2, held)
        assert e.value.status == FMI2_DISCARD
        from fmpy.fmi2 import fmi2LastSuccessfulTime, fmi2Terminated
        assert capped.slave.getBooleanStatus(fmi2Terminated)
        assert capped.slave.getRealStatus(fmi2LastSuccessfulTime) == 0.0
        assert np.array_equal(capped.get(), before), "the state from before the step"
        assert any("solver.max_step_cpu" in m for m in capped.log.reasons()), capped.log.lines
    finally:
        capped.close()
    free = Instance(unzipped("case_c_nocut"), "free").initialize()
    try:
        assert np.array_equal(free.get(), before)
        free.step(1e-2, held)
        assert not np.array_equal(free.get(), before), "the same step moves the sheet"
    finally:
        free.close()


def test_a_step_past_the_stop_time_is_an_error(unzipped):
    """FMI 2.0 section 2.1.6: with stopTimeDefined, doStep past stopTime
    returns fmi2Error and changes nothing."""
    inst = Instance(unzipped("square"), "stop")
    try:
        inst.slave.setupExperiment(startTime=0.0, stopTime=0.02)
        inst.slave.enterInitializationMode()
        inst.slave.exitInitializationMode()
        inst.step(0.02)
        with pytest.raises(FMICallException) as e:
            inst.step(0.01)
        assert e.value.status == FMI2_ERROR
        assert any("stopTime" in m for m in inst.log.messages())
    finally:
        inst.close()


def test_setting_damping_alpha_changes_the_motion(fmu):
    """damping.alpha is applied when set (it switches the automatic damping
    off); its start value is the automatic choice, so setting it to that
    value changes nothing."""
    path = str(fmu("single_crease"))
    md = read_model_description(path)
    alpha0 = next(float(v.start) for v in md.modelVariables if v.name == "damping.alpha")
    assert alpha0 > 0, "automatic damping is on"
    signal = np.array([(0.0, 0.0), (0.05, 1.0), (1.0, 1.0)],
                      dtype=[("time", float), ("fold", float)])

    def angle(start):
        r = simulate_fmu(path, stop_time=0.1, output_interval=1e-2, input=signal,
                         output=["crease[1].angle"], start_values=start)
        return r["crease[1].angle"][-1]

    auto = angle({})
    assert angle({"damping.alpha": alpha0}) == auto
    assert abs(angle({"damping.alpha": 10 * alpha0}) - auto) > 1e-3


def test_the_controller_example_settles(tmp_path):
    """examples/pi_controller.py: a PI loop stepping the FMU with FMU2Slave
    at 1 ms holds the crease at 45 deg; after the 5 mN disturbance at 0.8 s
    the mean angle over the last 0.2 s is within 0.3 deg of the set angle
    and the loop is quiet (standard deviation below 0.5 deg)."""
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, str(ROOT / "examples" / "pi_controller.py"),
                        "--fmu", str(tmp_path / "controlled_crease.fmu"), "--out", str(out)],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    data = np.genfromtxt(out / "pi_controller.csv", delimiter=",", names=True)
    last = data[data["time"] >= data["time"][-1] - 0.2]
    assert abs(last["crease_angle_deg"].mean() - 45.0) < 0.3
    assert last["crease_angle_deg"].std() < 0.5
    before = data[(data["time"] > 0.6) & (data["time"] < 0.8)]
    assert abs(before["crease_angle_deg"].mean() - 45.0) < 0.3
    assert (out / "pi_controller.png").stat().st_size > 10_000
