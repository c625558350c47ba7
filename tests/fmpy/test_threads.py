"""Eight instances stepping in eight threads give exactly the results of
eight serial runs (ctypes releases the GIL during each FMI call, so the
instances really run concurrently in one process)."""

from concurrent.futures import ThreadPoolExecutor

from fmu_helpers import Instance


def run(d, k, tag):
    inst = Instance(d, f"{tag}-{k}").initialize()
    try:
        rows = []
        for n in range(50):
            inst.step(0.002, {"fold": (k + 1) / 8 * min((n + 1) * 0.002 / 0.05, 1.0)})
            rows.append(inst.get())
        return b"".join(r.tobytes() for r in rows)
    finally:
        inst.close()


def test_eight_threads_match_serial_runs(unzipped):
    d = unzipped("square")
    serial = [run(d, k, "serial") for k in range(8)]
    with ThreadPoolExecutor(max_workers=8) as pool:
        parallel = list(pool.map(lambda k: run(d, k, "thread"), range(8)))
    assert parallel == serial
