"""Where webline finds its FMUs (installation.py): the checkout's out/ here, a one-line refusal on a
platform the FMUs carry no library for, and the extra a missing package belongs to
(tests/integration/python/test_wheel.py runs the installed wheel itself)."""

import subprocess
import sys

import pytest

from webline import installation
from webline.cli import main

from .conftest import ROOT


def test_in_a_checkout_webline_uses_the_repository_out_and_says_why(fmus):
    assert installation.CHECKOUT == ROOT
    assert installation.FMU_DIR == ROOT / "out" and installation.SCENES == ROOT / "webline" / "scenes"
    version = subprocess.run([sys.executable, "-m", "webline", "--version"], capture_output=True, text=True, check=True).stdout
    assert version.splitlines()[0] == f"webline {installation.version()}"
    assert f"FMUs: {ROOT / 'out'}: the repository's out/" in version


@pytest.mark.parametrize("host", ["darwin64", "aarch64-darwin", "x86_64-linux (musl)", "aarch64-linux"])
def test_a_platform_without_a_usable_library_is_refused_in_one_line(host, fmus, monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(installation, "host_platform", lambda: host)
    assert main(["run", str(ROOT / "webline" / "scenes" / "lamination.json"), "--out", str(tmp_path)]) == 2
    message = capsys.readouterr().err
    assert message.count("\n") == 1 and host in message, message
    if host == "aarch64-linux":
        assert "FMPy" in message and "binaries/linux64" in message
    else:
        assert "linux64" in message and "win64" in message and "fmu/package.py --add-binary" in message
    assert not list(tmp_path.iterdir())


def test_a_missing_package_names_its_extra():
    assert installation.missing_extra(ModuleNotFoundError("no", name="distributed")) == "studies"
    assert installation.missing_extra(ModuleNotFoundError("no", name="libcosimpy.CosimExecution")) == "cosim"
    assert installation.missing_extra(ModuleNotFoundError("no", name="numpy")) is None


def test_scenes_are_copied_and_a_changed_one_is_kept(tmp_path, capsys):
    (tmp_path / "lamination.json").write_text("{}")
    assert main(["scenes", "--to", str(tmp_path)]) == 0
    assert (tmp_path / "lamination.json").read_text() == "{}"
    assert (tmp_path / "splice.json").read_bytes() == (ROOT / "webline" / "scenes" / "splice.json").read_bytes()
    assert "kept your lamination.json" in capsys.readouterr().out
