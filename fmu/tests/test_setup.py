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


# The cross toolchain's whole path (resolve, download, unpack, Depends, std for each target) with a
# fake apt and a fake rustc-web (fake_apt.py, fake_cargo.sh) on a PATH without MinGW: what a clean
# machine meets, in seconds and without touching this one.
HERE = Path(__file__).resolve().parent


FAKED = ("apt-get", "apt-cache", "dpkg-query")


class Machine:
    """A clean machine for the cross toolchain: its PATH, its apt (a log of calls, failures to
    order), an empty tools cache."""

    def __init__(self, tmp_path):
        self.apt = tmp_path / "apt"
        self.bin = self.apt / "bin"
        self.bin.mkdir(parents=True)
        self.tools = tmp_path / "tools"
        for folder in ("/usr/sbin", "/usr/bin"):
            for tool in Path(folder).iterdir():
                name = tool.name
                if name.startswith("x86_64-w64-mingw32-") or name in FAKED or (self.bin / name).exists():
                    continue
                (self.bin / name).symlink_to(tool)
        for name in FAKED:
            (self.bin / name).symlink_to(HERE / "fake_apt.py")

    def fail(self, *what):
        (self.apt / "fail").write_text("\n".join(what) + "\n")

    def calls(self):
        return (self.apt / "calls").read_text().splitlines() if (self.apt / "calls").exists() else []

    def cross_toolchain(self):
        """fmu/cross_toolchain.sh as env.sh sources it, on this machine."""
        return self.step('unset SETUP_FUNCTIONS_ONLY && source fmu/cross_toolchain.sh && echo "CROSS_CARGO=$CROSS_CARGO"')

    def step(self, script, **env):
        """`script` after the set-up's functions (env.sh, toolchain.sh, tools.sh) are defined."""
        env = {"PATH": str(self.bin), "HOME": str(self.apt), "FAKE_APT": str(self.apt), "CONVERTING_SPAN_TOOLS": str(self.tools), **env}
        functions = ("export SETUP_FUNCTIONS_ONLY=1; source fmu/env.sh && source fmu/toolchain.sh "
                     "&& source fmu/cross_toolchain.sh && source tests/tools.sh")
        return subprocess.run(["bash", "-c", f"{functions}\n{script}"], cwd=ROOT, capture_output=True, text=True, env=env)


needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="the set-up installs with apt only as root")


@needs_root
def test_mingw_is_installed_before_std_is_built_for_windows(tmp_path):
    """The reported first run: std for x86_64-pc-windows-gnu was built before MinGW-w64, whose
    dlltool it calls, was installed. Fails if the install moves below the build again."""
    machine = Machine(tmp_path)
    out = machine.cross_toolchain()
    assert out.returncode == 0, out.stderr
    calls = machine.calls()
    install = next(i for i, c in enumerate(calls) if c.startswith("apt-get") and "install" in c and "gcc-mingw-w64-x86-64" in c)
    build = next(i for i, c in enumerate(calls) if c.startswith("cargo") and "build" in c and "x86_64-pc-windows-gnu" in c)
    assert install < build, calls
    tools_rust = machine.tools / "rust-web-9.9.9+fake1"
    for target in ("x86_64-pc-windows-gnu", "aarch64-unknown-linux-gnu"):
        assert list((tools_rust / "usr/lib/rustlib" / target / "lib").glob(".std-recipe-*")), target
    assert f"CROSS_CARGO={tools_rust}/bin/cargo" in out.stdout


def run_twice(machine, failure, message):
    """The set-up fails on `failure` with one line that contains `message` and says to run again;
    the second run, with the cause gone, passes."""
    machine.fail(*failure)
    first = machine.cross_toolchain()
    assert first.returncode != 0
    said = [line for line in first.stderr.splitlines() if line.startswith("cross_toolchain.sh:")]
    assert said and message in said[-1] and said[-1].endswith("then run again"), first.stderr
    (machine.apt / "fail").unlink(missing_ok=True)
    second = machine.cross_toolchain()
    assert second.returncode == 0, second.stderr
    return said[-1]


