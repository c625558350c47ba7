"""Fixtures of the fmpy suite: FMUs of the example scenes, built once per
session with the release CLI (`cargo build --release` must have run; the
test command scripts/test.sh does that)."""

import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).parent))

from fmu_helpers import EXAMPLES, build, scene_path, unzip  # noqa: E402


@pytest.fixture(scope="session")
def fmu_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("fmus")


@pytest.fixture(scope="session")
def fmu(fmu_dir):
    """fmu(name) -> path of the FMU of tests/fmpy/scenes/<name>.json."""
    built = {}

    def get(name):
        if name not in built:
            out = fmu_dir / f"{name}.fmu"
            r = build(scene_path(name), out)
            assert r.returncode == 0, r.stderr
            built[name] = out
        return built[name]

    return get


@pytest.fixture(scope="session")
def unzipped(fmu, fmu_dir):
    """unzipped(name) -> folder with the extracted FMU (shared, read-only)."""
    done = {}

    def get(name):
        if name not in done:
            done[name] = unzip(fmu(name), fmu_dir / f"{name}_unzipped")
        return done[name]

    return get


def pytest_generate_tests(metafunc):
    if "example" in metafunc.fixturenames:
        metafunc.parametrize("example", EXAMPLES)
