"""The first run's set-up (fmu/env.sh, fmu/toolchain.sh, fmu/cross_toolchain.sh,
fmu/package.py): the cross compiler is the one apt offers once its lists are
fresh, whatever state they were in; the cached compiler's libraries all
resolve; a failed step is one line that names it, never a traceback.

Resolving against a partial apt state needs root (apt-get update into a
folder of the test's own) and Debian's mirrors; it downloads only the lists
that changed, the security suite's (under 1 MB).
"""

import os
import shutil
import subprocess
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
LISTS = Path("/var/lib/apt/lists")


def bash(script, **env):
    """Runs `script` after sourcing fmu/env.sh (the cached tools), from the repository root."""
    return subprocess.run(["bash", "-c", f'source fmu/env.sh >/dev/null\n{script}'], cwd=ROOT, capture_output=True,
                          text=True, env={**os.environ, **env})


def cached_version():
    tools = Path(bash('echo "$CONVERTING_SPAN_TOOLS"').stdout.strip())
    return tools, (tools / "rust-web.version").read_text().strip()


def newest(versions):
    """The newest of Debian versions, by dpkg's own comparison."""
    best = versions[0]
    for v in versions[1:]:
        if subprocess.run(["dpkg", "--compare-versions", v, "gt", best]).returncode == 0:
            best = v
    return best


@pytest.mark.skipif(os.geteuid() != 0, reason="apt-get update into a folder of the test's own needs root")
def test_stale_lists_without_the_security_suite_still_resolve_the_newest_rustc_web(tmp_path):
    """The reported failure: lists without bookworm-security named bookworm main's
    older rustc-web. The resolver updates the lists first, so it picks the newest
    any suite offers, and apt can download that version."""
    def state(name, ignore):
        lists = tmp_path / name
        shutil.copytree(LISTS, lists, ignore=shutil.ignore_patterns(*ignore, "lock", "partial"))
        (lists / "partial").mkdir()
        return f"-o Dir::State::Lists={lists}".split()

    def candidate(options):
        out = subprocess.run(["apt-cache", *options, "policy", "rustc-web"], capture_output=True, text=True).stdout
        return next((line.split()[1] for line in out.splitlines() if "Candidate:" in line), "(none)")

    partial, full = state("partial", ["*security*"]), state("full", [])
    # What apt offers today, found independently of the resolver: every list updated.
    subprocess.run(["apt-get", *full, "update", "-qq"], check=True, capture_output=True)
    madison = subprocess.run(["apt-cache", *full, "madison", "rustc-web"], capture_output=True, text=True).stdout
    expected = newest([line.split("|")[1].strip() for line in madison.splitlines()])
    before = candidate(partial)
    if before == expected:
        pytest.skip(f"even the partial lists name {expected}: nothing newer in the security suite today")
    resolved = bash('rust_web_resolve && echo "$RUST_WEB_VERSION"', APT_OPTIONS=" ".join(partial))
    assert resolved.returncode == 0, resolved.stderr
    version = resolved.stdout.strip().splitlines()[-1]
    assert version == expected, f"resolved {version} from lists that named {before}; apt offers {expected}"
    options = " ".join(partial)
    # The chosen version's packages are there to download (what the first run does next).
    uris = subprocess.run(["apt-get", *options.split(), "download", "--print-uris", f"cargo-web={version}"],
                          capture_output=True, text=True)
    assert uris.returncode == 0 and "cargo-web" in uris.stdout, uris.stderr


def test_the_cached_compiler_is_the_recorded_version_and_every_library_resolves():
    tools, version = cached_version()
    folder = tools / f"rust-web-{version}"
    checked = bash(f'rust_web_check "{folder}"')
    assert checked.returncode == 0, checked.stderr
    upstream = version.split("+")[0]  # 1.96.0+dfsg1-1~deb12u2 -> 1.96.0
    for tool in ("cargo", "rustc"):
        out = subprocess.run([folder / "bin" / tool, "--version"], capture_output=True, text=True)
        assert out.returncode == 0 and out.stdout.startswith(f"{tool} {upstream}"), (out.stdout, out.stderr)
    # What its packages depend on is installed: apt has nothing left to add.
    wanted = ", ".join((folder / "DEPENDS").read_text().split("\n")).strip(", ")
    simulated = subprocess.run(["apt-get", "satisfy", "-s", "-qq", wanted], capture_output=True, text=True)
    assert simulated.returncode == 0 and "Inst " not in simulated.stdout, simulated.stdout + simulated.stderr