@needs_root
@pytest.mark.parametrize("failure, message, mingw", [
    (["update"], "apt-get install gcc-mingw-w64-x86-64 failed", False),  # the lists are updated before the first install
    (["update"], "could not update the apt lists", True),
    (["download"], "apt-get download of rustc-web", False),
    (["satisfy"], "apt-get satisfy", False),
    (["install gcc-mingw-w64-x86-64"], "apt-get install gcc-mingw-w64-x86-64 failed", False),
    (["candidate"], "apt offers no rustc-web", False),
])
def test_each_apt_failure_says_run_again_and_the_next_run_passes(tmp_path, failure, message, mingw):
    machine = Machine(tmp_path)
    if mingw:
        machine.fail()
        subprocess.run([machine.bin / "apt-get", "install", "-y", "gcc-mingw-w64-x86-64"], env={"FAKE_APT": str(machine.apt)}, check=True)
    if failure == ["satisfy"]:
        # Depends that apt would have to install: the set-up asks it to.
        (machine.apt / "inst").touch()
    run_twice(machine, failure, message)


@needs_root
def test_a_failed_std_build_says_run_again_and_the_next_run_builds_it(tmp_path):
    machine = Machine(tmp_path)
    (machine.apt / "fail-std-once").touch()
    first = machine.cross_toolchain()
    assert first.returncode != 0
    last = first.stderr.strip().splitlines()[-1]
    assert "building std" in last and last.endswith("then run again") and "remove" not in last, last
    second = machine.cross_toolchain()
    assert second.returncode == 0, second.stderr


@needs_root
def test_a_damaged_compiler_folder_is_named_and_removing_it_mends_it(tmp_path):
    machine = Machine(tmp_path)
    assert machine.cross_toolchain().returncode == 0
    folder = machine.tools / "rust-web-9.9.9+fake1"
    (folder / "usr/bin/rustc").unlink()
    broken = machine.cross_toolchain()
    last = broken.stderr.strip().splitlines()[-1]
    assert broken.returncode != 0 and last == f"cross_toolchain.sh: {folder} lacks cargo or rustc: remove it, then run again", last
    shutil.rmtree(folder)
    assert machine.cross_toolchain().returncode == 0


# The other steps' advice, each followed: pip and cargo cut off from their registries by a
# proxy nobody listens on, apt by the fake; then the same step again as it is.
OFFLINE_PIP = {"PIP_INDEX_URL": "http://127.0.0.1:9/simple", "PIP_FIND_LINKS": "", "PIP_RETRIES": "0", "PIP_TIMEOUT": "2"}
OFFLINE_CARGO = {"CARGO_HTTP_PROXY": "http://127.0.0.1:9", "CARGO_NET_RETRY": "0", "CARGO_HTTP_TIMEOUT": "2"}


def online():
    """This machine's own settings for the registries (pip's and cargo's), for the run that follows the advice."""
    return {k: v for k, v in os.environ.items() if k.startswith(("PIP_", "CARGO_", "RUSTUP_", "SSL_", "HTTP", "http"))}


def last_line(out):
    return out.stderr.strip().splitlines()[-1] if out.stderr.strip() else ""


@needs_root
def test_pip_unreachable_says_check_pypi_and_the_next_run_installs(tmp_path):
    """python_packages (fmu/requirements.txt, tests/requirements.txt): a failed install leaves no
    half-made cache that the next run takes for complete."""
    machine = Machine(tmp_path)
    requirements = tmp_path / "requirements.txt"
    requirements.write_text("six==1.16.0\n")
    venv = tmp_path / "venv"
    subprocess.run(["python3", "-m", "venv", "--without-pip", venv], check=True)
    step = f'python_packages probe "{requirements}"'
    first = machine.step(step, VENV=str(venv), **OFFLINE_PIP)
    assert first.returncode == 1
    assert last_line(first).startswith("env.sh: pip install -r ") and last_line(first).endswith("Check that PyPI is reachable, then run again.")
    second = machine.step(step, VENV=str(venv), **online())
    assert second.returncode == 0, second.stderr
    assert subprocess.run([venv / "bin" / "python", "-c", "import six"]).returncode == 0


