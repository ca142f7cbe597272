"""reprise: frames nobody rendered (frame-rate upconversion, the other eye, a codec) from rendered
colour, depth and motion. Conventions: docs/conventions.md.

Everything comes from the native module reprise._native; reprise.batch spreads a sequence's work
over Dask (python3-distributed), imported on its own so that `import reprise` needs no Dask.
"""
from ._native import *  # noqa: F401,F403 (the public names of the native module)
from ._native import __version__  # CMake's project version, as `reprise --version` prints it
