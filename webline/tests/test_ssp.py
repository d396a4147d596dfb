"""SSP archives of a line (webline.ssp, webline.archive, webline.engines).

The writer's output is checked against FMPy's SSP 1.0 schemas here with lxml directly (not through the
writer's own check). Archives from other users are untrusted: crafted archives (a `../` path, an absolute
path, a symbolic link, a huge entry, an entry larger than it declares, a missing FMU, a schema-invalid
.ssd) are each refused with a message naming the file and the entry, and nothing is written outside
the target folder.
"""

import io
import json
import stat
import struct
import zipfile
from pathlib import Path

import pytest
from lxml import etree

from webline.archive import ArchiveError, Limits, extract
from webline.engines import agreement, relative_difference, run_fmpy, run_libcosim
from webline.master import Master, Options
from webline.ssp import NS, SspError, read_ssp, write_ssp
from webline.scene import SceneError
from webline.system import Component, Connection, System

from .conftest import SCENES

SCHEMAS = Path(__import__("fmpy.ssp").ssp.__file__).parent / "schema"
WEB = {"E": 4.5e9, "thickness": 5e-5, "width": 1.0, "density": 1390.0, "d_r": 1e-3}


def span(name, fmus, **start):
    values = {"L": 1.0, **{f"{s}.{k}": v for s in ("wp1", "wp2") for k, v in WEB.items()},
              "includeDamping": True, "preventNegativeTension": False, "startAtEquilibrium": False,
              "eps_start": 3e-4, "web_a.v": 2.0, "web_b.v": 2.0005, "substeps": 2}
    values.update(start)
    return Component(name, "span", fmus / "ConvertingSpan.fmu", values)


@pytest.fixture
def two_spans(fmus):
    """Two spans in a row, the strain passed span to span; speeds as fixed inputs (no Roller needed)."""
    first = span("first", fmus, **{"web_a.eps": 3e-4})
    second = span("second", fmus, **{"web_a.eps": 3e-4, "web_a.v": 2.0005, "web_b.v": 2.001})
    second.profile = {"set": [{"time": 0.05, "L": 1.2}]}
    return System("two_spans", [first, second],
                  [Connection(("first", "web_b.eps"), ("second", "web_a.eps"))],
                  0.0, 0.1, 1e-4, [("first", "summary_Tension"), ("second", "summary_Tension"), ("first", "web_b.eps")])


def schema(name):
    return etree.XMLSchema(file=str(SCHEMAS / name))


def test_export_is_valid_ssp_1_0(two_spans, tmp_path):
    path = write_ssp(two_spans, tmp_path / "line.ssp")
    with zipfile.ZipFile(path) as zf:
        names = set(zf.namelist())
        # One FMU for both spans, carrying the second's profile under its name (libcosim unpacks one copy per GUID).
        assert names == {"SystemStructure.ssd", "resources/first.ssv", "resources/second.ssv", "resources/ConvertingSpan.fmu"}
        ssd = etree.fromstring(zf.read("SystemStructure.ssd"))
        ssvs = [etree.fromstring(zf.read(n)) for n in sorted(names) if n.endswith(".ssv")]
        with zipfile.ZipFile(io.BytesIO(zf.read("resources/ConvertingSpan.fmu"))) as fmu:
            assert b'"L": 1.2' in fmu.read("resources/second.json")
            # The first, without a profile, gets an empty one of its own name (so it finds its own file).
            assert json.loads(fmu.read("resources/first.json")) == {}
            assert "resources/profile.json" not in fmu.namelist()
    s = schema("SystemStructureDescription.xsd")
    assert s.validate(ssd), s.error_log
    for ssv in ssvs:
        s = schema("SystemStructureParameterValues.xsd")
        assert s.validate(ssv), s.error_log
    exp = ssd.find("ssd:DefaultExperiment", NS)
    assert (float(exp.get("startTime")), float(exp.get("stopTime"))) == (0.0, 0.1)
    assert exp.find("ssd:Annotations/ssc:Annotation[@type='com.opensimulationplatform']/osp:Algorithm/"
                    "osp:FixedStepAlgorithm", NS).get("baseStepSize") == "0.0001"
    # Unconnected inputs are parameters in the .ssv, not connectors (FMPy needs every input connector connected).
    first = ssd.find("ssd:System/ssd:Elements/ssd:Component[@name='first']", NS)
    assert {c.get("name"): c.get("kind") for c in first.findall("ssd:Connectors/ssd:Connector", NS)} == \
        {"web_b.eps": "output", "summary_Tension": "output"}
    second = ssd.find("ssd:System/ssd:Elements/ssd:Component[@name='second']", NS)
    assert {c.get("name"): c.get("kind") for c in second.findall("ssd:Connectors/ssd:Connector", NS)} == \
        {"web_a.eps": "input", "summary_Tension": "output"}
    # FMPy reads it as it is.
    from fmpy.ssp.ssd import read_ssd
    assert [c.name for c in read_ssd(str(path)).system.elements] == ["first", "second"]


