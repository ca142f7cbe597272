"""reprise.batch: one sequence's `reprise fruc` or `reprise stereo` spread over a Dask cluster.

The sequence is cut into chunks (fruc: input pairs, neighbours sharing one input frame; stereo:
frames). Each chunk is one `reprise COMMAND --range A:B` run on a worker, into a hidden folder of
its own; its frames are then moved into the output folder (one rename each) and a marker is
written last, so a chunk is complete exactly when its marker exists. A run that is started again
skips complete chunks; a worker lost mid-chunk costs that chunk a new run on another worker. The
frames are the bytes one whole `reprise COMMAND` writes (docs/scale.md).

    client = dask.distributed.Client("tcp://HOST:8786")       # or None: a LocalCluster
    reprise.batch.run("fruc", "in/", "out/", args=["--factor", "2"], client=client, chunk=50)

or from a shell: `reprise batch fruc --in DIR --out DIR --scheduler tcp://HOST:8786 --chunk 50`.
"""
import argparse
import ctypes
import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import uuid

COMMANDS = ("fruc", "stereo")
STATE = ".reprise-batch"  # in the output folder: the run's record, chunk markers, partial chunks


class BatchError(Exception):
    """A batch run that cannot go on: bad arguments, a failed chunk, another run's output."""


@dataclasses.dataclass(frozen=True)
class Chunk:
    first: int  # fruc: input pairs first..last; stereo: frames first..last
    last: int

    @property
    def name(self):
        return f"chunk_{self.first:06d}_{self.last:06d}"


@dataclasses.dataclass
class Result:
    chunks: int = 0  # in the whole sequence
    skipped: int = 0  # complete on disk before this run
    ran: int = 0  # run by this run
    frames: int = 0  # frame files the chunks run here wrote


def count_frames(folder):
    """Input frames as `reprise` reads a folder: visible regular files ending in .exr."""
    if not os.path.isdir(folder):
        raise BatchError(f"--in {folder}: not a folder")
    n = sum(1 for e in os.scandir(folder)
            if e.is_file() and e.name.lower().endswith(".exr") and not e.name.startswith("."))
    if n == 0:
        raise BatchError(f"--in {folder}: no .exr files in the folder")
    return n


def plan(command, frames, chunk):
    """The chunks of a sequence of `frames` inputs, `chunk` pairs (fruc) or frames (stereo) each."""
    if command not in COMMANDS:
        raise BatchError(f"command must be one of {', '.join(COMMANDS)}, not '{command}'")
    if chunk < 1:
        raise BatchError(f"--chunk must be at least 1, not {chunk}")
    items = frames - 1 if command == "fruc" else frames
    if items < 1:
        raise BatchError(f"fruc needs at least 2 input frames, the sequence has {frames}")
    return [Chunk(a, min(a + chunk, items) - 1) for a in range(0, items, chunk)]


def find_reprise(given=None):
    """The `reprise` executable: `given`, else $REPRISE_BINARY, else `reprise` on PATH."""
    path = given or os.environ.get("REPRISE_BINARY") or shutil.which("reprise")
    if not path or not os.access(path, os.X_OK):
        raise BatchError("the reprise executable was not found (give --reprise PATH or set "
                         "REPRISE_BINARY)" + (f": {path} is not executable" if path else ""))
    return os.path.abspath(path)


def _die_with_parent():
    # A worker killed mid-chunk takes its `reprise` run with it (Linux PR_SET_PDEATHSIG).
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)


def _write_whole(path, text):
    partial = f"{path}.{uuid.uuid4().hex}.partial"
    with open(partial, "w") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(partial, path)


def run_chunk(reprise, command, source, output, args, chunk):
    """Runs one chunk on this machine (a Dask task); returns the frame files it moved into place.

    Frames go to a folder of this attempt's own, then each is renamed into `output`; the marker
    (the list of frames) is written last. Another attempt of the same chunk writes the same bytes.
    """
    state = os.path.join(output, STATE)
    work = os.path.join(state, f"{chunk.name}.{uuid.uuid4().hex}.partial")
    line = [reprise, command, "--in", source, "--out", work, "--range", f"{chunk.first}:{chunk.last}"]
    done = subprocess.run(line + list(args), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True,
                          preexec_fn=_die_with_parent if sys.platform.startswith("linux") else None)
    if done.returncode != 0:
        shutil.rmtree(work, ignore_errors=True)
        raise BatchError(f"{chunk.name}: `{' '.join(line + list(args))}` failed "
                         f"(exit {done.returncode}):\n{done.stdout.strip()}")
    moved = []
    for folder, _, files in sorted(os.walk(work)):
        relative = os.path.relpath(folder, work)
        target = os.path.normpath(os.path.join(output, relative))
        os.makedirs(target, exist_ok=True)
        for name in sorted(files):
            if name.startswith("."):
                continue  # the range run's own bookkeeping
            os.replace(os.path.join(folder, name), os.path.join(target, name))
            moved.append(os.path.normpath(os.path.join(relative, name)))
    shutil.rmtree(work, ignore_errors=True)
    _write_whole(os.path.join(state, chunk.name + ".done"), json.dumps(moved) + "\n")
    return moved


def complete_chunks(output):
    """Names of the chunks whose marker is in `output` with every frame it lists."""
    state = os.path.join(output, STATE)
    if not os.path.isdir(state):
        return set()
    complete = set()
    for name in os.listdir(state):
        if not name.endswith(".done"):
            continue
        try:
            with open(os.path.join(state, name)) as f:
                listed = json.load(f)
        except (OSError, ValueError):
            continue  # unreadable: run the chunk again
        if all(os.path.isfile(os.path.join(output, frame)) for frame in listed):
            complete.add(name[:-len(".done")])
    return complete


