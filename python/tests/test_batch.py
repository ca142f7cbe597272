"""reprise.batch on a LocalCluster of 2 worker processes: the frames of one whole `reprise fruc`,
byte for byte; complete chunks skipped when started again; a worker killed mid-run costs a retry."""
import os
import signal
import stat
import subprocess

import pytest

distributed = pytest.importorskip("dask.distributed", reason="python3-distributed not installed")
from reprise import batch  # noqa: E402 (after the skip)

REPRISE = os.environ.get("REPRISE_BINARY")
pytestmark = pytest.mark.skipif(not REPRISE, reason="REPRISE_BINARY (the reprise executable) unset")
FRUC = ["--factor", "2", "--refine", "on"]


def reprise(*args):
    done = subprocess.run([REPRISE, *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def frames(folder):
    """frame_*.exr below `folder` by relative path, with their bytes (hidden folders left out)."""
    found = {}
    for root, dirs, files in os.walk(folder):
        dirs[:] = [d for d in dirs if not d.startswith(".")]
        for name in files:
            if name.endswith(".exr"):
                path = os.path.join(root, name)
                with open(path, "rb") as f:
                    found[os.path.relpath(path, folder)] = f.read()
    return found


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    """10 frames of the `cut` scene at 12 Hz (a cut between inputs 5 and 6) and one whole fruc."""
    dir = tmp_path_factory.mktemp("batch")
    reprise("render", "--scene", "cut", "--frames", 10, "--fps", 12, "--size", "32x24", "--aa", 1,
            "--out", dir / "in")
    out = reprise("fruc", "--in", dir / "in", "--out", dir / "whole", *FRUC)
    assert " 1 cuts" in out
    whole = frames(dir / "whole")
    assert len(whole) == 9 * 2 + 1
    return dir, whole


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       host="127.0.0.1", dashboard_address="127.0.0.1:0")
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_chunks_give_the_whole_runs_bytes_and_resume_skips_complete_ones(sequence, client):
    dir, whole = sequence
    out = dir / "batch"
    seen = []
    result = batch.run("fruc", dir / "in", out, args=FRUC, client=client, chunk=2,
                       reprise=REPRISE, progress=lambda done, total, c, n: seen.append(c.name))
    assert (result.chunks, result.skipped, result.ran, result.frames) == (5, 0, 5, 19)
    assert sorted(seen) == sorted(set(seen)) and len(seen) == 5  # each chunk reported once
    assert frames(out) == whole

    # Two chunks' markers lost, and a frame of a third (chunk 0 writes frames 0..4): a second run
    # runs those three only.
    state = out / batch.STATE
    lost = sorted(n for n in os.listdir(state) if n.endswith(".done"))[1:3]
    for name in lost:
        os.remove(state / name)
    os.remove(out / "frame_00004.exr")
    again = batch.run("fruc", dir / "in", out, args=FRUC, client=client, chunk=2, reprise=REPRISE,
                      progress=lambda *a: None)
    assert (again.chunks, again.skipped, again.ran, again.frames) == (5, 2, 3, 5 + 4 + 4)
    assert frames(out) == whole
    assert not [n for n in os.listdir(state) if n.endswith(".partial")]

    # Other arguments into the same folder are refused, naming it.
    with pytest.raises(batch.BatchError, match="another batch run"):
        batch.run("fruc", dir / "in", out, args=["--factor", "3"], client=client, chunk=2,
                  reprise=REPRISE)


def test_a_killed_worker_costs_a_retry_not_a_frame(sequence, client, tmp_path):
    """Last: the module's cluster loses a worker process (its nanny starts another)."""
    dir, whole = sequence
    # Each chunk's run waits 0.5 s first, logged, so that a worker is surely mid-chunk when killed.
    log = tmp_path / "runs.log"
    slow = tmp_path / "slow-reprise"
    slow.write_text(f'#!/bin/sh\necho "$*" >> {log}\nsleep 0.5\nexec {REPRISE} "$@"\n')
    slow.chmod(slow.stat().st_mode | stat.S_IXUSR)
    killed = []
    pids = client.run(os.getpid)

    def kill_one_busy_worker(done, total, chunk, n):
        if killed:
            return
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            os.kill(pids[busy[0]], signal.SIGTERM)
            killed.append(busy[0])

    result = batch.run("fruc", dir / "in", tmp_path / "out", args=FRUC, client=client, chunk=2,
                       reprise=str(slow), progress=kill_one_busy_worker)
    assert killed, "no worker was busy to be killed"
    assert (result.chunks, result.ran, result.frames) == (5, 5, 19)
    assert frames(tmp_path / "out") == whole  # every frame, once, identical
    started = log.read_text().splitlines()
    assert len(started) > 5, "the killed worker's chunk was not run again"
