"""Every example FMU builds, has the expected layout, passes `fmpy validate`,
and carries exactly the checked-in modelDescription.xml."""

import zipfile

from fmpy.validation import validate_fmu

from fmu_helpers import ROOT, build, cli, scene_path

# Where a cross-built win64 DLL is found, which `build` then packs too
# (docs/fmu.md, Platforms): scripts/windows_test.sh leaves one.
WIN64_DLLS = [cli().parent.parent / t / "release" / "origami_fmu.dll"
              for t in ("x86_64-win7-windows-gnu", "x86_64-pc-windows-gnu")]


def test_fmpy_validate_reports_no_problems(fmu, example):
    assert validate_fmu(str(fmu(example))) == []


def test_fmu_layout(fmu, example):
    # a FOLD source also travels as resources/scene.fold
    extra = ["resources/scene.fold"] if scene_path(example).suffix == ".fold" else []
    if any(p.is_file() for p in WIN64_DLLS):
        extra.append("binaries/win64/origami_fmu.dll")
    with zipfile.ZipFile(fmu(example)) as z:
        assert sorted(z.namelist()) == sorted([
            "binaries/linux64/origami_fmu.so",
            "modelDescription.xml",
            "resources/scene.json",
        ] + extra)
        assert z.read("binaries/linux64/origami_fmu.so")[:4] == b"\x7fELF"
        if "binaries/win64/origami_fmu.dll" in extra:
            assert z.read("binaries/win64/origami_fmu.dll")[:2] == b"MZ"


def test_model_description_is_the_checked_in_one(fmu, example):
    with zipfile.ZipFile(fmu(example)) as z:
        built = z.read("modelDescription.xml")
    assert built == (ROOT / "modelDescription" / f"{example}.xml").read_bytes()


def test_build_refuses_a_bad_scene_with_the_reason(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"name": "x"}')
    r = build(bad, tmp_path / "bad.fmu")
    assert r.returncode != 0
    assert "missing field" in r.stderr and "bad.json" in r.stderr
    assert not (tmp_path / "bad.fmu").exists()