def _open_output(output, record):
    """Creates the output's state folder; refuses one written by a run of other arguments."""
    state = os.path.join(output, STATE)
    os.makedirs(state, exist_ok=True)
    run_file = os.path.join(state, "run.json")
    text = json.dumps(record, sort_keys=True) + "\n"
    if os.path.exists(run_file):
        with open(run_file) as f:
            previous = f.read()
        if previous != text:
            raise BatchError(f"--out {output} was written by another batch run ({previous.strip()});"
                             " run it with the same arguments, or choose another --out")
    else:
        _write_whole(run_file, text)
    for name in os.listdir(state):  # attempts of an earlier run that did not finish
        if name.endswith(".partial"):
            path = os.path.join(state, name)
            shutil.rmtree(path, ignore_errors=True) if os.path.isdir(path) else os.remove(path)


def run(command, source, output, *, args=(), client=None, chunk=50, workers=2, reprise=None,
        progress=None, retries=2):
    """Runs `reprise COMMAND --in source --out output ARGS` as chunks on `client` (a
    dask.distributed.Client; None: a LocalCluster of `workers` processes for this call).

    `progress(done, total, chunk, frames)` is called as chunks finish (default: a line on stderr).
    Returns a Result. Raises BatchError naming the chunk when one fails `retries` + 1 times.
    """
    reprise = find_reprise(reprise)
    source, output = os.path.abspath(source), os.path.abspath(output)
    if source == output:
        raise BatchError(f"--out {output} is the input folder")
    args = [str(a) for a in args]
    for a in args:
        if a in ("--in", "--out", "--range", "--resume", "--overwrite-inputs"):
            raise BatchError(f"{a} is set by the batch run, not passed on to `reprise {command}`")
    chunks = plan(command, count_frames(source), chunk)
    try:
        from dask.distributed import Client, LocalCluster, as_completed
    except ImportError as e:
        raise BatchError("reprise.batch needs Dask distributed (Debian: apt-get install "
                         f"python3-distributed): {e}") from None
    _open_output(output, {"command": command, "in": source, "args": args, "chunk": chunk})
    done_before = complete_chunks(output)
    todo = [c for c in chunks if c.name not in done_before]
    result = Result(chunks=len(chunks), skipped=len(chunks) - len(todo))
    report = progress or (lambda done, total, c, frames: print(
        f"[batch] {done}/{total} chunks ({c.name}: {frames} frames)", file=sys.stderr, flush=True))
    if result.skipped:
        print(f"[batch] {result.skipped} of {len(chunks)} chunks complete on disk, skipped",
              file=sys.stderr, flush=True)
    if not todo:
        return result
    own = None
    if client is None:
        own = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address="127.0.0.1:0")
        client = Client(own)
    try:
        futures = {client.submit(run_chunk, reprise, command, source, output, args, c,
                                 key=f"reprise-{command}-{c.name}-{uuid.uuid4().hex[:8]}",
                                 retries=retries, pure=False): c for c in todo}
        for future in as_completed(futures):
            c = futures[future]
            try:
                moved = future.result()
            except Exception as e:
                for f in futures:
                    f.cancel()
                raise BatchError(f"{c.name} (--range {c.first}:{c.last}) failed: {e}") from None
            result.ran += 1
            result.frames += len(moved)
            report(result.skipped + result.ran, len(chunks), c, len(moved))
    finally:
        if own is not None:
            client.close()
            own.close()
    return result


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="reprise batch",
        description="Runs `reprise fruc` or `reprise stereo` over a Dask cluster in chunks; "
                    "options it does not know are passed on to the command (e.g. --factor 4). "
                    "Started again, it skips the chunks complete on disk.")
    parser.add_argument("command", choices=COMMANDS)
    parser.add_argument("--in", dest="source", metavar="DIR", required=True,
                        help="input sequence (folder)")
    parser.add_argument("--out", metavar="DIR", required=True, help="output folder")
    parser.add_argument("--scheduler", help="Dask scheduler address, e.g. tcp://HOST:8786 "
                        "(default: a local cluster of --workers processes)")
    parser.add_argument("--chunk", type=int, default=50,
                        help="input pairs (fruc) or frames (stereo) per chunk (default 50)")
    parser.add_argument("--workers", type=int, default=2,
                        help="worker processes of the local cluster (default 2)")
    parser.add_argument("--reprise", help="the reprise executable the workers run "
                        "(default: $REPRISE_BINARY, else reprise on PATH)")
    options, passed = parser.parse_known_args(argv)
    try:
        client = None
        if options.scheduler:
            try:
                from dask.distributed import Client
            except ImportError:
                raise BatchError("reprise batch needs Dask distributed (Debian: apt-get install "
                                 "python3-distributed)") from None
            client = Client(options.scheduler)
        result = run(options.command, options.source, options.out, args=passed, client=client,
                     chunk=options.chunk, workers=options.workers, reprise=options.reprise)
    except (BatchError, OSError) as e:
        print(f"reprise batch: {e}", file=sys.stderr)
        return 1
    print(f"batch {options.command}: {result.chunks} chunks, {result.skipped} complete before, "
          f"{result.ran} run, {result.frames} frames written to {options.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
