"""The package: one version (CMake's project version) for `reprise --version` and
reprise.__version__; `reprise batch` runs reprise.batch."""
import os
import subprocess

import pytest

import reprise

REPRISE = os.environ.get("REPRISE_BINARY")
needs_binary = pytest.mark.skipif(not REPRISE, reason="REPRISE_BINARY unset")


@needs_binary
def test_version_is_the_executables():
    printed = subprocess.run([REPRISE, "--version"], capture_output=True, text=True, check=True)
    assert printed.stdout == f"reprise {reprise.__version__}\n"
    assert reprise.__version__.count(".") == 2


def test_native_names_are_the_packages():
    assert reprise.FrameRateConverter is reprise._native.FrameRateConverter
    assert issubclass(reprise.Error, RuntimeError)


@needs_binary
def test_batch_front_names_what_is_wrong(tmp_path):
    done = subprocess.run([REPRISE, "batch", "fruc", "--in", str(tmp_path / "none"), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True)
    assert done.returncode != 0
    assert "reprise batch:" in done.stderr and "none" in done.stderr, done.stderr
