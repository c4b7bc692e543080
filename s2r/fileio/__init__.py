"""Safe file input and output: bounded reads of regular files only, atomic writes, no silent overwrites,
content hashes for provenance. Parsing YAML and XML is :mod:`s2r.safeparse`.

Layout (imports run one way, tests/test_import_graph.py):

- :mod:`s2r.fileio.reading` -- bounded reads of regular files, ``.npy`` without pickles, sha256 of a file.
- :mod:`s2r.fileio.inputs` -- what the running command reads (given paths, files found in them): no output is
  ever one of them, even with ``--force`` (``protecting_inputs``, ``protect_read_files``).
- :mod:`s2r.fileio.outputs` -- where s2r may write: output files and folders checked, new folders remembered,
  a folder replaced under ``--force`` restored on failure, never one holding an input (imports ``inputs``).
- :mod:`s2r.fileio.atomic` -- atomic writes, one file or a batch published all or none (imports ``outputs``).

Every public name is importable from ``s2r.fileio`` itself. Low in the layers: imports :mod:`s2r.errors` only.
"""

from s2r.fileio.atomic import OutputBatch, atomic_write_bytes, atomic_write_npy, atomic_write_text, npy_bytes
from s2r.fileio.inputs import protect_input, protect_read_files, protecting_inputs
from s2r.fileio.outputs import (
    TEMP_PREFIX,
    check_output_dir,
    check_output_free,
    discard_on_failure,
    prepare_output_dir,
    removing_new_folders_on_failure,
)
from s2r.fileio.reading import (
    MAX_NPY_BYTES,
    MAX_TEXT_BYTES,
    NotARegularFile,
    check_regular_file,
    read_file_head,
    read_npy,
    read_regular_file,
    read_text_file,
    sha256_file,
)

__all__ = [
    "MAX_NPY_BYTES",
    "MAX_TEXT_BYTES",
    "TEMP_PREFIX",
    "NotARegularFile",
    "OutputBatch",
    "atomic_write_bytes",
    "atomic_write_npy",
    "atomic_write_text",
    "check_output_dir",
    "check_output_free",
    "check_regular_file",
    "discard_on_failure",
    "npy_bytes",
    "prepare_output_dir",
    "protect_input",
    "protect_read_files",
    "protecting_inputs",
    "read_file_head",
    "read_npy",
    "read_regular_file",
    "read_text_file",
    "removing_new_folders_on_failure",
    "sha256_file",
]