def test_a_missing_library_is_one_line_naming_it(tmp_path):
    """A tool linked against a library the machine lacks: one line with the library (and the
    package, where Debian's naming finds one apt knows), not a loader error later."""
    (tmp_path / "lib.c").write_text("int convspan_missing(void) { return 1; }\n")
    (tmp_path / "main.c").write_text("int convspan_missing(void);\nint main(void) { return convspan_missing(); }\n")
    soname = "libconvspan-gone.so.7"
    subprocess.run(["gcc", "-shared", "-fPIC", f"-Wl,-soname,{soname}", "-o", tmp_path / soname, tmp_path / "lib.c"], check=True)
    subprocess.run(["gcc", "-o", tmp_path / "tool", tmp_path / "main.c", tmp_path / soname], check=True)
    (tmp_path / soname).unlink()
    out = bash(f'check_libraries "{tmp_path}" "a test package" "{tmp_path / "tool"}"')
    assert out.returncode == 1
    assert out.stderr.strip().splitlines() == [
        f"cross_toolchain.sh: a test package's tool needs {soname}, which is not installed"
    ]
    # Debian's naming policy, checked against apt: the library of the reported failure.
    named = bash("library_package libpcre.so.3; library_package libfoo1.2.so.0; library_package libconvspan-gone.so.7")
    assert named.stdout.split() == ["libpcre3"], named.stdout


def test_a_failed_build_is_one_line_naming_the_step(tmp_path):
    """package.py turns a compiler that cannot start (exit 127, as the missing library
    did) into one line: which step, why, what to do; no traceback."""
    fake = tmp_path / "cargo"
    fake.write_text("#!/bin/sh\necho 'cargo: error while loading shared libraries: libpcre.so.3' >&2\nexit 127\n")
    fake.chmod(0o755)
    env = {**os.environ, "CROSS_CARGO": str(fake), "CROSS_RUSTC": str(fake)}
    out = subprocess.run(["python3", "fmu/package.py", "--platforms", "win64", "--out", str(tmp_path / "x.fmu")],
                         cwd=ROOT, capture_output=True, text=True, env=env)
    assert out.returncode == 1
    assert "Traceback" not in out.stderr
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("package.py: building the win64 libraries failed: it could not start a program"), last


def test_env_sh_stops_with_one_line_when_cargo_is_missing(tmp_path):
    (tmp_path / "bin").mkdir()
    for tool in ("bash", "dirname", "id", "sha256sum", "cut", "cat", "python3"):
        found = shutil.which(tool)
        if found:
            (tmp_path / "bin" / tool).symlink_to(found)
    out = subprocess.run(["bash", "-c", "source fmu/env.sh"], cwd=ROOT, capture_output=True, text=True,
                         env={"PATH": str(tmp_path / "bin"), "HOME": str(tmp_path)})
    assert out.returncode == 1
    assert out.stderr.strip().splitlines() == [textwrap.dedent("""\
        env.sh: finding cargo failed: the Rust toolchain is not on PATH. Install it with rustup (https://rustup.rs), then run again.""")]


@pytest.mark.parametrize("target", ["x86_64-pc-windows-gnu", "aarch64-unknown-linux-gnu"])
def test_the_cached_compiler_has_std_for_each_cross_target(target, tmp_path):
    """std is built once into rustc-web's sysroot (fmu/cross_toolchain.sh), so a plain
    `cargo build --target` works, without -Zbuild-std, and its objects carry bitcode for LTO."""
    tools, version = cached_version()
    folder = tools / f"rust-web-{version}"
    lib = folder / "usr" / "lib" / "rustlib" / target / "lib"
    assert any(lib.glob(".std-recipe-*")), f"no std for {target} in {lib}"
    for crate in ("std", "core", "panic_unwind", "panic_abort", "test"):
        assert list(lib.glob(f"lib{crate}-*.rlib")), f"{lib} lacks {crate}"
    (tmp_path / "src").mkdir()
    (tmp_path / "Cargo.toml").write_text('[package]\nname = "probe"\nversion = "0.0.0"\nedition = "2021"\n[workspace]\n')
    (tmp_path / "src" / "lib.rs").write_text('pub fn probe() -> String { format!("{:?}", std::time::Duration::from_millis(1)) }\n')
    env = {k: v for k, v in os.environ.items() if k != "RUSTC_BOOTSTRAP"}  # no unstable flag may be needed
    built = subprocess.run([folder / "bin" / "cargo", "build", "--quiet", "--lib", "--target", target], cwd=tmp_path,
                           capture_output=True, text=True, env=env)
    assert built.returncode == 0, built.stderr
    # The wrappers find their folder from their own path: a copied or moved cache keeps working.
    for tool in ("cargo", "rustc"):
        assert str(tools) not in (folder / "bin" / tool).read_text()