def test_read_gives_the_system_back(two_spans, tmp_path):
    path = write_ssp(two_spans, tmp_path / "line.ssp")
    back = read_ssp(path, tmp_path / "x")
    for a, b in zip(back.components, two_spans.components):
        assert (a.name, a.kind, a.start, a.profile) == (b.name, b.kind, b.start, b.profile)
        assert Path(a.fmu).resolve().is_relative_to((tmp_path / "x").resolve())
    assert (back.connections, back.record) == (two_spans.connections, two_spans.record)
    assert (back.name, back.start_time, back.stop_time, back.step) == ("two_spans", 0.0, 0.1, 1e-4)


@pytest.mark.parametrize("variable, value, why", [
    ("wp1.record", "PET", "String"),
    ("solver", 2, "Enumeration"),
    ("summary_Tension", 1.0, "causality output"),
    ("eps_start", float("nan"), "finite"),
])
def test_export_refuses_what_an_engine_cannot_set(two_spans, tmp_path, variable, value, why):
    two_spans.components[0].start[variable] = value
    with pytest.raises(SspError, match=why) as e:
        write_ssp(two_spans, tmp_path / "line.ssp")
    assert f"first.{variable}" in str(e.value)
    assert not (tmp_path / "line.ssp").exists()


# ---------------------------------------------------------------- crafted archives


