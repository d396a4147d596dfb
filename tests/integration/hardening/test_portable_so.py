"""The FMUs' binaries load on old Linux systems: each .so in each packaged FMU
(binaries/linux64, x86-64, and binaries/aarch64-linux, ARM64) needs no glibc
symbol version newer than 2.17 and links nothing but glibc's own libraries and
libgcc_s (read with objdump -T and readelf -d, binutils). It exports exactly
the 44 fmi2 and 75 fmi3 functions and does not contain the test-only hook.
(test_binaries.py: the Windows DLL.)

    .venv/bin/python -m pytest tests/integration/hardening -q     (after python3 fmu/package.py)

Checks out/ConvertingSpan.fmu and out/Roller.fmu (FMU=path checks that one). The parser is checked on a
fabricated listing and on the plain host build (which needs a newer glibc),
so a check that could not fail would itself fail.
"""

import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "fmu"))
import package  # noqa: E402  (the export check and the lists of the functions)
FMUS = (
    [Path(os.environ["FMU"])]
    if "FMU" in os.environ
    else [ROOT / "out" / name for name in ("ConvertingSpan.fmu", "Roller.fmu") if name == "ConvertingSpan.fmu" or (ROOT / "out" / name).exists()]
)
NEWEST_ALLOWED = (2, 17)
ALLOWED_NEEDED = {
    "libc.so.6",
    "libm.so.6",
    "libpthread.so.0",
    "libdl.so.2",
    "ld-linux-x86-64.so.2",
    "ld-linux-aarch64.so.1",
    "libgcc_s.so.1",
}
# Version namespaces of those libraries: glibc's and libgcc_s's.
ALLOWED_NAMESPACES = ("GLIBC_", "GCC_")
LINUX_FOLDERS = ("linux64", "aarch64-linux")


def version_refs(objdump_t):
    """Symbol versions an `objdump -T` listing refers to, e.g. {'GLIBC_2.14', ...}."""
    return set(re.findall(r"\b((?:GLIBC|GCC|GLIBCXX|CXXABI)_[0-9A-Z_.]+)\b", objdump_t))


def glibc_versions(refs):
    out = []
    for ref in refs:
        m = re.fullmatch(r"GLIBC_(\d+)\.(\d+)(?:\.(\d+))?", ref)
        if m:
            out.append(tuple(int(x) for x in m.groups() if x is not None))
    return sorted(out)


def problems(objdump_t, readelf_d):
    """Everything that makes a library non-portable, as readable lines."""
    found = []
    refs = version_refs(objdump_t)
    for ref in sorted(refs):
        if not ref.startswith(ALLOWED_NAMESPACES) or ref == "GLIBC_PRIVATE":
            found.append(f"needs symbol version {ref}")
    for v in glibc_versions(refs):
        if v[:2] > NEWEST_ALLOWED:
            found.append("needs GLIBC_" + ".".join(map(str, v)))
    for lib in re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", readelf_d):
        if lib not in ALLOWED_NEEDED:
            found.append(f"links {lib}")
    return found


def tool(*args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


@pytest.fixture(scope="module", params=[(f, d) for f in FMUS for d in LINUX_FOLDERS], ids=lambda p: f"{p[0].name}-{p[1]}")
def shipped_so(request, tmp_path_factory):
    fmu, folder = request.param
    if not fmu.exists():
        pytest.fail(f"{fmu} is missing: run python3 fmu/package.py first")
    with zipfile.ZipFile(fmu) as zf:
        names = [n for n in zf.namelist() if n.startswith(f"binaries/{folder}/") and n.endswith(".so")]
        assert len(names) == 1, names
        path = tmp_path_factory.mktemp("so") / folder / Path(names[0]).name
        path.parent.mkdir()
        path.write_bytes(zf.read(names[0]))
    return path


def test_needs_no_glibc_newer_than_2_17_and_links_only_glibc_and_libgcc(shipped_so):
    objdump_t = tool("objdump", "-T", str(shipped_so))
    readelf_d = tool("readelf", "-d", str(shipped_so))
    assert problems(objdump_t, readelf_d) == []
    newest = glibc_versions(version_refs(objdump_t))[-1]
    needed = re.findall(r"\(NEEDED\)\s+Shared library: \[([^\]]+)\]", readelf_d)
    print(f"\n{shipped_so.parent.name}/{shipped_so.name}: newest symbol version GLIBC_{'.'.join(map(str, newest))}; NEEDED {needed}")


def test_exports_exactly_the_fmi_functions(shipped_so):
    assert package.exported_functions(shipped_so) == package.expected_exports(shipped_so.stem)


def test_the_test_only_hook_is_not_shipped(shipped_so):
    assert b"testHook." not in shipped_so.read_bytes()


def test_the_check_flags_a_newer_glibc_a_foreign_library_and_glibc_private():
    objdump_t = """
0000000000000000      DF *UND*  0000000000000000 (GLIBC_2.2.5) malloc
0000000000000000      DF *UND*  0000000000000000 (GLIBC_2.34) __libc_start_main
0000000000000000      DF *UND*  0000000000000000 (GLIBC_PRIVATE) _dl_find_object
0000000000000000      DF *UND*  0000000000000000 (GLIBCXX_3.4.29) _ZNSt6chrono
"""
    readelf_d = """
 0x0000000000000001 (NEEDED)             Shared library: [libstdc++.so.6]
 0x0000000000000001 (NEEDED)             Shared library: [libc.so.6]
"""
    found = problems(objdump_t, readelf_d)
    assert "needs GLIBC_2.34" in found
    assert "needs symbol version GLIBC_PRIVATE" in found
    assert "needs symbol version GLIBCXX_3.4.29" in found
    assert "links libstdc++.so.6" in found
    assert not any("2.2.5" in f or "libc.so.6" in f for f in found)


def test_the_check_flags_a_binary_built_against_this_machines_glibc():
    """The plain host build (cargo build --release) if there is one, else this
    machine's own `ls`: both need the glibc they were built with (2.36 on
    Debian 12), newer than 2.17."""
    host = ROOT / "target" / "release" / "libconverting_span.so"
    if not host.exists():
        host = Path(shutil.which("ls"))
    found = problems(tool("objdump", "-T", str(host)), tool("readelf", "-d", str(host)))
    assert any(f.startswith("needs GLIBC_2.") for f in found), (host, found)
