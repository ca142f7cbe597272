"""examples/python_upconvert.py runs and writes what it says."""
import os
import subprocess
import sys

import reprise

EXAMPLE = os.path.join(os.path.dirname(__file__), "..", "..", "examples", "python_upconvert.py")


def test_example_runs(tmp_path):
    result = subprocess.run([sys.executable, EXAMPLE, str(tmp_path)], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "PSNR" in result.stdout
    assert len(reprise.open_sequence(str(tmp_path / "fruc60"))[0]) == 9
    assert reprise.read_header(str(tmp_path / "blender_frame.exr"))["blender"]