@needs_root
def test_zig_unreachable_says_check_pypi_and_the_next_run_installs(tmp_path):
    machine = Machine(tmp_path)
    first = machine.step("zig_setup", **OFFLINE_PIP)
    assert first.returncode == 1 and last_line(first).startswith("toolchain.sh: installing zig failed"), first.stderr
    assert last_line(first).endswith("Check that PyPI is reachable, then run again.")
    second = machine.step('zig_setup && "$TOOLS/bin/zig" version', **online())
    assert second.returncode == 0 and second.stdout.strip().endswith("0.15.2"), second.stderr


@needs_root
@pytest.mark.parametrize("step, binary, script", [("zigbuild_setup", "cargo-zigbuild", "toolchain.sh"),
                                                  ("fmi_sim_setup", "fmi-sim", "tools.sh")])
def test_crates_io_unreachable_says_check_it_and_leaves_nothing_taken_for_installed(tmp_path, step, binary, script):
    """`cargo install` writes its binary only when the build is done: the next run installs
    again (that run is a full build, which tests/clean_machine.sh's first run makes)."""
    machine = Machine(tmp_path)
    first = machine.step(step, **{k: v for k, v in online().items() if not k.startswith("CARGO_HTTP")}, **OFFLINE_CARGO)
    assert first.returncode == 1, first.stderr
    assert last_line(first).startswith(f"{script}: installing {binary} failed") and last_line(first).endswith(
        "Check that crates.io is reachable, then run again."), first.stderr
    assert not (machine.tools / "bin" / binary).exists()


@needs_root
@pytest.mark.parametrize("step, packages, first", [("test_packages_setup", "TEST_PACKAGES", "wine64"),
                                                   ("browser_setup", "BROWSER_PACKAGES", "chromium chromium-driver")])
def test_apt_unreachable_for_the_tests_packages_says_run_again_and_the_next_run_installs(tmp_path, step, packages, first):
    machine = Machine(tmp_path)
    machine.fail("update")
    failed = machine.step(step)
    assert failed.returncode == 1 and last_line(failed).startswith(f"tools.sh: apt-get install {first}"), failed.stderr
    assert last_line(failed).endswith("then run again.")
    machine.fail()
    assert machine.step(step).returncode == 0
    assert machine.step(f'installed "${{{packages}[@]}}"').returncode == 0
    # Installed once: the next run asks apt nothing.
    asked = len(machine.calls())
    assert machine.step(step).returncode == 0
    assert [c for c in machine.calls()[asked:] if not c.startswith("dpkg-query")] == []


def test_not_root_names_the_packages_the_root_run_installs(tmp_path):
    """Without root the set-up cannot install: its message names exactly what it installs as root."""
    machine = Machine(tmp_path)
    (machine.bin / "id").unlink()
    (machine.bin / "id").write_text("#!/bin/sh\necho 1000\n")
    (machine.bin / "id").chmod(0o755)
    (machine.bin / "gcc").unlink(missing_ok=True)
    out = machine.step("base_setup")
    assert out.returncode == 1
    named = "env.sh: please install the Debian packages gcc libc6-dev ca-certificates, then run again"
    assert named in out.stderr.splitlines(), out.stderr
    listed = machine.step('echo "${BASE_PACKAGES[*]}|$VENV_PACKAGE|$MINGW_PACKAGE|${TEST_PACKAGES[*]}|${BROWSER_PACKAGES[*]}"')
    base, venv, mingw, tests, browser = listed.stdout.strip().split("|")
    assert base == "gcc libc6-dev ca-certificates" and venv == "python3-venv" and mingw == "gcc-mingw-w64-x86-64"
    assert tests.split()[0] == "wine64"
    # The browser test skips with this line where it cannot install Chromium (tests/integration/python/browser.py).
    out = machine.step("browser_setup")
    assert out.returncode == 1
    assert f"env.sh: please install the Debian packages {browser}, then run again" in out.stderr.splitlines(), out.stderr
