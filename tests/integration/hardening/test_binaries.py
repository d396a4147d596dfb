"""The Windows DLL in each packaged FMU imports only what Windows 10 and later
guarantee (system DLLs; no MinGW runtime such as libgcc_s_seh-1.dll or
libwinpthread-1.dll) and exports exactly the 44 fmi2 and 75 fmi3 functions, read from its
PE tables with objdump -p. (test_portable_so.py: the Linux binaries.) And
fmu/package.py's --add-binary merges libraries built elsewhere after the same
export check: tried here with the binaries built here.

    .venv/bin/python -m pytest tests/integration/hardening -q     (after python3 fmu/package.py)
"""

import re
import shutil
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "fmu"))
import package  # noqa: E402

FMUS = [ROOT / "out" / f"{model.name}.fmu" for model in package.MODELS]
# Rust's std on x86_64-pc-windows-gnu: the C runtime every Windows has, the
# kernel, sockets, the user profile (home_dir), the random seed (ProcessPrng,
# Windows 10+) and API sets of Windows' own DLLs.
ALLOWED_DLLS = {"kernel32.dll", "msvcrt.dll", "ntdll.dll", "userenv.dll", "ws2_32.dll", "bcryptprimitives.dll"}
ALLOWED_API_SET = re.compile(r"api-ms-win-core-[a-z0-9-]+\.dll")


def imported_dlls(objdump_p):
    return [name.lower() for name in re.findall(r"^\s*DLL Name: (\S+)$", objdump_p, re.M)]


def problems(objdump_p):
    return [f"imports {dll}" for dll in imported_dlls(objdump_p) if dll not in ALLOWED_DLLS and not ALLOWED_API_SET.fullmatch(dll)]


@pytest.fixture(scope="module", params=FMUS, ids=lambda p: p.name)
def shipped_dll(request, tmp_path_factory):
    fmu = request.param
    if not fmu.exists():
        pytest.fail(f"{fmu} is missing: run python3 fmu/package.py first")
    name = f"binaries/win64/{fmu.stem}.dll"
    with zipfile.ZipFile(fmu) as zf:
        assert name in zf.namelist(), f"{fmu.name} lacks {name}"
        path = tmp_path_factory.mktemp("dll") / Path(name).name
        path.write_bytes(zf.read(name))
    return path


def test_imports_only_windows_own_dlls(shipped_dll):
    listing = subprocess.run(["objdump", "-p", str(shipped_dll)], check=True, capture_output=True, text=True).stdout
    assert "x86-64" in listing or "pei-x86-64" in subprocess.run(["objdump", "-f", str(shipped_dll)], capture_output=True, text=True).stdout
    assert problems(listing) == []
    print(f"\n{shipped_dll.name}: imports {', '.join(imported_dlls(listing))}")


def test_exports_exactly_the_fmi_functions(shipped_dll):
    assert package.exported_functions(shipped_dll) == package.expected_exports(shipped_dll.stem)


def test_the_check_flags_the_mingw_runtime_and_other_dlls():
    listing = """
	DLL Name: KERNEL32.dll
	DLL Name: libgcc_s_seh-1.dll
	DLL Name: libwinpthread-1.dll
	DLL Name: api-ms-win-core-synch-l1-2-0.dll
	DLL Name: VCRUNTIME140.dll
"""
    assert problems(listing) == ["imports libgcc_s_seh-1.dll", "imports libwinpthread-1.dll", "imports vcruntime140.dll"]


def packaged(fmu, prefix):
    with zipfile.ZipFile(fmu) as zf:
        return {n: zf.read(n) for n in zf.namelist() if n.startswith(prefix)}


def test_add_binary_merges_libraries_built_elsewhere(tmp_path):
    """The Windows and ARM64 libraries of the packaged FMUs, taken out and
    merged back with --add-binary beside a linux64-only packaging: the same
    binaries land in the same places."""
    elsewhere = {folder: tmp_path / folder for folder in ("win64", "aarch64-linux")}
    for fmu in FMUS:
        for folder, where in elsewhere.items():
            where.mkdir(exist_ok=True)
            for name, data in packaged(fmu, f"binaries/{folder}/").items():
                (where / Path(name).name).write_bytes(data)
    out = tmp_path / "merged" / "ConvertingSpan.fmu"
    command = ["python3", "fmu/package.py", "--no-build", "--platforms", "linux64", "--out", str(out)]
    for folder, where in elsewhere.items():
        command += ["--add-binary", f"{folder}={where}"]
    subprocess.run(command, cwd=ROOT, check=True, capture_output=True, text=True)
    for fmu in FMUS:
        merged = out.parent / fmu.name
        assert packaged(merged, "binaries/") == packaged(fmu, "binaries/")


def test_add_binary_refuses_a_library_without_the_fmi2_api(tmp_path):
    wrong = tmp_path / "ConvertingSpan.so"
    shutil.copy(next(Path("/usr/lib/x86_64-linux-gnu").glob("libz.so.1*")), wrong)
    proc = subprocess.run(
        ["python3", "fmu/package.py", "--no-build", "--platforms", "linux64", "--out", str(tmp_path / "x" / "ConvertingSpan.fmu"),
         "--add-binary", f"aarch64-linux={wrong}"], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode != 0
    assert "must export exactly the 44 fmi2 and the 75 fmi3 functions" in proc.stderr


def test_the_mach_o_reader_finds_external_defined_symbols(tmp_path):
    """macOS libraries cannot be built here: a fabricated 64-bit Mach-O with
    one exported, one undefined and one local symbol checks the reader."""
    strings = b"\0_fmi2DoStep\0_malloc\0_local\0"
    # nlist_64: n_strx, n_type, n_sect, n_desc, n_value; 0x0f = N_SECT|N_EXT, 0x01 = N_UNDF|N_EXT, 0x0e = N_SECT
    symbols = struct.pack("<IBBHQ", 1, 0x0F, 1, 0, 0) + struct.pack("<IBBHQ", 13, 0x01, 0, 0, 0) + struct.pack("<IBBHQ", 21, 0x0E, 1, 0, 0)
    header = struct.pack("<IiiIIIII", 0xFEEDFACF, 0x0100000C, 0, 6, 1, 24, 0, 0)
    symoff = 32 + 24
    symtab = struct.pack("<IIIIII", 0x2, 24, symoff, 3, symoff + len(symbols), len(strings))
    path = tmp_path / "ConvertingSpan.dylib"
    path.write_bytes(header + symtab + symbols + strings)
    assert package.exported_functions(path) == {"fmi2DoStep"}