def crafted(path, entries):
    """A zip archive of (ZipInfo or name, bytes) entries, written as given."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for info, data in entries:
            zf.writestr(info, data)
    return path


def symlink(name, to):
    info = zipfile.ZipInfo(name)
    info.external_attr = (stat.S_IFLNK | 0o777) << 16
    return info, to


def lying(path, declared):
    """An archive whose one entry declares `declared` bytes but holds 4 MiB (sizes patched in both headers)."""
    crafted(path, [("resources/big.bin", bytes(4 << 20))])
    data = bytearray(path.read_bytes())
    local = data.index(b"PK\x03\x04")
    central = data.index(b"PK\x01\x02")
    struct.pack_into("<I", data, local + 22, declared)
    struct.pack_into("<I", data, central + 24, declared)
    path.write_bytes(bytes(data))
    return path


def outside_is_untouched(tmp_path, archive):
    """Nothing but the archive and the target folder (and what the test made) beside them."""
    assert {p.name for p in tmp_path.iterdir()} <= {archive.name, "target", "outside"}
    assert list((tmp_path / "outside").iterdir()) == []


@pytest.mark.parametrize("case", ["dotdot", "absolute", "symlink", "symlink_folder", "huge", "lying", "many"])
def test_crafted_archives_are_refused(tmp_path, case):
    outside = tmp_path / "outside"
    outside.mkdir()
    archive = tmp_path / f"{case}.ssp"
    limits = Limits()
    if case == "dotdot":
        crafted(archive, [("SystemStructure.ssd", b"<x/>"), ("resources/../../outside/evil.txt", b"x")])
        entry, why = "resources/../../outside/evil.txt", "'..'"
    elif case == "absolute":
        entry = str(outside / "evil.txt")
        crafted(archive, [(entry, b"x")])
        why = "absolute path"
    elif case == "symlink":
        crafted(archive, [symlink("resources/link", str(outside))])
        entry, why = "resources/link", "symbolic link"
    elif case == "symlink_folder":  # a link then a file through it
        crafted(archive, [symlink("resources", str(outside)), ("resources/evil.txt", b"x")])
        entry, why = "resources", "symbolic link"
    elif case == "huge":  # a zip bomb: 300 MiB of zeros in about 300 kB
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as zf, zf.open("resources/bomb.bin", "w", force_zip64=True) as f:
            for _ in range(300):
                f.write(bytes(1 << 20))
        assert archive.stat().st_size < 1 << 20
        entry, why = "resources/bomb.bin", "more than the 268435456 allowed for one entry"
    elif case == "lying":  # declares 1000 bytes, holds 4 MiB
        lying(archive, 1000)
        entry, why = "resources/big.bin", "unreadable"
    else:
        crafted(archive, [(f"f{i}", b"") for i in range(20)])
        limits = Limits(entries=10)
        entry, why = "", "20 entries, more than the 10 allowed"
    with pytest.raises(ArchiveError, match=why) as e:
        extract(archive, tmp_path / "target", limits)
    assert str(archive) in str(e.value)
    assert not entry or f"entry {entry!r}" in str(e.value)
    outside_is_untouched(tmp_path, archive)
    target = tmp_path / "target"
    assert not target.exists() or [p for p in target.rglob("*") if p.is_file() or p.is_symlink()] == []


def test_read_ssp_refuses_a_missing_fmu(two_spans, tmp_path):
    path = write_ssp(two_spans, tmp_path / "line.ssp")
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(broken, "w") as dst:
        for info in src.infolist():
            if info.filename != "resources/ConvertingSpan.fmu":
                dst.writestr(info, src.read(info))
    with pytest.raises(SspError, match=r"component 'first'.*'resources/ConvertingSpan.fmu' is missing from the archive") as e:
        read_ssp(broken, tmp_path / "target")
    assert str(broken) in str(e.value) and "SystemStructure.ssd" in str(e.value)


@pytest.mark.parametrize("edit, why", [
    (lambda ssd: ssd.replace(b'kind="output"', b'kind="sideways"', 1), "not valid SSP 1.0"),
    (lambda ssd: ssd.replace(b"<ssd:Elements>", b"<ssd:Elements><ssd:Oops/>", 1), "not valid SSP 1.0"),
    (lambda ssd: ssd[: len(ssd) // 2], "not readable XML"),
    (lambda ssd: ssd.replace(b'baseStepSize="0.0001"', b'baseStepSize="-1"'), "no positive step"),
    (lambda ssd: b'<!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]>' + ssd.split(b"?>", 1)[1].replace(
        b'name="two_spans">', b'name="two_spans" description="&e;">'), "DOCTYPE|external entity"),
])
def test_read_ssp_refuses_a_bad_ssd(two_spans, tmp_path, edit, why):
    path = write_ssp(two_spans, tmp_path / "line.ssp")
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(broken, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            dst.writestr(info, edit(data) if info.filename == "SystemStructure.ssd" else data)
    with pytest.raises(SspError, match=why) as e:
        read_ssp(broken, tmp_path / "target")
    assert f"{broken}: SystemStructure.ssd" in str(e.value)


def test_read_ssp_checks_the_fmus_inside(two_spans, tmp_path):
    """An FMU in the archive is an archive too: its entries get the same checks before any engine unpacks it."""
    path = write_ssp(two_spans, tmp_path / "line.ssp")
    evil = tmp_path / "evil.fmu"
    crafted(evil, [("modelDescription.xml", b"<x/>"), ("../../escape.txt", b"x")])
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(broken, "w") as dst:
        for info in src.infolist():
            dst.writestr(info, evil.read_bytes() if info.filename == "resources/ConvertingSpan.fmu" else src.read(info))
    with pytest.raises(SspError, match=r"ConvertingSpan.fmu: entry '../../escape.txt'"):
        read_ssp(broken, tmp_path / "target")
    assert not (tmp_path / "escape.txt").exists()


# ---------------------------------------------------------------- engines

# Same coupling, same FMUs, same step: only the order of floating-point operations may differ.
AGREE = 1e-9


def test_engines_agree_with_the_master_on_two_spans(two_spans, tmp_path):
    """libcosim = the master's engine coupling (Jacobi, held, uniform grid); FMPy = Options.fmpy() (its summed
    time, 0.0 inputs on the first step). The zero start is visible: FMPy differs from the engine coupling."""
    two_spans.components[1].profile = None  # the span's set events are checked with the scenes
    archive = write_ssp(two_spans, tmp_path / "line.ssp")
    system = read_ssp(archive, tmp_path / "x")
    libcosim, fmpy = run_libcosim(tmp_path / "x", system), run_fmpy(archive, system)
    assert len(libcosim.time) == 1000 and libcosim.time[0] == pytest.approx(1e-4)
    assert max(relative_difference(libcosim, Master(system, Options.engine()).run()).values()) < AGREE
    assert max(relative_difference(fmpy, Master(system, Options.fmpy()).run()).values()) < AGREE
    assert max(relative_difference(fmpy, libcosim).values()) > 1e-4


def test_columns_made_of_several_variables_travel_with_the_archive(two_spans, tmp_path):
    """A laminate's columns are sums of its layers' spans' variables (System.sums, docs/merge-split.md [M6]):
    the archive keeps them in webline's annotation, read_ssp gives them back, and libcosim, FMPy and the
    master each give the column the sum of what they record (to AGREE of the master's); a term that
    names no recorded variable is refused."""
    two_spans.components[1].profile = None
    two_spans.sums = [("both.T [N]", [(0, 1.0), (1, 1.0)]), ("first.eps [1]", [(2, 0.5), (2, 0.5)])]
    archive = write_ssp(two_spans, tmp_path / "line.ssp")
    system = read_ssp(archive, tmp_path / "x")
    assert system.sums == two_spans.sums and system.record == two_spans.record
    raw = Master(read_ssp(archive, tmp_path / "y"), Options.engine()).run()  # as read: the sums applied
    system.sums = None
    each = Master(system, Options.engine()).run()
    system.sums = two_spans.sums
    assert raw.columns == ["both.T [N]", "first.eps [1]"]
    assert raw.data[:, 0] == pytest.approx(each.data[:, 0] + each.data[:, 1], rel=1e-15)
    assert raw.data[:, 1] == pytest.approx(each.data[:, 2], rel=1e-15)
    for result in (run_libcosim(tmp_path / "x", system), run_fmpy(archive, system)):
        assert result.columns == raw.columns and result.data.shape[1] == 2
    assert max(relative_difference(run_libcosim(tmp_path / "x", system), raw).values()) < AGREE
    broken = tmp_path / "broken.ssp"
    with zipfile.ZipFile(archive) as src, zipfile.ZipFile(broken, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            dst.writestr(info, data.replace(b'variable="1"', b'variable="9"') if info.filename == "SystemStructure.ssd" else data)
    with pytest.raises(SspError, match=r"recorded column 'both.T \[N\]': a term '9' x '1.0' \(needs a recorded variable's index"):
        read_ssp(broken, tmp_path / "z")


def test_fmpy_boolean_literals_are_converted(two_spans, tmp_path):
    """FMPy would set includeDamping="false" as True; the harness passes 0.0: damping off changes the run."""
    two_spans.components[0].start["includeDamping"] = False
    two_spans.components[1].profile = None
    archive = write_ssp(two_spans, tmp_path / "line.ssp")
    system = read_ssp(archive, tmp_path / "x")
    assert max(relative_difference(run_fmpy(archive, system), Master(system, Options.fmpy()).run()).values()) < AGREE


@pytest.mark.parametrize("scene", sorted(p.stem for p in SCENES.glob("*.json")))
def test_every_shipped_scene_runs_unchanged_in_libcosim_and_fmpy(scene, fmus, tmp_path):
    """Exported at its predicted step, read back, run by libcosim and FMPy: each agrees with webline on its
    coupling to 1e-9, and stays within the coupling error docs/ssp.md states (COUPLING_ERROR) of the
    monolithic reference. Some runs stop early to keep CI short (STOP). The laminator and the slitter
    run with their nip's and slitter's ports wired (issue 21)."""
    if scene in REFUSED:
        with pytest.raises(SceneError, match=REFUSED[scene]):
            agreement(SCENES / f"{scene}.json", fmus, tmp_path)
        return
    r = agreement(SCENES / f"{scene}.json", fmus, tmp_path, stop_time=STOP.get(scene))
    assert r["libcosim_vs_webline"] < AGREE, r
    assert r["fmpy_vs_webline"] < AGREE, r
    held, fmpy = COUPLING_ERROR[scene]
    for engine in ("libcosim", "webline"):
        assert r[f"{engine}_vs_reference"] < held, (engine, r)
    assert r["fmpy_vs_reference"] < fmpy, r


# At the predicted step (0.02 ms) these scenes take 75,000 and 125,000 steps per engine. The test stops
# the dancer after the start of its disturbance (0.3 s), the splice after the new roll (1 s) and the
# splice's entry into the first span (1 s, 1.15 s); the full runs are in docs/ssp.md's table
# (bench/ssp_agreement.py). The laminator (0.2 ms, 22,500 steps) stops in its constant acceleration, past
# the ramp's jerk-limited start (0.2 s to 0.6 s); the slitter (0.5 ms, 22,000 steps) likewise (0.5 s to
# 1.5 s). Their full runs take about 45 s together here against 27 s stopped (most of the rest is
# the export's linearization and the reference); the errors of the full runs are in docs/ssp.md.
# A web that may slip, a loop that measures another part, a roll with runout and a lay-on roller are refused by the parts and their SSP
# (docs/scenes.md), each by name: the Line FMU runs them.
REFUSED = {"idler_skid": "has traction", "rewind_ramp_loop": "has a loop in its drive", "runout_dancer": "has runout",
           "rewind_layon": "has a lay-on roller"}
STOP = {"dancer": 0.4, "splice": 1.2, "laminator": 1.0, "slitter": 2.0}

# docs/ssp.md: the error against the monolithic reference, largest over the recorded columns relative to each
# column's largest magnitude, measured at the exported step (and the STOP above), times 2 rounded up, at
# least 1e-6. (Jacobi with held inputs, libcosim and webline alike; FMPy's own: its first step with 0.0 on
# every connected input, is a start transient the others lack: forces 0 on the rollers, speeds 0 on the
# spans, which with web mass read as a sudden acceleration.)
COUPLING_ERROR = {  # scene: (libcosim and webline, FMPy); measured in the comment
    "dancer": (2e-3, 2e-2),  # 8.4e-4, 7.7e-3
    "emergency_stop": (0.7, 0.7),  # 0.32, 0.33 (the nip's stop: held inputs lag a steep transient)
    "laminator": (2e-2, 3e-2),  # 6.5e-3 (infeed.T: the foil idler's fast mode, held inputs), 1.5e-2 (laminate.T)
    "lamination": (3e-3, 4e-2),  # 1.5e-3, 1.6e-2
    "paper_line": (4e-2, 4e-2),  # 1.7e-2, 1.6e-2 (the pull roll's speed step, held inputs)
    "slitter": (2e-3, 0.2),  # 6.2e-4 (lane_c.T), 5.0e-2 (lane_b.T: FMPy's zero start, the winders' first step
    #                            pulls against no tension)
    "splice": (5e-3, 5e-3),  # 2.2e-3, 2.3e-3
    "stiff_line": (2e-4, 0.2),  # 6.4e-5, 9.4e-2
}


def test_no_shipped_scene_names_a_part_after_the_start_of_anothers():
    """FMPy 0.3's simulate_ssp hands a parameter to every component whose name starts it
    (`film` would take `film_unwind.J`): the shipped scenes' SSP archives must run in plain FMPy."""
    from webline.scene import load_scene

    for path in sorted(SCENES.glob("*.json")):
        names = [c.name for c in load_scene(path).parts]
        clashes = [(a, b) for a in names for b in names if a != b and b.startswith(a)]
        assert not clashes, f"{path.name}: {clashes}"


def test_export_warns_when_a_part_name_begins_another(fmus, tmp_path, capsys):
    from webline.cli import main

    scene = tmp_path / "clash.json"
    scene.write_text((SCENES / "laminator.json").read_text().replace('"infeed"', '"foil_in"').replace('"infeed.T"', '"foil_in.T"'))
    assert main(["export", str(scene), "--fmu-dir", str(fmus), "-o", str(tmp_path / "clash.ssp")]) == 0
    err = capsys.readouterr().err
    assert "part 'foil' begins the name of part 'foil_in'" in err, err


def test_no_part_of_an_archive_is_told_it_matches_no_profile(fmus, tmp_path, capfd):
    """An SSP's Roller FMU carries its components' profiles; a part without a drive (an idler) gets an
    empty one of its own name, so no instance warns that it "matches none of the profiles" (FMPy showed
    that for every idler). Each Roller component is initialized under its name, as an importer does,
    with FMPy's own printer of the FMU's log."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from webline.compiler import compile_scene
    from webline.scene import load_scene

    system = compile_scene(load_scene(SCENES / "lamination.json", fmu_dir=fmus), fmus)
    rollers = [c for c in system.components if c.profile is not None or "Roller" in Path(c.fmu).name]
    assert any(c.profile is None for c in rollers), "the scene has a part without a drive"
    archive = write_ssp(system, tmp_path / "lamination.ssp")
    read_ssp(archive, tmp_path / "x")
    initialized, plain = 0, [c for c in rollers if c.profile is None]
    for fmu in sorted((tmp_path / "x" / "resources").glob("Roller*.fmu")):
        unzipped = extract(str(fmu))
        md = read_model_description(unzipped)
        with zipfile.ZipFile(fmu) as z:
            carried = {Path(n).name for n in z.namelist() if n.startswith("resources/")}
        for c in [c for c in plain if f"{c.name}.json" in carried]:
            slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                              instanceName=c.name)
            slave.instantiate(loggingOn=True)
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            slave.terminate()
            slave.freeInstance()
            initialized += 1
    assert initialized == len(plain), "every Roller component without a drive finds its own file"
    assert "matches none" not in capfd.readouterr().out
